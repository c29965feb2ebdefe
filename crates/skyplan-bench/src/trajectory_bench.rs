//! `skyplan bench --trajectory`: trajectories of far city routes — compute time, duration against
//! the route at the speed limit and against stopping at each waypoint, violations checked
//! independently — beside TOPP-RA and ruckig on the same routes (`bench/peers_trajectory.py`).

use skyplan_plan::trajectory::{self as tj, Method};
use skyplan_plan::{PlanRequest, Session, TrajectoryLimits, World};
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu, path_length_m};
use std::time::Instant;

/// One method's results on every route.
#[derive(Debug, Clone, Default)]
pub struct TrajRow {
    /// The method, as the table names it.
    pub name: String,
    /// Compute time per route, milliseconds (median of the repeats).
    pub compute_ms: Vec<f64>,
    /// Duration per route, seconds.
    pub duration_s: Vec<f64>,
    /// Routes whose trajectory broke a guarantee (`None`: not checked).
    pub violations: Option<usize>,
    /// Routes on which the optimiser fell back to stopping at each waypoint.
    pub fallbacks: usize,
    /// Notes (a peer missing, a route it failed).
    pub notes: Vec<String>,
}

/// Far routes: `base` (its planner, altitude, margin) between seeded random points at least
/// `min_m` apart.
pub fn far_routes(
    session: &mut Session,
    base: &PlanRequest,
    n: usize,
    (seed, min_m): (u64, f64),
) -> Vec<Vec<Neu>> {
    let b = session.world().bounds_ne(1.0);
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut out = Vec::new();
    for _ in 0..n * 200 {
        if out.len() == n {
            break;
        }
        let mut point = || {
            [
                b.north_min_m + 1.0 + next() * (b.north_max_m - b.north_min_m - 2.0),
                b.east_min_m + 1.0 + next() * (b.east_max_m - b.east_min_m - 2.0),
            ]
        };
        let (s, g) = (point(), point());
        if (s[0] - g[0]).hypot(s[1] - g[1]) < min_m {
            continue;
        }
        let request = PlanRequest {
            start_ne: Some(s),
            goal_ne: Some(g),
            ..base.clone()
        };
        if let Ok(plan) = session.plan(&request) {
            out.push(plan.points_nea());
        }
    }
    out
}

/// Whether a trajectory keeps every guarantee: [`tj::verify`] against the world, and an
/// independent dense check (samples ≤ 1 cm apart at the proven speed bound) of free space
/// through the world's index and of speed and acceleration at the samples.
fn violates(t: &tj::Trajectory, world: &BoxWorld3) -> bool {
    if tj::verify(t, world).is_err() {
        return true;
    }
    let total = t.duration_s();
    let n = (total * t.bounds.speed_m_s.max(1e-3) / 0.01).ceil() as usize;
    let l = t.limits;
    let norm = |v: Neu| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (0..=n).any(|i| {
        let s = t.state_at(total * i as f64 / n as f64);
        !world.is_free(s.point_neu)
            || norm(s.vel_neu_m_s) > l.max_speed_m_s * (1.0 + 1e-9)
            || norm(s.accel_neu_m_s2) > l.max_accel_m_s2 * (1.0 + 1e-9)
    })
}

/// skyplan's optimised trajectory and its stop-at-each-waypoint profile on every route, each
/// timed over `repeats` runs (median).
pub fn skyplan_rows(
    routes: &[Vec<Neu>],
    world: &BoxWorld3,
    limits: &TrajectoryLimits,
    repeats: usize,
) -> Result<[TrajRow; 2], tj::TrajectoryError> {
    let mut opt = TrajRow {
        name: "skyplan minimum jerk (corridor)".into(),
        violations: Some(0),
        ..TrajRow::default()
    };
    let mut stop = TrajRow {
        name: "skyplan stop at each waypoint".into(),
        violations: Some(0),
        ..TrajRow::default()
    };
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    for route in routes {
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..repeats.max(1) {
            let t0 = Instant::now();
            let t = tj::plan(route, world, limits, &tj::Options::default())?;
            times.push(t0.elapsed().as_secs_f64() * 1e3);
            last = Some(t);
        }
        let Some(t) = last else { continue };
        opt.compute_ms.push(median(times));
        opt.duration_s.push(t.duration_s());
        opt.fallbacks += usize::from(t.method == Method::StopAtWaypoints);
        if violates(&t, world) {
            opt.violations = opt.violations.map(|v| v + 1);
        }
        let t0 = Instant::now();
        let s = tj::stop_at_waypoints(route, limits)?;
        stop.compute_ms.push(t0.elapsed().as_secs_f64() * 1e3);
        stop.duration_s.push(s.duration_s());
        let mut s = s;
        match tj::verify(&s, world) {
            Ok(b) => s.bounds = b,
            Err(_) => stop.violations = stop.violations.map(|v| v + 1),
        }
        if violates(&s, world) {
            stop.violations = stop.violations.map(|v| v + 1);
        }
    }
    Ok([opt, stop])
}

/// One peer's runs: its name, (duration s, compute ms) per route, its notes.
type PeerRuns = (String, Vec<Option<(f64, f64)>>, Vec<String>);

/// The peers' rows from the script's output lines, in route order (a route a peer failed is
/// left out of its row and named in its notes).
pub fn peer_rows(stdout: &str, routes: usize) -> Vec<TrajRow> {
    let mut rows: Vec<TrajRow> = Vec::new();
    let label = |peer: &str| {
        match peer {
        "toppra" => "TOPP-RA (spline through the waypoints; per-axis limits ÷ √axes; no jerk limit; not checked against obstacles)".to_string(),
        "ruckig" => "ruckig (stop at each waypoint; per-axis limits ÷ √axes; jerk-limited)".to_string(),
        other => other.to_string(),
    }
    };
    let mut per: Vec<PeerRuns> = Vec::new();
    for line in stdout.lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        let peer = v["peer"].as_str().unwrap_or("?").to_string();
        let i = match per.iter().position(|p| p.0 == peer) {
            Some(i) => i,
            None => {
                per.push((peer.clone(), vec![None; routes], Vec::new()));
                per.len() - 1
            }
        };
        if let Some(note) = v["note"].as_str() {
            per[i].2.push(note.to_string());
        } else if let (Some(k), Some(d), Some(c)) = (
            v["route"].as_u64(),
            v["duration_s"].as_f64(),
            v["compute_s"].as_f64(),
        ) && (k as usize) < routes
        {
            per[i].1[k as usize] = Some((d, c * 1e3));
        }
    }
    for (peer, runs, notes) in per {
        let mut row = TrajRow {
            name: label(&peer),
            notes,
            ..TrajRow::default()
        };
        for r in runs.into_iter().flatten() {
            row.duration_s.push(r.0);
            row.compute_ms.push(r.1);
        }
        rows.push(row);
    }
    rows
}

/// The routes' lengths over the speed limit and their stop-at-each-waypoint durations.
pub fn baselines(routes: &[Vec<Neu>], limits: &TrajectoryLimits) -> Vec<(f64, f64)> {
    routes
        .iter()
        .map(|r| {
            let stop = tj::stop_at_waypoints(r, limits)
                .map(|t| t.duration_s())
                .unwrap_or(f64::NAN);
            (path_length_m(r) / limits.max_speed_m_s, stop)
        })
        .collect()
}

/// The bundled city's box world as plans on it use it (margin 5 m, ground to 120 m).
pub fn city_boxes(world: &World, safety_m: f64) -> Option<BoxWorld3> {
    let map = world.colliders()?;
    let b = world.bounds_ne(1.0);
    let spec = skyplan_world3::WorldSpec {
        safety_m,
        min_alt_m: 0.0,
        max_alt_m: 120.0,
        margin_bounds_m: 0.0,
    };
    let bounds = skyplan_world3::Aabb {
        min: [b.north_min_m, b.east_min_m, 0.0],
        max: [b.north_max_m, b.east_max_m, 120.0],
    };
    BoxWorld3::with_bounds(&map.boxes, &spec, bounds).ok()
}
