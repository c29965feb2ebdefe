//! The numbers of `skyplan bench --replan`: seeded scenarios (far-apart ends on the map, hidden
//! buildings on the first route, the full-knowledge optimum), the result of each flight, and one
//! row per replanner. The flights themselves need a vehicle and a link, so the caller flies them.

use crate::hidden::{HiddenSpec, place_hidden, true_world};
use crate::replanner::{ReplanStats, Replanner, ReplannerKind, percentile};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_flight::executor::Target;
use skyplan_flight::sensing::{ObstacleReading, RouteDecision, RouteWatcher};
use skyplan_map::colliders::ObstacleBox;
use skyplan_plan::{PlanRequest, PlannerId, Session, World};
use skyplan_search::MoveModel;
use std::sync::{Arc, Mutex};

/// A [`Replanner`] shared between the flight loop (which owns the watcher) and the caller (who
/// reads the statistics and the learned cells afterwards).
#[derive(Clone)]
pub struct SharedReplanner(pub Arc<Mutex<Replanner>>);

impl RouteWatcher for SharedReplanner {
    fn on_reading(&mut self, reading: &ObstacleReading, route: &[Target]) -> RouteDecision {
        match self.0.lock() {
            Ok(mut r) => r.on_reading(reading, route),
            // A panic elsewhere poisoned the lock: keep flying what is planned.
            Err(_) => RouteDecision::Keep,
        }
    }
}

/// How the scenarios are drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioSpec {
    /// Flights.
    pub flights: usize,
    /// Seed of the first flight (flight `k` uses `seed + k`).
    pub seed: u64,
    /// Hidden buildings per flight.
    pub hidden: usize,
    /// Flight altitude, metres.
    pub alt_m: f64,
    /// Safety margin, metres.
    pub safety_m: f64,
    /// Shortest straight distance between the ends, metres.
    pub min_distance_m: f64,
}

/// One seeded flight: where from, where to, what the map does not show, the best it could do.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// The seed it was drawn with.
    pub seed: u64,
    /// The plan request (JPS at the altitude and margin, these ends).
    pub request: PlanRequest,
    /// The hidden buildings, on or near the first route.
    pub hidden: Vec<ObstacleBox>,
    /// Length of the shortest route in the true world (map and hidden buildings), metres.
    pub optimum_m: f64,
}

/// Draws `spec.flights` scenarios on `world` (a colliders map): ends in free cells at least
/// `min_distance_m` apart with a route between them, hidden buildings across that route (never
/// sealing the goal), and the full-knowledge optimum.
pub fn scenarios(world: &World, spec: &ScenarioSpec) -> Result<Vec<Scenario>, String> {
    let map = world
        .colliders()
        .ok_or("bench --replan needs a colliders map (its boxes fly in the simulator)")?;
    let mut session = Session::new(world.clone());
    let grid = session
        .grid(spec.alt_m, spec.safety_m, 1.0)
        .map_err(|e| e.to_string())?;
    let b = world.bounds_ne(1.0);
    let mut out = Vec::with_capacity(spec.flights);
    for k in 0..spec.flights {
        let seed = spec.seed.wrapping_add(k as u64);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut found = None;
        for _ in 0..2000 {
            let mut free = || {
                let n = rng
                    .random_range(b.north_min_m + 1.0..b.north_max_m - 1.0)
                    .floor()
                    + 0.5;
                let e = rng
                    .random_range(b.east_min_m + 1.0..b.east_max_m - 1.0)
                    .floor()
                    + 0.5;
                grid.cell_at_ne(n, e)
                    .filter(|&c| !grid.is_blocked(c))
                    .map(|_| [n, e])
            };
            let (Some(s), Some(g)) = (free(), free()) else {
                continue;
            };
            if (s[0] - g[0]).hypot(s[1] - g[1]) < spec.min_distance_m {
                continue;
            }
            let request = PlanRequest {
                planner: Some(PlannerId::Jps),
                start_ne: Some(s),
                goal_ne: Some(g),
                alt_m: Some(spec.alt_m),
                safety_m: Some(spec.safety_m),
                ..PlanRequest::default()
            };
            let Ok(plan) = session.plan(&request) else {
                continue;
            };
            let hidden_spec = HiddenSpec {
                count: spec.hidden,
                seed,
                route_ne: plan.waypoints.iter().map(|w| [w[0], w[1]]).collect(),
                start_ne: s,
                goal_ne: g,
                alt_m: spec.alt_m,
                safety_m: spec.safety_m,
                cell_m: 1.0,
                model: MoveModel::Octile,
            };
            let Ok(hidden) = place_hidden(map, &hidden_spec) else {
                continue;
            };
            let truth = true_world(world, &hidden).map_err(|e| e.to_string())?;
            let Ok(best) = Session::new(truth).plan(&request) else {
                continue;
            };
            found = Some(Scenario {
                seed,
                request,
                hidden,
                optimum_m: best.mission_length_m,
            });
            break;
        }
        out.push(found.ok_or_else(|| {
            format!("seed {seed}: no ends {} m apart with a route between them and room for {} hidden buildings", spec.min_distance_m, spec.hidden)
        })?);
    }
    Ok(out)
}

/// How one flight went.
#[derive(Debug, Clone, PartialEq)]
pub struct FlightResult {
    /// Landed and disarmed at the goal.
    pub success: bool,
    /// Simulator track samples inside a true obstacle (0 for a clean flight).
    pub collisions: usize,
    /// What the replanner did: replans, their latencies, CPU times and expansions.
    pub stats: ReplanStats,
    /// Horizontal distance flown, metres.
    pub flown_m: f64,
    /// The scenario's full-knowledge optimum, metres.
    pub optimum_m: f64,
}

/// One replanner over every flight: the `bench --replan` row.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplanRow {
    /// `dstar-lite` or `scratch`.
    pub replanner: ReplannerKind,
    /// Flights flown.
    pub flights: usize,
    /// Flights that landed at the goal, percent.
    pub success_pct: f64,
    /// Flights with any collision.
    pub collisions: usize,
    /// Every flight's replans together: counts, latency, CPU time, expansions.
    pub replans: ReplanStats,
    /// Median over successful flights of flown length ÷ full-knowledge optimum.
    pub flown_over_optimum_median: Option<f64>,
}

/// Sums up `results` of one replanner.
///
/// ```
/// use skyplan_replan::{ReplanSample, ReplanStats, ReplannerKind};
/// use skyplan_replan::bench::{FlightResult, summarise};
/// let sample = ReplanSample { latency_ms: 1.0, cpu_ms: Some(0.5), expansions: 10 };
/// let r = |replans: u64, flown_m: f64| FlightResult {
///     success: true, collisions: 0,
///     stats: ReplanStats { replans, samples: vec![sample; replans as usize], ..Default::default() },
///     flown_m, optimum_m: 100.0,
/// };
/// let row = summarise(ReplannerKind::DStarLite, &[r(1, 110.0), r(3, 120.0), r(0, 100.0)]);
/// assert_eq!((row.flights, row.success_pct, row.replans_per_flight()), (3, 100.0, 4.0 / 3.0));
/// assert_eq!(row.flown_over_optimum_median, Some(1.1));
/// assert_eq!(row.replans.expansions_per_replan(), Some(10.0));
/// assert_eq!((row.replans.latency().unwrap().p99_ms, row.replans.cpu().unwrap().p99_ms), (1.0, 0.5));
/// ```
pub fn summarise(replanner: ReplannerKind, results: &[FlightResult]) -> ReplanRow {
    let n = results.len();
    let ratios: Vec<f64> = results
        .iter()
        .filter(|r| r.success && r.optimum_m > 0.0)
        .map(|r| r.flown_m / r.optimum_m)
        .collect();
    ReplanRow {
        replanner,
        flights: n,
        success_pct: 100.0 * results.iter().filter(|r| r.success).count() as f64 / n.max(1) as f64,
        collisions: results.iter().filter(|r| r.collisions > 0).count(),
        replans: ReplanStats::merged(results.iter().map(|r| &r.stats)),
        flown_over_optimum_median: percentile(&ratios, 50.0),
    }
}

impl ReplanRow {
    /// Replans per flight, mean.
    pub fn replans_per_flight(&self) -> f64 {
        self.replans.replans as f64 / self.flights.max(1) as f64
    }
}

/// The rows as a table (a header, then one line per replanner; `-` where there is nothing).
pub fn format_rows(rows: &[ReplanRow]) -> String {
    let opt =
        |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |x| format!("{x:.digits$}"));
    let mut s = format!(
        "{:<11} {:>7} {:>9} {:>10} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>11} {:>14}\n",
        "replanner",
        "flights",
        "success",
        "collisions",
        "replans",
        "p50 ms",
        "p99 ms",
        "max ms",
        "cpu p50",
        "cpu p99",
        "cpu max",
        "expansions",
        "flown/optimum"
    );
    for r in rows {
        let (latency, cpu) = (r.replans.latency(), r.replans.cpu());
        s.push_str(&format!(
            "{:<11} {:>7} {:>8.0}% {:>10} {:>8.2} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>11} {:>14}\n",
            r.replanner.name(),
            r.flights,
            r.success_pct,
            r.collisions,
            r.replans_per_flight(),
            opt(latency.map(|s| s.p50_ms), 2),
            opt(latency.map(|s| s.p99_ms), 2),
            opt(latency.map(|s| s.max_ms), 2),
            opt(cpu.map(|s| s.p50_ms), 2),
            opt(cpu.map(|s| s.p99_ms), 2),
            opt(cpu.map(|s| s.max_ms), 2),
            opt(r.replans.expansions_per_replan(), 0),
            opt(r.flown_over_optimum_median, 3),
        ));
    }
    s
}
