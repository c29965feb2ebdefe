//! The jerk-limited stop-at-each-waypoint profile: each segment of the route flown from rest to
//! rest along the segment itself (seven phases of constant jerk: the classic S-curve), at the
//! speed the climb and descent limits allow on that segment.

use crate::{Limits, Method, Piece, Region, Trajectory, TrajectoryError, assemble};
use skyplan_world3::Neu;

/// Phase durations `[t_jerk, t_accel, t_cruise]` and the peak speed for a rest-to-rest move of
/// `len` with speed, acceleration and jerk limits.
fn s_curve(len: f64, v: f64, a: f64, j: f64) -> ([f64; 3], f64) {
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
        return ([tj, ta, (len - v * ramp) / v], v);
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
    ([tj, ta, 0.0], vp)
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
        let ([tj, ta, tc], _) = s_curve(len, v, a, j);
        // Jerk per phase: up, hold, down, cruise, down, hold, up.
        let phases = [
            (tj, j),
            (ta, 0.0),
            (tj, -j),
            (tc, 0.0),
            (tj, -j),
            (ta, 0.0),
            (tj, j),
        ];
        let (mut s, mut vel, mut acc) = (0.0, 0.0, 0.0);
        let start = pieces.len();
        for (d, jk) in phases {
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
