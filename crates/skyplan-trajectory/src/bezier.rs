//! Bézier (Bernstein) pieces: evaluation by de Casteljau, hodographs (derivatives), splitting,
//! and bounds that hold on the whole continuous curve (the convex-hull property).

use skyplan_world3::Neu;

/// A point of the curve at `tau ∈ [0, 1]` (de Casteljau: stable for any degree).
pub(crate) fn eval(ctrl: &[Neu], tau: f64) -> Neu {
    let mut work: Vec<Neu> = ctrl.to_vec();
    let n = work.len();
    for level in 1..n {
        for k in 0..n - level {
            let next = work[k + 1];
            for (w, x) in work[k].iter_mut().zip(next) {
                *w = (1.0 - tau) * *w + tau * x;
            }
        }
    }
    work.first().copied().unwrap_or([0.0; 3])
}

/// Control points of the derivative with respect to time of a piece lasting `duration_s`
/// (the hodograph: `n (c[k+1] − c[k]) / T`); empty for a constant piece.
pub(crate) fn hodograph(ctrl: &[Neu], duration_s: f64) -> Vec<Neu> {
    let n = ctrl.len().saturating_sub(1) as f64;
    ctrl.windows(2)
        .map(|w| [0, 1, 2].map(|a| n * (w[1][a] - w[0][a]) / duration_s))
        .collect()
}

/// The two halves of a curve split at `tau = 1/2` (de Casteljau), each a Bézier curve of the
/// same degree over `[0, 1]`.
pub(crate) fn split_half(ctrl: &[Neu]) -> (Vec<Neu>, Vec<Neu>) {
    let n = ctrl.len();
    let mut left = Vec::with_capacity(n);
    let mut right = vec![[0.0; 3]; n];
    let mut work: Vec<Neu> = ctrl.to_vec();
    for level in 0..n {
        left.push(work[0]);
        right[n - 1 - level] = work[n - 1 - level];
        for k in 0..n - 1 - level {
            let next = work[k + 1];
            for (w, x) in work[k].iter_mut().zip(next) {
                *w = 0.5 * (*w + x);
            }
        }
    }
    (left, right)
}

/// Most control points a curve split on the stack may have (a quintic has 6).
const MAX_POINTS: usize = 8;

/// An upper bound of `f` over the whole curve: the largest `f` of the control points after
/// splitting the curve `depth` times (2^depth sub-curves). Valid for any convex `f` (a norm, a
/// coordinate): the curve lies in each sub-curve's control hull, and a convex function's
/// maximum over a hull is at a vertex. More depth, a tighter bound.
///
/// A sub-curve's hull lies inside its parent's, so a sub-curve whose parent's bound is no
/// larger than the best found so far cannot raise it: such branches are skipped, which gives
/// the same value as visiting all 2^depth sub-curves.
pub(crate) fn hull_max(ctrl: &[Neu], depth: u32, f: &impl Fn(Neu) -> f64) -> f64 {
    if ctrl.is_empty() {
        return f64::NEG_INFINITY;
    }
    if ctrl.len() > MAX_POINTS {
        // Not a curve this crate makes; split on the heap.
        let here = ctrl.iter().map(|&c| f(c)).fold(f64::NEG_INFINITY, f64::max);
        if depth == 0 {
            return here;
        }
        let (l, r) = split_half(ctrl);
        return hull_max(&l, depth - 1, f).max(hull_max(&r, depth - 1, f));
    }
    let mut points = [[0.0; 3]; MAX_POINTS];
    points[..ctrl.len()].copy_from_slice(ctrl);
    let mut best = f64::NEG_INFINITY;
    hull_max_into(&points[..ctrl.len()], depth, f, &mut best);
    best
}

fn hull_max_into(ctrl: &[Neu], depth: u32, f: &impl Fn(Neu) -> f64, best: &mut f64) {
    let here = ctrl.iter().map(|&c| f(c)).fold(f64::NEG_INFINITY, f64::max);
    if depth == 0 || ctrl.len() <= 2 || here <= *best {
        // A line segment's hull is the segment: its bound is exact already.
        *best = best.max(here);
        return;
    }
    let n = ctrl.len();
    let mut left = [[0.0; 3]; MAX_POINTS];
    let mut right = [[0.0; 3]; MAX_POINTS];
    let mut work = [[0.0; 3]; MAX_POINTS];
    work[..n].copy_from_slice(ctrl);
    for level in 0..n {
        left[level] = work[0];
        right[n - 1 - level] = work[n - 1 - level];
        for k in 0..n - 1 - level {
            let next = work[k + 1];
            for (w, x) in work[k].iter_mut().zip(next) {
                *w = 0.5 * (*w + x);
            }
        }
    }
    hull_max_into(&left[..n], depth - 1, f, best);
    hull_max_into(&right[..n], depth - 1, f, best);
}

/// The Euclidean norm of a vector.
pub(crate) fn norm(v: Neu) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cubic() -> Vec<Neu> {
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 2.0, 0.0],
            [3.0, -1.0, 1.0],
            [4.0, 0.5, 2.0],
        ]
    }

    /// Power-basis reference: B(τ) = Σ C(3,k) τ^k (1−τ)^(3−k) c_k.
    fn reference(c: &[Neu], t: f64) -> Neu {
        let b = [
            (1.0 - t).powi(3),
            3.0 * t * (1.0 - t).powi(2),
            3.0 * t * t * (1.0 - t),
            t.powi(3),
        ];
        [0, 1, 2].map(|a| (0..4).map(|k| b[k] * c[k][a]).sum())
    }

    #[test]
    fn de_casteljau_matches_the_bernstein_sum_and_the_halves_join() {
        let c = cubic();
        for i in 0..=20 {
            let t = i as f64 / 20.0;
            let (p, q) = (eval(&c, t), reference(&c, t));
            assert!((0..3).all(|a| (p[a] - q[a]).abs() < 1e-12), "{t}");
        }
        let (l, r) = split_half(&c);
        for i in 0..=10 {
            let t = i as f64 / 10.0;
            let (pl, ql) = (eval(&l, t), reference(&c, t / 2.0));
            let (pr, qr) = (eval(&r, t), reference(&c, 0.5 + t / 2.0));
            assert!((0..3).all(|a| (pl[a] - ql[a]).abs() < 1e-12 && (pr[a] - qr[a]).abs() < 1e-12));
        }
    }

    #[test]
    fn the_hodograph_is_the_derivative_and_hull_bounds_hold_and_tighten() {
        let c = cubic();
        let d = hodograph(&c, 2.0); // a piece of 2 s: d/dt = (1/2) d/dτ
        let h = 1e-6;
        for i in 1..20 {
            let t = i as f64 / 20.0;
            let (a, b) = (reference(&c, t - h), reference(&c, t + h));
            let fd = [0, 1, 2].map(|k| (b[k] - a[k]) / (2.0 * h) / 2.0);
            let e = eval(&d, t);
            assert!((0..3).all(|k| (fd[k] - e[k]).abs() < 1e-6));
        }
        let dense = (0..=10_000)
            .map(|i| norm(eval(&d, i as f64 / 10_000.0)))
            .fold(0.0, f64::max);
        let mut last = f64::INFINITY;
        for depth in 0..6 {
            let b = hull_max(&d, depth, &norm);
            assert!(
                b >= dense - 1e-12,
                "depth {depth}: bound {b} below the true max {dense}"
            );
            assert!(b <= last + 1e-12);
            last = b;
        }
        assert!(
            last - dense < 0.05 * dense,
            "depth 5 bound {last} vs max {dense}"
        );
    }

    /// Every leaf of the full 2^depth split, visited without pruning.
    fn all_leaves_max(c: &[Neu], depth: u32, f: &impl Fn(Neu) -> f64) -> f64 {
        let here = c.iter().map(|&p| f(p)).fold(f64::NEG_INFINITY, f64::max);
        if depth == 0 || c.len() <= 2 {
            return here;
        }
        let (l, r) = split_half(c);
        all_leaves_max(&l, depth - 1, f).max(all_leaves_max(&r, depth - 1, f))
    }

    #[test]
    fn pruned_hull_bounds_equal_the_full_split() {
        let mut rng = skyplan_testkit::XorShift::new(3);
        let mut next = || rng.unit() * 20.0 - 10.0;
        for n in 2..=7 {
            for _ in 0..200 {
                let c: Vec<Neu> = (0..n).map(|_| [next(), next(), next()]).collect();
                for depth in [0, 1, 4, 6] {
                    for f in [&norm as &dyn Fn(Neu) -> f64, &|p: Neu| p[2], &|p: Neu| {
                        -p[2]
                    }] {
                        let (a, b) = (hull_max(&c, depth, &f), all_leaves_max(&c, depth, &f));
                        assert_eq!(a, b, "{n} points, depth {depth}");
                    }
                }
            }
        }
    }
}
