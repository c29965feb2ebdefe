//! The jerk-limited stop-at-each-waypoint profile: each segment of the route flown from rest to
//! rest along the segment itself (seven phases of constant jerk: the classic S-curve), at the
//! speed the climb and descent limits allow on that segment.

use crate::{Limits, Method, Piece, Region, Trajectory, TrajectoryError, assemble};
use skyplan_world3::Neu;

/// The shortest phase the profile keeps, seconds: a piece much shorter than this has control
/// points so close together that their rounding (about 1e-14 m at 100 m from home) shows in the
/// acceleration bound divided by its duration squared, and the proof of the limits would fail by
/// a hair.
const MIN_PHASE_S: f64 = 0.05;

/// Phase durations `[t_jerk, t_accel, t_cruise]` and the jerk of the fastest rest-to-rest move
/// of `len` within speed, acceleration and jerk limits that has no phase shorter than
/// [`MIN_PHASE_S`] (apart from phases of zero length).
fn s_curve(len: f64, v: f64, a: f64, j: f64) -> ([f64; 3], f64) {
    // A jerk so high that the acceleration is reached in under the shortest phase is lowered.
    let j = j.min(a / MIN_PHASE_S);
    let tiny = |t: f64| t > 1e-12 && t < 0.5 * MIN_PHASE_S;
    let ok = |p: &[f64; 3]| p.iter().all(|&t| t > -1e-12 && !tiny(t));
    let total = |p: &[f64; 3]| 4.0 * p[0] + 2.0 * p[1] + p[2];
    let clean = |p: [f64; 3]| p.map(|t| if t <= 1e-12 { 0.0 } else { t });
    let exact = time_optimal(len, v, a, j);
    if ok(&exact) {
        return (clean(exact), j);
    }
    // A move with no hold and no cruise always exists: a peak speed `V` reached by one jerk
    // ramp up and down, `len = 2 V t`, `V = j' t²`, within every limit.
    let peak = (j * len * len / 4.0)
        .cbrt()
        .min((a * len / 2.0).sqrt())
        .min(v);
    let tj = len / (2.0 * peak);
    let mut best = ([tj, 0.0, 0.0], peak / (tj * tj));
    let mut consider = |p: [f64; 3]| {
        if ok(&p) && total(&p) < total(&best.0) {
            best = (clean(p), j);
        }
    };
    // A hold of the shortest kept length at the same speed: a little less acceleration
    // (`v = a'² / j + a' · MIN_PHASE_S`).
    let m = MIN_PHASE_S * j;
    let a_hold = (0.5 * (-m + (m * m + 4.0 * j * v).sqrt())).min(a);
    consider(time_optimal(len, v, a_hold, j));
    // No hold: the speed the jerk ramp alone reaches at full acceleration.
    if a * a / j < v {
        consider(time_optimal(len, a * a / j, a, j));
    }
    // A cruise of the shortest kept length: the speed found by bisection (the cruise shortens
    // as the speed grows).
    let (mut lo, mut hi) = (0.0, v);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if time_optimal(len, mid, a, j)[2] >= MIN_PHASE_S {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if lo > 0.0 {
        consider(time_optimal(len, lo, a, j));
    }
    best
}

/// Phase durations `[t_jerk, t_accel, t_cruise]` of the time-optimal rest-to-rest move of `len`
/// with speed, acceleration and jerk limits (the classic S-curve).
fn time_optimal(len: f64, v: f64, a: f64, j: f64) -> [f64; 3] {
    // Accelerating to `v` and back covers v · (time to reach v).
    let reach = |v: f64| -> ([f64; 2], f64) {
        if v * j >= a * a {
            let tj = a / j;
            ([tj, v / a - tj], v / a + tj)
        } else {
            let tj = (v / j).sqrt();
            ([tj, 0.0], 2.0 * tj)
        }
    };
    let ([tj, ta], ramp) = reach(v);
    if v * ramp <= len {
        return [tj, ta, (len - v * ramp) / v];
    }
    // Too short to reach v: the peak speed that just covers len.
    let (tj0, a0) = (a / j, a);
    let vp = 0.5 * a0 * (-tj0 + (tj0 * tj0 + 4.0 * len / a0).sqrt());
    let vp = if vp * j >= a * a {
        vp
    } else {
        (len * j.sqrt() / 2.0).powf(2.0 / 3.0)
    };
    let ([tj, ta], _) = reach(vp);
    [tj, ta, 0.0]
}

/// The seven phases of an S-curve as (duration, jerk): up, hold, down, cruise, down, hold, up.
fn phases([tj, ta, tc]: [f64; 3], j: f64) -> [(f64, f64); 7] {
    [
        (tj, j),
        (ta, 0.0),
        (tj, -j),
        (tc, 0.0),
        (tj, -j),
        (ta, 0.0),
        (tj, j),
    ]
}

/// A cubic piece of the line `from + dir · s(t)` with `s(t) = s0 + v0 t + a0 t²/2 + j t³/6`.
fn cubic(from: Neu, to: Neu, dir: Neu, s: [f64; 4], duration_s: f64) -> Piece {
    let [s0, v0, a0, j] = s;
    let t = duration_s;
    let (b0, b1, b2, b3) = (s0, v0 * t, a0 * t * t / 2.0, j * t * t * t / 6.0);
    let bern = [
        b0,
        b0 + b1 / 3.0,
        b0 + 2.0 * b1 / 3.0 + b2 / 3.0,
        b0 + b1 + b2 + b3,
    ];
    Piece {
        duration_s,
        control_points_neu: bern
            .iter()
            .map(|&u| [0, 1, 2].map(|k| from[k] + dir[k] * u))
            .collect(),
        region: Region::Segment { from, to },
    }
}

/// The stop-at-each-waypoint trajectory of `route` within `limits` (yaw as for any trajectory).
///
/// ```
/// use skyplan_trajectory::{stop_at_waypoints, Limits};
/// let t = stop_at_waypoints(&[[0.0, 0.0, 10.0], [100.0, 0.0, 10.0]], &Limits::default())?;
/// // 2.9 s to reach 10 m/s (jerk-limited), 7.1 s at 10 m/s, 2.9 s to stop.
/// assert!((t.duration_s() - 12.9).abs() < 1e-9);
/// # Ok::<(), skyplan_trajectory::TrajectoryError>(())
/// ```
pub fn stop_at_waypoints(route: &[Neu], limits: &Limits) -> Result<Trajectory, TrajectoryError> {
    limits.check()?;
    let route = crate::check_route(route)?;
    let (a, j) = (limits.max_accel_m_s2, limits.max_jerk_m_s3);
    let mut pieces = Vec::new();
    for w in route.windows(2) {
        let (from, to) = (w[0], w[1]);
        let len = skyplan_world3::distance_m(from, to);
        if len <= 1e-9 {
            continue;
        }
        let dir = [0, 1, 2].map(|k| (to[k] - from[k]) / len);
        let v = crate::leg_speed_m_s(from, to, limits);
        let ([tj, ta, tc], j) = s_curve(len, v, a, j);
        let (mut s, mut vel, mut acc) = (0.0, 0.0, 0.0);
        let start = pieces.len();
        for (d, jk) in phases([tj, ta, tc], j) {
            if d <= 1e-12 {
                continue;
            }
            pieces.push(cubic(from, to, dir, [s, vel, acc, jk], d));
            s += vel * d + acc * d * d / 2.0 + jk * d * d * d / 6.0;
            vel += acc * d + jk * d * d / 2.0;
            acc += jk * d;
        }
        // The last phase is `to − dir · j (T − t)³ / 6`: control points [·, to, to, to]
        // exactly (at rest, without the rounding of the phase sums).
        if let Some(last) = pieces[start..].last_mut() {
            for c in last.control_points_neu.iter_mut().skip(1) {
                *c = to;
            }
        }
    }
    Ok(assemble(Method::StopAtWaypoints, None, limits, pieces))
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_testkit::XorShift;

    /// Integrates the seven phases exactly (in steps): distance, and the peaks of speed,
    /// acceleration and jerk.
    fn integrate(p: [f64; 3], j: f64) -> (f64, f64, f64) {
        let (mut s, mut v, mut acc, mut v_max, mut a_max) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (d, jk) in phases(p, j) {
            s += v * d + acc * d * d / 2.0 + jk * d * d * d / 6.0;
            v += acc * d + jk * d * d / 2.0;
            acc += jk * d;
            v_max = v_max.max(v);
            a_max = a_max.max(acc.abs());
        }
        assert!(v.abs() < 1e-9 && acc.abs() < 1e-9, "not at rest: {v} {acc}");
        (s, v_max, a_max)
    }

    /// Random moves, many near the borders where a hold or a cruise is tiny: no phase under
    /// half the minimum, the move covers the length from rest to rest within every limit, and
    /// costs little over the time-optimal one.
    #[test]
    fn profiles_keep_no_tiny_phase_and_stay_near_optimal() {
        let mut rng = XorShift::new(11);
        let mut worst_s: f64 = 0.0;
        for case in 0..20_000 {
            let (v, a, j) = (
                0.5 + 15.0 * rng.unit(),
                0.5 + 8.0 * rng.unit(),
                1.0 + 30.0 * rng.unit(),
            );
            // Every third case sits where the exact profile's hold or cruise is nearly empty.
            let len = match case % 3 {
                0 => 0.01 + 150.0 * rng.unit(),
                1 => {
                    let j = j.min(a / MIN_PHASE_S);
                    let v = v.min(a * a / j * (1.0 + 0.01 * rng.unit()));
                    if v < 0.5 {
                        continue;
                    }
                    let [tj, ta, _] = time_optimal(1e9, v, a, j);
                    v * (2.0 * tj + ta) * (1.0 + 1e-3 * rng.unit())
                }
                _ => {
                    let [tj, ta, _] = time_optimal(1e9, v, a, j);
                    v * (2.0 * tj + ta) + v * 0.03 * rng.unit()
                }
            };
            let (p, jerk) = s_curve(len, v, a, j);
            for t in p {
                assert!(
                    t <= 1e-12 || t >= 0.5 * MIN_PHASE_S,
                    "phase {t} s in case {case}"
                );
            }
            let (s, v_max, a_max) = integrate(p, jerk);
            assert!((s - len).abs() < 1e-9 * len.max(1.0), "covers {s} of {len}");
            assert!(
                v_max <= v * (1.0 + 1e-12)
                    && a_max <= a * (1.0 + 1e-12)
                    && jerk <= j * (1.0 + 1e-12)
            );
            let opt = time_optimal(len, v, a, j);
            let excess = (4.0 * p[0] + 2.0 * p[1] + p[2]) - (4.0 * opt[0] + 2.0 * opt[1] + opt[2]);
            assert!(excess >= -1e-9, "faster than optimal by {excess} s");
            if excess > worst_s {
                eprintln!(
                    "excess {excess}: {p:?} vs {opt:?} len {len} v {v} a {a} j {j} jerk {jerk}"
                );
            }
            worst_s = worst_s.max(excess);
        }
        assert!(
            worst_s < 0.2,
            "up to {worst_s} s over the time-optimal move"
        );
    }
}
