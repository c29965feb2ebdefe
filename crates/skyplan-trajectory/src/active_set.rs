//! The corridor QP of one axis, solved by a primal active-set method on the joins' states.
//!
//! Parametrised by the position, velocity and acceleration at each join (the ends are at rest),
//! a chain of quintic pieces is C² by construction, and its jerk energy is a block-tridiagonal
//! quadratic in those states: a banded matrix of bandwidth 5 whose Cholesky factor costs O(n).
//! Every control point is a linear function of at most three states, so the corridor is a set
//! of sparse linear inequalities of which only a handful are active at the optimum (14 of 1,224
//! on the default route). A primal active-set method started from a feasible point — the joins
//! where the shape put them, at rest, whose pieces are straight segments inside their boxes —
//! adds the constraint that blocks each step and drops the one with the most negative
//! multiplier, solving each equality-constrained step through the Schur complement of the
//! working set (one banded solve per constraint, cached while it stays in the set).
//!
//! The result is the same minimiser clarabel finds for the same problem (tested against it); it
//! answers `None` when it cannot start (an infeasible starting point, as a climb limit can make
//! one) or does not finish within its iteration cap, and the caller then uses clarabel.

// Band and triangle indices are arithmetic on the loop variable: ranges read clearer here.
#![allow(clippy::needless_range_loop)]

/// One axis's problem, in coordinates shifted so the start is 0 (like [`crate::optimize`]).
pub(crate) struct AxisProblem<'a> {
    /// Piece durations, seconds.
    pub times: &'a [f64],
    /// Each piece's box on this axis.
    pub lo: Vec<f64>,
    /// Each piece's box on this axis.
    pub hi: Vec<f64>,
    /// Where the trajectory ends on this axis.
    pub goal: f64,
    /// Bounds on each join's position (join `j` between pieces `j` and `j + 1`), if any.
    pub joint_bounds: Option<Vec<(f64, f64)>>,
    /// A feasible position for each join, inside both of its boxes (and its bounds).
    pub start_joins: Vec<f64>,
    /// `(max_climb_m_s, max_descent_m_s)` on the vertical axis.
    pub climb: Option<(f64, f64)>,
    /// How far inside each box the control points are kept (the solver's hair).
    pub hair: f64,
    /// A guess at each join's `(position, velocity, acceleration)` (a previous solution): the
    /// iterations start as far towards it from the feasible start as the constraints allow.
    pub warm: Option<Vec<[f64; 3]>>,
}

/// Up to six `(state, coefficient)` terms, inline (a control point has at most three, a
/// difference of two at most six): rows are read in every iteration, so no pointer to chase.
#[derive(Clone, Copy, Default)]
struct Terms {
    items: [(usize, f64); 6],
    len: usize,
}

impl Terms {
    fn one(i: usize, v: f64) -> Self {
        let mut t = Self::default();
        t.push((i, v));
        t
    }

    fn push(&mut self, term: (usize, f64)) {
        self.items[self.len] = term;
        self.len += 1;
    }
}

impl std::ops::Deref for Terms {
    type Target = [(usize, f64)];
    fn deref(&self) -> &Self::Target {
        &self.items[..self.len]
    }
}

impl std::ops::DerefMut for Terms {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.items[..self.len]
    }
}

/// A linear expression over the free states plus a constant.
#[derive(Clone, Copy, Default)]
struct Expr {
    terms: Terms,
    constant: f64,
}

/// A constraint `g · y ≤ b` over the free states.
struct Row {
    g: Terms,
    b: f64,
    /// `|g|₁`.
    norm: f64,
}

impl Row {
    fn dot(&self, y: &[f64]) -> f64 {
        self.g.iter().map(|&(i, v)| v * y[i]).sum()
    }
}

/// A symmetric positive definite banded matrix, factorised in place (lower band, `BW` below
/// the diagonal).
struct Banded {
    n: usize,
    /// `band[i][k]` is entry `(i, i - BW + k)`; `band[i][BW]` the diagonal.
    band: Vec<[f64; BW + 1]>,
}

const BW: usize = 5;

impl Banded {
    fn zeros(n: usize) -> Self {
        Self {
            n,
            band: vec![[0.0; BW + 1]; n],
        }
    }

    /// Adds `v` to the symmetric entry `(i, j)`; `None` outside the band.
    fn add(&mut self, i: usize, j: usize, v: f64) -> Option<()> {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        let k = (BW + c).checked_sub(r)?;
        self.band[r][k] += v;
        Some(())
    }

    /// Cholesky `L Lᵀ` in place; `None` when not positive definite.
    fn factor(&mut self) -> Option<()> {
        for i in 0..self.n {
            for k in 0..=BW {
                let j = (i + k).checked_sub(BW);
                let Some(j) = j else { continue };
                // Entry (i, j), j ≤ i.
                let mut s = self.band[i][k];
                let from = i.saturating_sub(BW).max(j.saturating_sub(BW));
                for m in from..j {
                    s -= self.band[i][BW + m - i] * self.band[j][BW + m - j];
                }
                if j == i {
                    if s <= 0.0 || !s.is_finite() {
                        return None;
                    }
                    self.band[i][BW] = s.sqrt();
                } else {
                    self.band[i][k] = s / self.band[j][BW];
                }
            }
        }
        Some(())
    }

    /// Solves `L Lᵀ x = rhs` in place.
    fn solve(&self, x: &mut [f64]) {
        for i in 0..self.n {
            let mut s = x[i];
            for m in i.saturating_sub(BW)..i {
                s -= self.band[i][BW + m - i] * x[m];
            }
            x[i] = s / self.band[i][BW];
        }
        for i in (0..self.n).rev() {
            let mut s = x[i];
            for m in i + 1..(i + BW + 1).min(self.n) {
                s -= self.band[m][BW + i - m] * x[m];
            }
            x[i] = s / self.band[i][BW];
        }
    }
}

impl AxisProblem<'_> {
    /// The control points of each piece (shifted coordinates), or `None` (use clarabel).
    pub(crate) fn solve(&self, weights: &[f64], hessian: &[[f64; 6]; 6]) -> Option<Vec<[f64; 6]>> {
        let n = self.times.len();
        let joins = n - 1;
        let tref = self.times.iter().sum::<f64>() / n as f64;
        // State `3 (j - 1) + r` of join j (1..n): r = 0 position, 1 velocity × tref,
        // 2 acceleration × tref². Fixed states (in flat boxes) have a value instead of an index.
        let mut fixed: Vec<Option<f64>> = vec![None; 3 * joins];
        for p in 0..n {
            if self.hi[p] - self.lo[p] < 1e-6 {
                let mid = 0.5 * (self.lo[p] + self.hi[p]);
                for j in [p, p + 1] {
                    if j == 0 || j == n {
                        continue;
                    }
                    for (r, v) in [mid, 0.0, 0.0].into_iter().enumerate() {
                        let slot = &mut fixed[3 * (j - 1) + r];
                        if slot.is_some_and(|old| (old - v).abs() > 1e-9) {
                            return None;
                        }
                        *slot = Some(v);
                    }
                }
            }
        }
        let mut free_of = vec![usize::MAX; 3 * joins];
        let mut nfree = 0;
        for (s, f) in fixed.iter().enumerate() {
            if f.is_none() {
                free_of[s] = nfree;
                nfree += 1;
            }
        }
        // The state `r` of join `j` as an expression.
        let state = |j: usize, r: usize| -> Expr {
            if j == 0 {
                return Expr::default();
            }
            if j == n {
                return Expr {
                    terms: Terms::default(),
                    constant: if r == 0 { self.goal } else { 0.0 },
                };
            }
            let s = 3 * (j - 1) + r;
            match fixed[s] {
                Some(v) => Expr {
                    terms: Terms::default(),
                    constant: v,
                },
                None => Expr {
                    terms: Terms::one(free_of[s], 1.0),
                    constant: 0.0,
                },
            }
        };
        // Control point k of piece p as Σ coef · state.
        let control = |p: usize, k: usize| -> Expr {
            let s = self.times[p] / tref;
            let (j, sign) = if k < 3 { (p, 1.0) } else { (p + 1, -1.0) };
            let coefs = match k {
                0 | 5 => [1.0, 0.0, 0.0],
                1 | 4 => [1.0, sign * s / 5.0, 0.0],
                _ => [1.0, sign * 2.0 * s / 5.0, s * s / 20.0],
            };
            let mut e = Expr::default();
            for (r, &c) in coefs.iter().enumerate() {
                if c == 0.0 {
                    continue;
                }
                let st = state(j, r);
                e.constant += c * st.constant;
                for &(i, v) in st.terms.iter() {
                    e.terms.push((i, c * v));
                }
            }
            e
        };
        // The objective ½ yᵀ Q y + lin · y.
        let mut q = Banded::zeros(nfree);
        let mut lin = vec![0.0; nfree];
        for p in 0..n {
            let cps: Vec<Expr> = (0..6).map(|k| control(p, k)).collect();
            let w = weights[p];
            for (a, ca) in cps.iter().enumerate() {
                for (b, cb) in cps.iter().enumerate() {
                    let h = 2.0 * w * hessian[a][b];
                    if h == 0.0 {
                        continue;
                    }
                    for &(i, vi) in ca.terms.iter() {
                        for &(j, vj) in cb.terms.iter() {
                            // Entry (i, j) of the symmetric Q; the lower band holds i ≥ j.
                            if i >= j {
                                q.add(i, j, h * vi * vj)?;
                            }
                        }
                        lin[i] += h * vi * cb.constant;
                    }
                }
            }
        }
        q.factor()?;
        // Constraints.
        let mut rows: Vec<Row> = Vec::new();
        let mut push = |e: &Expr, sign: f64, bound: f64| -> Option<()> {
            if bound.is_infinite() {
                return Some(());
            }
            if e.terms.is_empty() {
                // A constant point (the start, the goal): it must already hold, to a hair.
                return (sign * e.constant <= bound + 2.0 * self.hair + 1e-9).then_some(());
            }
            let mut g = e.terms;
            g.iter_mut().for_each(|t| t.1 *= sign);
            g.sort_by_key(|t| t.0);
            rows.push(Row {
                norm: g.iter().map(|t| t.1.abs()).sum(),
                g,
                b: bound - sign * e.constant,
            });
            Some(())
        };
        for p in 0..n {
            if self.hi[p] - self.lo[p] < 1e-6 {
                continue;
            }
            let hair = self.hair.min((self.hi[p] - self.lo[p]) / 4.0);
            for k in 0..6 {
                if (k == 0 && p > 0) || (k == 5 && p + 1 < n) {
                    // A join: bounded by both of its boxes at once (below).
                    continue;
                }
                let e = control(p, k);
                push(&e, 1.0, self.hi[p] - hair)?;
                push(&e, -1.0, -(self.lo[p] + hair))?;
            }
            if let Some((up, down)) = self.climb {
                let c = 5.0 / self.times[p];
                for k in 0..5 {
                    let (a, b) = (control(p, k + 1), control(p, k));
                    let mut d = Expr {
                        terms: a.terms,
                        constant: c * (a.constant - b.constant),
                    };
                    d.terms.iter_mut().for_each(|t| t.1 *= c);
                    for &(i, v) in b.terms.iter() {
                        d.terms.push((i, -c * v));
                    }
                    push(&d, 1.0, up)?;
                    push(&d, -1.0, down)?;
                }
            }
        }
        // Each join inside both of its boxes, the hair scaled to where they overlap (on a
        // face two boxes share, that is the face).
        for j in 1..n {
            let (lo, hi) = (
                self.lo[j - 1].max(self.lo[j]),
                self.hi[j - 1].min(self.hi[j]),
            );
            if hi < lo - 1e-9 {
                return None;
            }
            let hair = self.hair.min((hi - lo).max(0.0) / 4.0);
            let e = state(j, 0);
            push(&e, 1.0, hi - hair)?;
            push(&e, -1.0, -(lo + hair))?;
        }
        if let Some(bounds) = &self.joint_bounds {
            for (j, &(lo, hi)) in bounds.iter().enumerate() {
                let e = state(j + 1, 0);
                push(&e, 1.0, hi)?;
                push(&e, -1.0, -lo)?;
            }
        }
        let rows = dedupe(rows);
        // The starting point: joins where given, at rest.
        let mut y = vec![0.0; nfree];
        for j in 1..n {
            if let Some(&i) = free_of.get(3 * (j - 1)).filter(|&&i| i != usize::MAX) {
                y[i] = self.start_joins[j - 1];
            }
        }
        // At rest every control point of a piece is one of its joins: the rows on a join's
        // position alone bound it; a start on a face is moved the hair inwards.
        for r in rows.iter().filter(|r| r.g.len() == 1) {
            let (i, c) = r.g[0];
            if c > 0.0 {
                y[i] = y[i].min(r.b / c);
            } else {
                y[i] = y[i].max(r.b / c);
            }
        }
        let scale = 1.0 + y.iter().fold(self.goal.abs(), |m, v| m.max(v.abs()));
        if rows
            .iter()
            .any(|r| r.dot(&y) > r.b + 2.0 * self.hair + 1e-9 * scale)
        {
            return None;
        }
        if let Some(warm) = &self.warm {
            let mut toward = y.clone();
            for (j, st) in warm.iter().enumerate().take(joins) {
                for (r, v) in [st[0], st[1] * tref, st[2] * tref * tref]
                    .into_iter()
                    .enumerate()
                {
                    let f = free_of[3 * j + r];
                    if f != usize::MAX && v.is_finite() {
                        toward[f] = v;
                    }
                }
            }
            // Each join moves as far along the straight line towards its guess as its own
            // rows allow (a box row bounds one control point: it involves one join's states);
            // rows over two joins (climb limits) then cap every join's step at once.
            let mut join_of = vec![0; nfree];
            for (s, &f) in free_of.iter().enumerate() {
                if f != usize::MAX {
                    join_of[f] = s / 3;
                }
            }
            let d: Vec<f64> = toward.iter().zip(&y).map(|(a, b)| a - b).collect();
            let mut theta = vec![1.0_f64; joins];
            let mut common = 1.0_f64;
            let mut coupled = false;
            for r in &rows {
                let gd = dot_sparse(&r.g, &d);
                if gd <= 0.0 {
                    continue;
                }
                let step = ((r.b - r.dot(&y)) / gd).max(0.0);
                common = common.min(step);
                let j = join_of[r.g[0].0];
                if r.g.iter().all(|t| join_of[t.0] == j) {
                    theta[j] = theta[j].min(step);
                } else {
                    coupled = true;
                }
            }
            let apart: Vec<f64> = y
                .iter()
                .zip(&d)
                .enumerate()
                .map(|(i, (yi, di))| yi + theta[join_of[i]] * di)
                .collect();
            let tol = 2.0 * self.hair + 1e-9 * scale;
            if !coupled || rows.iter().all(|r| r.dot(&apart) <= r.b + tol) {
                y = apart;
            } else {
                for (yi, di) in y.iter_mut().zip(&d) {
                    *yi += common * di;
                }
            }
        }
        self.iterate(&q, &lin, &rows, y, scale)
            .map(|y| self.control_points(&y, &control))
    }

    fn control_points(&self, y: &[f64], control: &impl Fn(usize, usize) -> Expr) -> Vec<[f64; 6]> {
        (0..self.times.len())
            .map(|p| {
                std::array::from_fn(|k| {
                    let e = control(p, k);
                    e.constant + e.terms.iter().map(|&(i, v)| v * y[i]).sum::<f64>()
                })
            })
            .collect()
    }

    /// The primal active-set iterations from the feasible `y`.
    fn iterate(
        &self,
        q: &Banded,
        lin: &[f64],
        rows: &[Row],
        mut y: Vec<f64>,
        scale: f64,
    ) -> Option<Vec<f64>> {
        let nfree = y.len();
        let mut work = Working::new(rows.len());
        let cap = 4 * rows.len() + 100;
        // Whether y is the minimiser on the working set (the last step was a full one).
        let mut at_min = false;
        // Rows that depend on the working set (cleared when a row leaves it).
        let mut aside = vec![false; rows.len()];
        let mut q_lin = lin.to_vec();
        q.solve(&mut q_lin);
        for _ in 0..cap {
            // u = Q⁻¹ (Q y + lin) = y + Q⁻¹ lin.
            let u: Vec<f64> = y.iter().zip(&q_lin).map(|(a, b)| a + b).collect();
            // S μ = −G_W u + (G_W y − b_W), then p = −u − Σ μ_j Q⁻¹ g_j: the step keeps the
            // working rows at their bounds and takes back what rounding let them drift.
            let rhs: Vec<f64> = work
                .rows
                .iter()
                .map(|&i| -dot_sparse(&rows[i].g, &u) + rows[i].dot(&y) - rows[i].b)
                .collect();
            let mu = work.solve(rhs);
            let mut p: Vec<f64> = u.iter().map(|v| -v).collect();
            for (m, zj) in mu.iter().zip(&work.z) {
                for (pi, zi) in p.iter_mut().zip(zj) {
                    *pi -= m * zi;
                }
            }
            let pmax = p.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            if at_min || pmax <= 1e-11 * scale {
                at_min = false;
                // At the minimiser on the working set: optimal unless a multiplier is negative.
                let mscale = 1.0 + mu.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                let worst = mu
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.total_cmp(b.1))
                    .filter(|(_, m)| **m < -1e-10 * mscale);
                match worst {
                    None => {
                        // Rounding may have let a row slip by a hair: never past the box. A
                        // row that slipped further joins the working set, and the next step
                        // takes it back to its bound.
                        let slack = 0.5 * self.hair;
                        let slipped = rows
                            .iter()
                            .enumerate()
                            .filter(|(i, r)| !work.has[*i] && r.dot(&y) > r.b + slack)
                            .max_by(|a, b| (a.1.dot(&y) - a.1.b).total_cmp(&(b.1.dot(&y) - b.1.b)));
                        let Some((i, _)) = slipped else {
                            return rows.iter().all(|r| r.dot(&y) <= r.b + slack).then_some(y);
                        };
                        let mut zi = vec![0.0; nfree];
                        for &(k, v) in rows[i].g.iter() {
                            zi[k] = v;
                        }
                        q.solve(&mut zi);
                        if !work.add(i, zi, rows) {
                            return None;
                        }
                    }
                    Some((k, _)) => {
                        work.remove(k, rows)?;
                        aside.iter_mut().for_each(|a| *a = false);
                    }
                }
                continue;
            }
            // The longest step along p that stays feasible. A blocking row that depends on
            // the working set (it only blocks through rounding) is set aside, not added.
            let (alpha, block) = loop {
                let mut alpha = 1.0;
                let mut block = None;
                for (i, r) in rows.iter().enumerate() {
                    if work.has[i] || aside[i] {
                        continue;
                    }
                    let gp = dot_sparse(&r.g, &p);
                    if gp <= 1e-12 * r.norm * pmax {
                        continue;
                    }
                    let a = ((r.b - r.dot(&y)) / gp).max(0.0);
                    if a < alpha {
                        alpha = a;
                        block = Some(i);
                    }
                }
                let Some(i) = block else {
                    break (alpha, false);
                };
                let mut zi = vec![0.0; nfree];
                for &(k, v) in rows[i].g.iter() {
                    zi[k] = v;
                }
                q.solve(&mut zi);
                if work.add(i, zi, rows) {
                    break (alpha, true);
                }
                aside[i] = true;
            };
            for (yi, pi) in y.iter_mut().zip(&p) {
                *yi += alpha * pi;
            }
            at_min = !block;
        }
        None
    }
}

/// The working set: its rows, each one's `Q⁻¹ g`, and the Cholesky factor of their Schur
/// complement `S = G Q⁻¹ Gᵀ`, grown a row at a time.
struct Working {
    rows: Vec<usize>,
    has: Vec<bool>,
    z: Vec<Vec<f64>>,
    /// Lower-triangular factor of S, row by row.
    l: Vec<Vec<f64>>,
}

impl Working {
    fn new(n_rows: usize) -> Self {
        Self {
            rows: Vec::new(),
            has: vec![false; n_rows],
            z: Vec::new(),
            l: Vec::new(),
        }
    }

    /// Appends row `i` (with `zi = Q⁻¹ gᵢ`) unless it depends on the set; says whether it did.
    fn add(&mut self, i: usize, zi: Vec<f64>, rows: &[Row]) -> bool {
        let own = dot_sparse(&rows[i].g, &zi);
        let cross: Vec<f64> = self
            .rows
            .iter()
            .map(|&w| dot_sparse(&rows[w].g, &zi))
            .collect();
        // Forward substitution: L w = cross.
        let mut w = cross;
        for r in 0..w.len() {
            let s: f64 = (0..r).map(|c| self.l[r][c] * w[c]).sum();
            w[r] = (w[r] - s) / self.l[r][r];
        }
        // What the working set cannot express of row i, in Q⁻¹'s metric.
        let left = own - w.iter().map(|v| v * v).sum::<f64>();
        if left.is_nan() || left <= 1e-9 * own {
            return false;
        }
        w.push(left.sqrt());
        self.l.push(w);
        self.rows.push(i);
        self.has[i] = true;
        self.z.push(zi);
        true
    }

    /// Drops the `k`-th member and refactors; `None` if the rest stopped being independent.
    fn remove(&mut self, k: usize, rows: &[Row]) -> Option<()> {
        let i = self.rows.remove(k);
        self.has[i] = false;
        self.z.remove(k);
        let n = self.rows.len();
        let mut l = vec![vec![0.0; 0]; n];
        for r in 0..n {
            let mut row = vec![0.0; r + 1];
            for c in 0..=r {
                let mut s = dot_sparse(&rows[self.rows[r]].g, &self.z[c]);
                for m in 0..c {
                    let lcm = if c == r { row[m] } else { l[c][m] };
                    s -= row[m] * lcm;
                }
                if c == r {
                    if s <= 0.0 || !s.is_finite() {
                        return None;
                    }
                    row[c] = s.sqrt();
                } else {
                    row[c] = s / l[c][c];
                }
            }
            l[r] = row;
        }
        self.l = l;
        Some(())
    }

    /// Solves `S x = b` with the factor.
    fn solve(&self, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for r in 0..n {
            let s: f64 = (0..r).map(|c| self.l[r][c] * b[c]).sum();
            b[r] = (b[r] - s) / self.l[r][r];
        }
        for r in (0..n).rev() {
            let s: f64 = (r + 1..n).map(|m| self.l[m][r] * b[m]).sum();
            b[r] = (b[r] - s) / self.l[r][r];
        }
        b
    }
}

fn dot_sparse(g: &[(usize, f64)], x: &[f64]) -> f64 {
    g.iter().map(|&(i, v)| v * x[i]).sum()
}

/// One row per distinct left-hand side, with the tightest bound (a join's position is bounded
/// by both of its boxes: two parallel rows would make the working set singular).
fn dedupe(mut rows: Vec<Row>) -> Vec<Row> {
    let same_side = |a: &Row, b: &Row| {
        a.g.iter()
            .map(|&(i, v)| (i, v.to_bits()))
            .cmp(b.g.iter().map(|&(i, v)| (i, v.to_bits())))
    };
    rows.sort_by(|a, b| same_side(a, b).then(a.b.total_cmp(&b.b)));
    rows.dedup_by(|later, kept| same_side(later, kept).is_eq());
    rows
}
