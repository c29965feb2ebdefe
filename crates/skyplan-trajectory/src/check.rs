//! The guarantees, checked from the final pieces: every piece's control points inside a region
//! that is free, derivative bounds within the limits on the whole curve, continuity, and rest
//! at both ends.

use crate::bezier::{eval, hodograph, hull_max, norm};
use crate::{FreeSpace, Region, Trajectory};
use skyplan_world3::{Aabb, Neu};

/// Splits used for the hull bounds (2^4 sub-curves a piece).
pub(crate) const BOUND_DEPTH: u32 = 4;

/// Upper bounds that hold on the whole continuous trajectory (hull bounds of its derivative
/// curves), in the limits' units.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Bounds {
    /// Speed, m/s.
    pub speed_m_s: f64,
    /// Acceleration, m/s².
    pub accel_m_s2: f64,
    /// Jerk, m/s³.
    pub jerk_m_s3: f64,
    /// Climb rate, m/s.
    pub climb_m_s: f64,
    /// Descent rate, m/s.
    pub descent_m_s: f64,
    /// Yaw rate, degrees per second.
    pub yaw_rate_deg_s: f64,
}

/// Per-piece bounds of speed, acceleration, jerk, climb and descent.
pub(crate) fn piece_bounds(ctrl: &[Neu], duration_s: f64) -> Bounds {
    let v = hodograph(ctrl, duration_s);
    let a = hodograph(&v, duration_s);
    let j = hodograph(&a, duration_s);
    let nonneg = |x: f64| if x.is_finite() { x.max(0.0) } else { 0.0 };
    Bounds {
        speed_m_s: nonneg(hull_max(&v, BOUND_DEPTH, &norm)),
        accel_m_s2: nonneg(hull_max(&a, BOUND_DEPTH, &norm)),
        jerk_m_s3: nonneg(hull_max(&j, BOUND_DEPTH, &norm)),
        climb_m_s: nonneg(hull_max(&v, BOUND_DEPTH, &|c: Neu| c[2])),
        descent_m_s: nonneg(hull_max(&v, BOUND_DEPTH, &|c: Neu| -c[2])),
        yaw_rate_deg_s: 0.0,
    }
}

fn max_bounds(a: Bounds, b: Bounds) -> Bounds {
    Bounds {
        speed_m_s: a.speed_m_s.max(b.speed_m_s),
        accel_m_s2: a.accel_m_s2.max(b.accel_m_s2),
        jerk_m_s3: a.jerk_m_s3.max(b.jerk_m_s3),
        climb_m_s: a.climb_m_s.max(b.climb_m_s),
        descent_m_s: a.descent_m_s.max(b.descent_m_s),
        yaw_rate_deg_s: a.yaw_rate_deg_s.max(b.yaw_rate_deg_s),
    }
}

/// Distance from `p` to the segment `a → b`.
fn to_segment(p: Neu, a: Neu, b: Neu) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1] + (p[2] - a[2]) * d[2]) / len2)
            .clamp(0.0, 1.0)
    } else {
        0.0
    };
    norm([0, 1, 2].map(|k| p[k] - (a[k] + t * d[k])))
}

fn region_holds(region: &Region, ctrl: &[Neu], free: &dyn FreeSpace) -> Result<(), String> {
    match *region {
        Region::Box { min, max } => {
            let b = Aabb { min, max };
            if let Some(c) = ctrl.iter().find(|c| !b.contains(**c)) {
                return Err(format!(
                    "a control point ({:.3}, {:.3}, {:.3}) is outside its box",
                    c[0], c[1], c[2]
                ));
            }
            if !free.box_is_free(&b) {
                return Err("a corridor box is not free".into());
            }
        }
        Region::Segment { from, to } => {
            // Collinear to a nanometre: the fallback's pieces are the segment's own points.
            if ctrl.iter().any(|c| to_segment(*c, from, to) > 1e-9) {
                return Err("a control point is off its route segment".into());
            }
            if !free.segment_is_free(from, to) {
                return Err("a route segment is not free".into());
            }
        }
    }
    Ok(())
}

/// Checks every guarantee of `traj` against `free` and its limits, returning the proven
/// bounds, or the first guarantee broken, in a sentence.
pub fn verify(traj: &Trajectory, free: &dyn FreeSpace) -> Result<Bounds, String> {
    verify_from(traj, free, [0.0; 3], [0.0; 3])
}

/// As [`verify`] for a trajectory that starts moving (made by [`crate::plan_from`]): its
/// velocity and acceleration at the start must be `vel_neu_m_s` and `accel_neu_m_s2` (to a
/// micrometre per second); it still ends at rest.
pub fn verify_from(
    traj: &Trajectory,
    free: &dyn FreeSpace,
    vel_neu_m_s: Neu,
    accel_neu_m_s2: Neu,
) -> Result<Bounds, String> {
    let lim = &traj.limits;
    let mut all = Bounds::default();
    let (Some(first), Some(last)) = (traj.pieces.first(), traj.pieces.last()) else {
        return Err("the trajectory has no pieces".into());
    };
    for (k, p) in traj.pieces.iter().enumerate() {
        if !(p.duration_s > 0.0 && p.duration_s.is_finite()) {
            return Err(format!("piece {k} lasts {} s", p.duration_s));
        }
        region_holds(&p.region, &p.control_points_neu, free)
            .map_err(|e| format!("piece {k}: {e}"))?;
        all = max_bounds(all, piece_bounds(&p.control_points_neu, p.duration_s));
    }
    // Continuity of position, velocity and acceleration between pieces (to a micrometre per
    // second^k: the solver's rounding), and rest at both ends.
    for (k, w) in traj.pieces.windows(2).enumerate() {
        let (a, b) = (&w[0], &w[1]);
        let mut ca = a.control_points_neu.clone();
        let mut cb = b.control_points_neu.clone();
        for what in ["position", "velocity", "acceleration"] {
            if ca.is_empty() || cb.is_empty() {
                return Err(format!("pieces {k} and {} are of too low a degree", k + 1));
            }
            let (ea, eb) = (eval(&ca, 1.0), eval(&cb, 0.0));
            let gap = norm([0, 1, 2].map(|i| ea[i] - eb[i]));
            if gap > 1e-6 {
                return Err(format!(
                    "the {what} jumps by {gap:.2e} between pieces {k} and {}",
                    k + 1
                ));
            }
            ca = hodograph(&ca, a.duration_s);
            cb = hodograph(&cb, b.duration_s);
        }
    }
    let v0 = hodograph(&first.control_points_neu, first.duration_s);
    let v1 = hodograph(&last.control_points_neu, last.duration_s);
    let (a0, a1) = (
        hodograph(&v0, first.duration_s),
        hodograph(&v1, last.duration_s),
    );
    let off = |got: Neu, want: Neu| norm([0, 1, 2].map(|i| got[i] - want[i]));
    let (v_start, a_start) = (
        off(eval(&v0, 0.0), vel_neu_m_s),
        off(eval(&a0, 0.0), accel_neu_m_s2),
    );
    // At rest exactly (as the end); a moving start is set from the numbers given.
    let tol = if vel_neu_m_s == [0.0; 3] && accel_neu_m_s2 == [0.0; 3] {
        1e-9
    } else {
        1e-6
    };
    if v_start > tol || a_start > tol {
        return Err(format!(
            "the trajectory does not start in the state asked (velocity off by {v_start:.2e} m/s, acceleration by {a_start:.2e} m/s²)"
        ));
    }
    let at_rest = norm(eval(&v1, 1.0));
    let still = norm(eval(&a1, 1.0));
    if at_rest > 1e-9 || still > 1e-9 {
        return Err(format!(
            "the trajectory is not at rest at its end (speed {at_rest:.2e} m/s, acceleration {still:.2e} m/s²)"
        ));
    }
    // Yaw rate.
    for y in &traj.yaw {
        let c: Vec<Neu> = y
            .control_points_rad
            .iter()
            .map(|&v| [v, 0.0, 0.0])
            .collect();
        let d = hodograph(&c, y.duration_s);
        let r = hull_max(&d, BOUND_DEPTH, &norm).to_degrees();
        all.yaw_rate_deg_s = all.yaw_rate_deg_s.max(r);
    }
    let rel = 1.0 + 1e-9;
    for (what, got, max) in [
        ("speed", all.speed_m_s, lim.max_speed_m_s),
        ("acceleration", all.accel_m_s2, lim.max_accel_m_s2),
        ("jerk", all.jerk_m_s3, lim.max_jerk_m_s3),
        ("climb rate", all.climb_m_s, lim.max_climb_m_s),
        ("descent rate", all.descent_m_s, lim.max_descent_m_s),
        ("yaw rate", all.yaw_rate_deg_s, lim.max_yaw_rate_deg_s),
    ] {
        if got > max * rel {
            return Err(format!(
                "the {what} may reach {got:.3}, above the limit {max}"
            ));
        }
    }
    let yaw_total: f64 = traj.yaw.iter().map(|y| y.duration_s).sum();
    if (yaw_total - traj.duration_s()).abs() > 1e-6 * traj.duration_s().max(1.0) {
        return Err("the yaw lasts another time than the position".into());
    }
    Ok(all)
}
