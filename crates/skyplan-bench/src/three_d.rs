//! `skyplan bench --3d`'s core: reproducible 3D queries, per-planner records, the table.

use serde::Serialize;
use skyplan_world3::{CollisionChecker, Neu, distance_m};

/// One 3D query's outcome.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rec3 {
    /// Time to the first path (the budget when none), microseconds.
    pub time_us: f64,
    /// Length of the returned path, metres (`None`: not solved).
    pub length_m: Option<f64>,
    /// The path passed the exact continuous re-check against every box.
    pub recheck_ok: bool,
}

/// Random free points at least half the footprint's diagonal apart, altitudes 5–60 m (xorshift,
/// seeded), after the FCND route (home → 420, 390 at 5 m) when it is free.
///
/// ```
/// use skyplan_world3::{BoxWorld3, WorldSpec};
/// let map = skyplan_map::colliders::parse_colliders(skyplan_plan::FCND_CITY_CSV)?;
/// let world = BoxWorld3::new(&map.boxes, &WorldSpec::default())?;
/// let qs = skyplan_bench::three_d::random_queries(&world, 3, 1);
/// assert_eq!(qs.len(), 4);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn random_queries(world: &impl CollisionChecker, count: usize, seed: u64) -> Vec<(Neu, Neu)> {
    let b = world.bounds();
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut draw = || loop {
        let p = [
            b.min[0] + next() * (b.max[0] - b.min[0]),
            b.min[1] + next() * (b.max[1] - b.min[1]),
            5.0 + next() * 55.0,
        ];
        if world.is_free(p) {
            return p;
        }
    };
    let min_d = 0.5 * (b.max[0] - b.min[0]).hypot(b.max[1] - b.min[1]);
    let mut out = vec![([0.0, 0.0, 5.0], [420.0, 390.0, 5.0])];
    out.retain(|(s, g)| world.is_free(*s) && world.is_free(*g));
    let mut tries = 0;
    while out.len() < count + 1 && tries < 1_000_000 {
        tries += 1;
        let (s, g) = (draw(), draw());
        if distance_m(s, g) >= min_d {
            out.push((s, g));
        }
    }
    out
}

/// One row of the 3D table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row3 {
    /// Planner name.
    pub planner: String,
    /// Queries run.
    pub queries: usize,
    /// Queries solved.
    pub solved: usize,
    /// Solved paths that passed the exact re-check.
    pub recheck_ok: usize,
    /// Median time to the first path, ms.
    pub median_first_ms: f64,
    /// 95th percentile, ms.
    pub p95_first_ms: f64,
    /// Median of length ÷ straight line over the solved queries.
    pub median_length_over_straight: Option<f64>,
    /// Median ÷ the fastest median.
    pub median_over_fastest: f64,
}

/// The rows of the 3D table for runs over the same queries.
pub fn table(runs: &[(String, Vec<Rec3>)], queries: &[(Neu, Neu)]) -> Vec<Row3> {
    let straight: Vec<f64> = queries.iter().map(|(s, g)| distance_m(*s, *g)).collect();
    let times = |r: &[Rec3]| r.iter().map(|x| x.time_us).collect::<Vec<_>>();
    let fastest = runs
        .iter()
        .filter_map(|(_, r)| crate::Stats::of(&times(r)))
        .map(|s| s.median)
        .fold(f64::INFINITY, f64::min);
    runs.iter()
        .filter_map(|(planner, recs)| {
            let t = crate::Stats::of(&times(recs))?;
            let ratios: Vec<f64> = recs
                .iter()
                .zip(&straight)
                .filter_map(|(r, d)| r.length_m.map(|l| l / d))
                .collect();
            Some(Row3 {
                planner: planner.clone(),
                queries: recs.len(),
                solved: ratios.len(),
                recheck_ok: recs.iter().filter(|r| r.recheck_ok).count(),
                median_first_ms: t.median / 1e3,
                p95_first_ms: t.p95 / 1e3,
                median_length_over_straight: crate::Stats::of(&ratios).map(|s| s.median),
                median_over_fastest: t.median / fastest,
            })
        })
        .collect()
}

/// The 3D table as aligned text.
pub fn format_table(rows: &[Row3]) -> String {
    let mut s = format!(
        "{:<22} {:>7} {:>7} {:>13} {:>13} {:>14} {:>14}\n",
        "planner",
        "solved",
        "exact ✓",
        "median 1st ms",
        "p95 1st ms",
        "length/line",
        "×fastest 1st"
    );
    for r in rows {
        s.push_str(&format!(
            "{:<22} {:>7} {:>7} {:>13.3} {:>13.3} {:>14} {:>14.1}\n",
            r.planner,
            format!("{}/{}", r.solved, r.queries),
            format!("{}/{}", r.recheck_ok, r.solved),
            r.median_first_ms,
            r.p95_first_ms,
            r.median_length_over_straight
                .map_or("-".to_string(), |x| format!("{x:.3}")),
            r.median_over_fastest
        ));
    }
    s
}

/// The OMPL peers' output (one JSON object per line) as runs and notes.
pub fn parse_peer_lines(text: &str) -> (Vec<(String, Vec<Rec3>)>, Vec<String>) {
    crate::peer_lines(text, |v| {
        let solved = v["solved"].as_bool().unwrap_or(false);
        Rec3 {
            time_us: v["time_s"].as_f64().unwrap_or(f64::NAN) * 1e6,
            length_m: if solved { v["length_m"].as_f64() } else { None },
            recheck_ok: v["recheck_ok"].as_bool().unwrap_or(false),
        }
    })
}

/// Every 3D planner of the registry (`dims == 3`, in registry order) through the planning API
/// on `qs` (seeds `seed + k`), each within `budget_s` (the API re-checks every path exactly: a
/// route that failed it would be an internal failure, never a solved row).
pub fn skyplan_runs(
    session: &mut skyplan_plan::Session,
    qs: &[(Neu, Neu)],
    safety_m: f64,
    seed: u64,
    budget_s: f64,
) -> Vec<(String, Vec<Rec3>)> {
    use skyplan_plan::{PlanRequest, PlannerId};
    let mut runs = Vec::new();
    for &planner in PlannerId::ALL.iter().filter(|p| p.info().dims == 3) {
        let mut recs = Vec::new();
        for (k, &(start, goal)) in qs.iter().enumerate() {
            let request = PlanRequest {
                planner: Some(planner),
                start_ne: Some([start[0], start[1]]),
                goal_ne: Some([goal[0], goal[1]]),
                start_alt_m: Some(start[2]),
                goal_alt_m: Some(goal[2]),
                safety_m: Some(safety_m),
                seed: Some(seed + k as u64),
                time_limit_ms: Some((budget_s * 1e3) as u64),
                ..Default::default()
            };
            let plan = session.plan(&request).ok();
            let first_us = plan
                .as_ref()
                .and_then(|p| p.details.get("first_solution_us"))
                .and_then(|v| v.as_f64());
            recs.push(Rec3 {
                time_us: first_us.unwrap_or(budget_s * 1e6),
                length_m: plan.as_ref().map(|p| p.mission_length_m),
                recheck_ok: plan.is_some(),
            });
        }
        runs.push((format!("skyplan {planner}"), recs));
    }
    runs
}
