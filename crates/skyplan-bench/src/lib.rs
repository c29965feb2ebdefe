//! Benchmark core for skyplan (no I/O): reproducible query sets, timed runs of every planner on
//! the same queries, statistics, and the Rust peer (the `pathfinding` crate's A\*).
//!
//! ```
//! use skyplan_bench::{random_far_queries, run, Contender};
//! use skyplan_plan::PlannerId;
//! use skyplan_cspace::Grid2;
//! use skyplan_search::MoveModel;
//! let grid = Grid2::from_ascii(&"..........\n".repeat(10))?;
//! let queries = random_far_queries(&grid, MoveModel::Octile, 5, 42, 6.0);
//! assert_eq!(queries.len(), 5);
//! let jps = run(&grid, MoveModel::Octile, Contender::Skyplan(PlannerId::JpsPlus), &queries, |_| {})?;
//! let astar = run(&grid, MoveModel::Octile, Contender::Skyplan(PlannerId::Astar), &queries, |_| {})?;
//! for (a, b) in jps.records.iter().zip(&astar.records) {
//!     assert_eq!(a.cost, b.cost);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bench3d;
pub mod cpp_peers;
pub mod grid_bench;
mod peer_pathfinding;
pub mod python_peers;
pub mod replay;
pub mod replay_report;
pub mod three_d;
pub mod trajectory_bench;

use rand::{RngExt, SeedableRng};
use serde::Serialize;
use skyplan_cspace::{Cell, Grid2};
use skyplan_plan::{CellSearch, PlannerId};
use skyplan_search::{Components, MoveModel};
use std::time::Instant;

/// What the benchmark can run: a skyplan grid planner (through the planning API), or a peer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Contender {
    /// A skyplan grid-search planner (JPS+ builds its table once per grid; reported apart).
    Skyplan(PlannerId),
    /// The Rust `pathfinding` crate's A\* with exact octile costs (a peer).
    PathfindingCrateAStar,
}

impl Contender {
    /// Short name for tables and `--planners`: the planner's CLI spelling, or the peer's name.
    pub fn name(self) -> &'static str {
        match self {
            Contender::Skyplan(p) => p.name(),
            Contender::PathfindingCrateAStar => "rust-pathfinding-astar",
        }
    }

    /// Parses a [`Contender::name`]: a grid-search planner or the peer.
    pub fn from_name(name: &str) -> Option<Self> {
        if name == "rust-pathfinding-astar" {
            return Some(Contender::PathfindingCrateAStar);
        }
        let p: PlannerId = name.parse().ok()?;
        p.is_cell_search().then_some(Contender::Skyplan(p))
    }

    /// True for skyplan's own planners (false for peers).
    pub fn is_skyplan(self) -> bool {
        matches!(self, Contender::Skyplan(_))
    }
}

/// The planners `skyplan bench` runs when none are named: `auto` (its row named with its pick
/// for the query count, `auto (jps-plus)`), JPS+, JPS and A\*, the contraction hierarchy
/// (`ch`) on MovingAI maps (where per-map preprocessing is the norm; on large open maps such as
/// the city at 1 m its preprocessing takes minutes, so it is opt-in there), and the Rust
/// `pathfinding` crate's A\* with `peers`.
///
/// ```
/// use skyplan_bench::{default_contenders, Contender};
/// use skyplan_plan::PlannerId;
/// assert_eq!(default_contenders(true, false)[0], Contender::Skyplan(PlannerId::Auto));
/// assert_eq!(default_contenders(true, false)[1], Contender::Skyplan(PlannerId::Ch));
/// assert!(!default_contenders(false, false).contains(&Contender::Skyplan(PlannerId::Ch)));
/// assert!(default_contenders(false, true).contains(&Contender::PathfindingCrateAStar));
/// ```
pub fn default_contenders(movingai_map: bool, peers: bool) -> Vec<Contender> {
    let mut v = vec![Contender::Skyplan(PlannerId::Auto)];
    if movingai_map {
        v.push(Contender::Skyplan(PlannerId::Ch));
    }
    v.extend([
        Contender::Skyplan(PlannerId::JpsPlus),
        Contender::Skyplan(PlannerId::Jps),
        Contender::Skyplan(PlannerId::Astar),
    ]);
    if peers {
        v.push(Contender::PathfindingCrateAStar);
    }
    v
}

/// One timed query.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Record {
    /// Planner name.
    pub planner: String,
    /// Query number.
    pub query: usize,
    /// Search time, microseconds (the search alone).
    pub time_us: f64,
    /// Expanded nodes (`None` when the planner does not report it).
    pub expansions: Option<u64>,
    /// Path cost in cells (`None`: no path found).
    pub cost: Option<f64>,
}

/// All queries of one planner.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Run {
    /// Planner name.
    pub planner: String,
    /// One record per query, in query order.
    pub records: Vec<Record>,
    /// One-off preparation time (JPS+ table: built, or loaded from a file), microseconds.
    pub precompute_us: f64,
    /// Peak resident memory of the process while this planner ran, bytes (measured by the
    /// caller, e.g. VmHWM after resetting it; `None` if not measured).
    pub peak_rss_bytes: Option<u64>,
}

/// `count` reproducible queries between free cells of the largest connected region, at least
/// `min_distance_cells` apart (relaxed by 10 % after every 10 000 failed draws).
pub fn random_far_queries(
    grid: &Grid2,
    model: MoveModel,
    count: usize,
    seed: u64,
    min_distance_cells: f64,
) -> Vec<(Cell, Cell)> {
    let components = Components::new(grid, model);
    let largest =
        (0..components.count() as u32).max_by_key(|&l| (components.size(l), std::cmp::Reverse(l)));
    let Some(largest) = largest else {
        return Vec::new();
    };
    let cells: Vec<Cell> = (0..grid.len())
        .map(|i| grid.cell(i))
        .filter(|&c| components.label(c) == Some(largest))
        .collect();
    if cells.len() < 2 {
        return Vec::new();
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut min_d = min_distance_cells;
    let mut queries = Vec::with_capacity(count);
    let mut failures = 0u32;
    while queries.len() < count {
        let a = cells[rng.random_range(0..cells.len())];
        let b = cells[rng.random_range(0..cells.len())];
        let d = (f64::from(a.row) - f64::from(b.row)).hypot(f64::from(a.col) - f64::from(b.col));
        if d >= min_d && a != b {
            queries.push((a, b));
        } else {
            failures += 1;
            if failures.is_multiple_of(10_000) {
                min_d *= 0.9;
            }
        }
    }
    queries
}

/// Runs one planner on every query (after one untimed warm-up query), calling `progress(k)`
/// after query `k`; refused when a skyplan planner cannot be prepared on the grid (e.g. a
/// first-move table too large for it).
pub fn run(
    grid: &Grid2,
    model: MoveModel,
    contender: Contender,
    queries: &[(Cell, Cell)],
    progress: impl FnMut(usize),
) -> Result<Run, skyplan_plan::PlanFailure> {
    let engine = match contender {
        Contender::Skyplan(p) => Some(CellSearch::for_queries(
            grid,
            p,
            model,
            queries.len() as u64,
        )?),
        Contender::PathfindingCrateAStar => None,
    };
    Ok(run_prepared(
        grid, model, contender, engine, queries, progress,
    ))
}

/// [`run`] with the skyplan planner already prepared (e.g. JPS+ with a table loaded from a
/// file: [`CellSearch::with_jps_plus_table`]); `engine` is `None` for the peer (and only for
/// it: a skyplan contender without an engine would be timed as the peer).
pub fn run_prepared(
    grid: &Grid2,
    model: MoveModel,
    contender: Contender,
    mut engine: Option<CellSearch<'_>>,
    queries: &[(Cell, Cell)],
    mut progress: impl FnMut(usize),
) -> Run {
    let precompute_us = engine.as_ref().map_or(0.0, |e| e.precompute_us() as f64);
    // `auto` is reported with what it picked: `auto (jps-plus)`.
    let name = match engine.as_ref().and_then(|e| e.auto_pick()) {
        Some(p) => format!("{} ({})", contender.name(), p.planner),
        None => contender.name().to_string(),
    };
    let mut query_once = |start: Cell, goal: Cell| -> (Option<f64>, Option<u64>) {
        match engine.as_mut() {
            Some(e) => match e.search(start, goal) {
                Ok(p) => (Some(p.cost_cells()), Some(p.expansions)),
                Err(_) => (None, None),
            },
            None => (peer_pathfinding::astar_cost(grid, model, start, goal), None),
        }
    };
    // One untimed warm-up query, so that no planner's first timed query pays for allocating and
    // faulting in its buffers.
    if let Some(&(start, goal)) = queries.first() {
        let _warm_up = query_once(start, goal);
    }
    let mut records = Vec::with_capacity(queries.len());
    for (query, &(start, goal)) in queries.iter().enumerate() {
        let t = Instant::now();
        let (cost, expansions) = query_once(start, goal);
        let time_us = t.elapsed().as_secs_f64() * 1e6;
        records.push(Record {
            planner: name.clone(),
            query,
            time_us,
            expansions,
            cost,
        });
        progress(query);
    }
    Run {
        planner: name,
        records,
        precompute_us,
        peak_rss_bytes: None,
    }
}

/// Order statistics of a set of times.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    /// Number of samples.
    pub n: usize,
    /// Median.
    pub median: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Maximum.
    pub max: f64,
    /// Mean.
    pub mean: f64,
}

impl Stats {
    /// Statistics of `values` (`None` when empty).
    ///
    /// ```
    /// let s = skyplan_bench::Stats::of(&[4.0, 1.0, 3.0, 2.0]).unwrap();
    /// assert_eq!((s.median, s.max, s.mean), (2.5, 4.0, 2.5));
    /// ```
    pub fn of(values: &[f64]) -> Option<Self> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            (v[n / 2 - 1] + v[n / 2]) / 2.0
        };
        let rank = ((0.95 * n as f64).ceil() as usize).clamp(1, n);
        Some(Self {
            n,
            median,
            p95: v[rank - 1],
            max: v[n - 1],
            mean: v.iter().sum::<f64>() / n as f64,
        })
    }
}

/// Ratio of a run's total cost to the best total over the queries every run solved
/// (1.0 = as short as the best; optimal planners all give exactly 1.0).
pub fn cost_ratio(run: &[Option<f64>], best: &[Option<f64>]) -> Option<f64> {
    let (mut mine, mut theirs) = (0.0, 0.0);
    for (a, b) in run.iter().zip(best) {
        if let (Some(a), Some(b)) = (a, b) {
            mine += a;
            theirs += b;
        }
    }
    (theirs > 0.0).then(|| mine / theirs)
}

/// One row of the benchmark table: a planner's times, expansions and costs over the queries.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// Planner name.
    pub planner: String,
    /// Queries answered.
    pub queries: usize,
    /// Median search time, microseconds.
    pub median_us: f64,
    /// 95th percentile, microseconds.
    pub p95_us: f64,
    /// Slowest query, microseconds.
    pub max_us: f64,
    /// Mean, microseconds.
    pub mean_us: f64,
    /// Mean expansions (planners that report them).
    pub mean_expansions: Option<f64>,
    /// Mean cost of the solved queries, metres.
    pub mean_cost_m: Option<f64>,
    /// Cost relative to the best over every planner, per query (1 = always optimal).
    pub cost_over_best: Option<f64>,
    /// Median time ÷ the fastest skyplan planner's median.
    pub median_over_fastest: f64,
    /// One-off preparation (the JPS+ table), milliseconds.
    pub precompute_ms: f64,
    /// Peak resident memory of the process while the planner ran, MiB (`None`: not measured).
    pub peak_rss_mib: Option<f64>,
}

/// The table's rows: each run against the best cost per query over every run, and against the
/// fastest skyplan planner's median.
pub fn table(runs: &[Run], query_count: usize, cell_m: f64) -> Vec<Row> {
    let best: Vec<Option<f64>> = (0..query_count)
        .map(|q| {
            runs.iter()
                .filter_map(|r| {
                    r.records
                        .get(q)
                        .filter(|rec| rec.query == q)
                        .and_then(|rec| rec.cost)
                })
                .min_by(f64::total_cmp)
        })
        .collect();
    let times = |r: &Run| r.records.iter().map(|x| x.time_us).collect::<Vec<_>>();
    let fastest = runs
        .iter()
        // `auto` is named with its pick: `auto (ch)`.
        .filter(|r| {
            let name = r.planner.split(" (").next().unwrap_or(&r.planner);
            Contender::from_name(name).is_some_and(Contender::is_skyplan)
        })
        .filter_map(|r| Stats::of(&times(r)).map(|s| s.median))
        .fold(f64::INFINITY, f64::min);
    let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    runs.iter()
        .filter_map(|r| {
            let stats = Stats::of(&times(r))?;
            let exp: Vec<f64> = r
                .records
                .iter()
                .filter_map(|x| x.expansions.map(|e| e as f64))
                .collect();
            let costs: Vec<Option<f64>> = r.records.iter().map(|x| x.cost).collect();
            let best_same: Vec<Option<f64>> = r
                .records
                .iter()
                .map(|x| best.get(x.query).copied().flatten())
                .collect();
            let solved: Vec<f64> = costs.iter().flatten().copied().collect();
            Some(Row {
                planner: r.planner.clone(),
                queries: stats.n,
                median_us: stats.median,
                p95_us: stats.p95,
                max_us: stats.max,
                mean_us: stats.mean,
                mean_expansions: mean(&exp),
                mean_cost_m: mean(&solved).map(|c| c * cell_m),
                cost_over_best: cost_ratio(&costs, &best_same),
                median_over_fastest: stats.median / fastest,
                precompute_ms: r.precompute_us / 1e3,
                peak_rss_mib: r.peak_rss_bytes.map(|b| b as f64 / (1024.0 * 1024.0)),
            })
        })
        .collect()
}

/// The table as aligned text, times in milliseconds.
pub fn format_table(rows: &[Row]) -> String {
    let mut s = format!(
        "{:<24} {:>7} {:>10} {:>10} {:>10} {:>10} {:>11} {:>10} {:>10} {:>10} {:>9}\n",
        "planner",
        "queries",
        "median ms",
        "p95 ms",
        "max ms",
        "expansions",
        "mean cost m",
        "cost/best",
        "×fastest",
        "prep ms",
        "peak MiB"
    );
    for r in rows {
        let opt =
            |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |x| format!("{x:.digits$}"));
        let prep = (r.precompute_ms > 0.0).then_some(r.precompute_ms);
        s.push_str(&format!(
            "{:<24} {:>7} {:>10.3} {:>10.3} {:>10.3} {:>10} {:>11} {:>10} {:>10.1} {:>10} {:>9}\n",
            r.planner,
            r.queries,
            r.median_us / 1e3,
            r.p95_us / 1e3,
            r.max_us / 1e3,
            opt(r.mean_expansions, 0),
            opt(r.mean_cost_m, 2),
            opt(r.cost_over_best, 6),
            r.median_over_fastest,
            opt(prep, 1),
            opt(r.peak_rss_mib, 1)
        ));
    }
    s
}

/// The Python peers' output (one JSON object per line: `peer`, `query`, `time_s`, `cost`, or
/// `unavailable`) as runs, and notes for the unavailable ones.
pub fn parse_peer_lines(text: &str) -> (Vec<Run>, Vec<String>) {
    let (runs, notes) = peer_lines(text, |v| (v["query"].as_u64().unwrap_or(0) as usize, v));
    let runs = runs
        .into_iter()
        .map(|(peer, recs)| Run {
            records: recs
                .into_iter()
                .map(|(query, v)| Record {
                    planner: peer.clone(),
                    query,
                    time_us: v["time_s"].as_f64().unwrap_or(f64::NAN) * 1e6,
                    expansions: None,
                    cost: v["cost"].as_f64(),
                })
                .collect(),
            planner: peer,
            precompute_us: 0.0,
            peak_rss_bytes: None,
        })
        .collect();
    (runs, notes)
}

/// Peers' JSON lines grouped by `peer` in order of appearance, each line made a record by
/// `record`; a line with `unavailable` becomes a note instead.
pub(crate) fn peer_lines<R>(
    text: &str,
    record: impl Fn(serde_json::Value) -> R,
) -> (Vec<(String, Vec<R>)>, Vec<String>) {
    let mut runs: Vec<(String, Vec<R>)> = Vec::new();
    let mut notes = Vec::new();
    for line in text.lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        let peer = v["peer"].as_str().unwrap_or("?").to_string();
        if let Some(why) = v["unavailable"].as_str() {
            notes.push(format!(
                "{peer} unavailable ({why}); run bench/setup-peers.sh"
            ));
            continue;
        }
        let rec = record(v);
        match runs.iter_mut().find(|(n, _)| *n == peer) {
            Some((_, r)) => r.push(rec),
            None => runs.push((peer, vec![rec])),
        }
    }
    (runs, notes)
}

#[cfg(test)]
mod table_tests {
    use super::*;

    /// `auto` reported with its pick counts as skyplan's: the fastest median may be its own.
    #[test]
    fn auto_with_its_pick_is_measured_against_the_fastest() {
        let run = |planner: &str, time_us: f64| Run {
            planner: planner.into(),
            records: (0..3)
                .map(|query| Record {
                    planner: planner.into(),
                    query,
                    time_us,
                    expansions: None,
                    cost: Some(10.0),
                })
                .collect(),
            precompute_us: 0.0,
            peak_rss_bytes: None,
        };
        let rows = table(&[run("auto (ch)", 50.0), run("jps", 200.0)], 3, 1.0);
        let ratio: Vec<f64> = rows.iter().map(|r| r.median_over_fastest).collect();
        assert_eq!(ratio, vec![1.0, 4.0]);
    }
}
