//! Flies the city's default route with hidden buildings (seeded), once per replanner, in a fake
//! flight loop (5 m/s, a 72-sector 30 m reading every 0.1 s) and prints replans, replan latency
//! p50/p99/max, expansions per replan and the flown length ÷ the full-knowledge optimum.
//!
//! `cargo run --release -p skyplan-replan --example city_replan [SEEDS] [HIDDEN]`

#[path = "../tests/common/mod.rs"]
mod common;

use skyplan_flight::executor::Target;
use skyplan_flight::sensing::{ObstacleReading, RouteDecision, RouteWatcher};
use skyplan_map::colliders::{CollidersMap, ObstacleBox, parse_colliders};
use skyplan_plan::{FCND_CITY_CSV, FCND_DEFAULT_GOAL_NE, PlanRequest, Session, World};
use skyplan_replan::hidden::{place_hidden, true_world};
use skyplan_replan::{ReplanOptions, Replanner, ReplannerKind};
use skyplan_search::MoveModel;
use std::time::Instant;

/// Times every call (readings that keep the route included).
struct Timed<'a> {
    inner: &'a mut Replanner,
    calls_ms: Vec<f64>,
    /// A* from scratch on the same grid after each replan (cells expanded), for comparison.
    astar_expansions: Vec<f64>,
}

impl RouteWatcher for Timed<'_> {
    fn on_reading(&mut self, reading: &ObstacleReading, route: &[Target]) -> RouteDecision {
        let t = Instant::now();
        let d = self.inner.on_reading(reading, route);
        self.calls_ms.push(t.elapsed().as_secs_f64() * 1e3);
        if let RouteDecision::Replace { event, .. } = &d {
            let grid = self.inner.world().grid();
            let [n, e, _] = event.position_ned;
            let from = grid.cell_at_ne(n, e).filter(|&c| !grid.is_blocked(c));
            let goal = grid.cell_at_ne(FCND_DEFAULT_GOAL_NE[0], FCND_DEFAULT_GOAL_NE[1]);
            if let (Some(a), Some(b)) = (from, goal)
                && let Ok(p) = skyplan_search::GridSearch::new().search(
                    grid,
                    a,
                    b,
                    MoveModel::Octile,
                    skyplan_search::Planner::AStar,
                )
            {
                self.astar_expansions.push(p.expansions as f64);
            }
        }
        d
    }
}

/// What the flights of one replanner measured.
#[derive(Default)]
struct Tally {
    /// Replan latencies, ms.
    latencies: Vec<f64>,
    /// Expansions per replan.
    expansions: Vec<f64>,
    /// Flown length ÷ the full-knowledge optimum, per flight.
    ratios: Vec<f64>,
    /// Flights that reached the goal without a collision.
    reached: usize,
    replans: usize,
    /// The slowest replan: latency (ms), expansions and reason.
    slowest: Option<(f64, u64, String)>,
    /// Every reading's call time, ms.
    calls: Vec<f64>,
    /// Replan CPU times, ms.
    cpu: Vec<f64>,
    /// A* from scratch at the same replans, cells expanded.
    astar: Vec<f64>,
}

/// The `p`-th percentile (nearest rank; NaN for no value).
fn pct(v: &[f64], p: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    v[(((p / 100.0) * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seeds: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(10);
    let count: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(5);
    let map = parse_colliders(FCND_CITY_CSV)?;
    let request = PlanRequest::default();
    println!(
        "replanner   flights  reached  replans/flight  p50_ms  p99_ms  max_ms  expansions/replan  flown/optimum(median)"
    );
    let configs = [
        ("dstar-lite", ReplannerKind::DStarLite, Some(2_000)),
        ("dstar-10k", ReplannerKind::DStarLite, Some(10_000)),
        ("dstar-pure", ReplannerKind::DStarLite, None),
        ("scratch", ReplannerKind::Scratch, None),
    ];
    for (label, kind, budget) in configs {
        let mut tally = Tally::default();
        for seed in 0..seeds {
            let options = ReplanOptions {
                replanner: kind,
                dstar_budget_expansions: budget,
                ..Default::default()
            };
            fly_one(&map, &request, options, (count, seed), &mut tally)?;
        }
        tally.print(label, seeds);
    }
    Ok(())
}

/// One flight among `count` hidden buildings placed with `seed`, measured into `tally`.
fn fly_one(
    map: &CollidersMap,
    request: &PlanRequest,
    options: ReplanOptions,
    (count, seed): (usize, u64),
    tally: &mut Tally,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut r = Replanner::new(Session::new(World::fcnd_city()), request, options)?;
    let spec = common::city_hidden_spec(common::route_ne(&r.initial_plan().waypoints), count, seed);
    let hidden = place_hidden(map, &spec)?;
    let truth: Vec<ObstacleBox> = map.boxes.iter().chain(&hidden).copied().collect();
    let targets = r.initial_targets();
    let mut timed = Timed {
        inner: &mut r,
        calls_ms: Vec::new(),
        astar_expansions: Vec::new(),
    };
    let flight = common::fly(
        &mut timed,
        targets,
        &truth,
        [0.0, 0.0, 5.0],
        5.0,
        0.1,
        1800.0,
    );
    tally.calls.extend(timed.calls_ms);
    tally.astar.extend(timed.astar_expansions);
    let collided = common::first_collision(&flight.track, &truth, 2.5).is_some();
    if flight.reached_goal && !collided {
        tally.reached += 1;
    }
    tally.replans += flight.replans.len();
    for e in &flight.replans {
        if tally.slowest.as_ref().is_none_or(|s| e.latency_ms > s.0) {
            tally.slowest = Some((e.latency_ms, e.expansions, e.reason.clone()));
        }
    }
    let replans = &flight.replans;
    tally.latencies.extend(replans.iter().map(|e| e.latency_ms));
    tally.cpu.extend(replans.iter().filter_map(|e| e.cpu_ms));
    tally
        .expansions
        .extend(replans.iter().map(|e| e.expansions as f64));
    let flown = common::track_length_m(&flight.track);
    let truth_world = true_world(&World::fcnd_city(), &hidden)?;
    let optimum = Session::new(truth_world).plan(&PlanRequest {
        planner: Some(skyplan_plan::PlannerId::Jps),
        ..request.clone()
    })?;
    tally.ratios.push(flown / optimum.mission_length_m);
    Ok(())
}

impl Tally {
    /// The replanner's row of the table and its detail lines.
    fn print(&self, label: &str, seeds: u64) {
        let Tally {
            latencies,
            expansions,
            ratios,
            calls,
            cpu,
            astar,
            ..
        } = self;
        println!(
            "{:<11} {:>7}  {:>7}  {:>14.1}  {:>6.2}  {:>6.2}  {:>6.2}  {:>17.0}  {:>8.3}",
            label,
            seeds,
            self.reached,
            self.replans as f64 / seeds as f64,
            pct(latencies, 50.0),
            pct(latencies, 99.0),
            pct(latencies, 100.0),
            mean(expansions),
            pct(ratios, 50.0)
        );
        println!(
            "  every reading (learn + check, replans included): p50 {:.3} ms, p99 {:.3} ms over {} readings",
            pct(calls, 50.0),
            pct(calls, 99.0),
            calls.len()
        );
        println!(
            "  expansions per replan: mean {:.0}, p50 {:.0}, p99 {:.0}; A* from scratch at the same replans: mean {:.0}, p50 {:.0}, p99 {:.0}",
            mean(expansions),
            pct(expansions, 50.0),
            pct(expansions, 99.0),
            mean(astar),
            pct(astar, 50.0),
            pct(astar, 99.0)
        );
        println!(
            "  replan CPU time: p50 {:.3} ms, p99 {:.3} ms, max {:.3} ms",
            pct(cpu, 50.0),
            pct(cpu, 99.0),
            pct(cpu, 100.0)
        );
        if let Some((ms, n, why)) = &self.slowest {
            println!("  slowest replan: {ms:.2} ms, {n} expansions ({why})");
        }
    }
}
