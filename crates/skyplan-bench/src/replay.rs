//! MovingAI scenario replay: every scenario's cost against its published `optimal_length`.

use serde::Serialize;
use skyplan_cspace::{Cell, Grid2};
use skyplan_map::movingai::{MovingAiMap, Scenario};
use skyplan_plan::auto::AutoPick;
use skyplan_plan::{CellSearch, PlanFailure, PlannerId};
use skyplan_search::MoveModel;
use std::collections::BTreeMap;
use std::time::Instant;

/// Relative tolerance for matching a published optimal length.
pub const REL_TOL: f64 = 1e-6;

/// One scenario's outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Outcome {
    /// Line of the scenario file.
    pub line: usize,
    /// The scenario's bucket.
    pub bucket: u32,
    /// The cost found (`None`: no path).
    pub cost: Option<f64>,
    /// The published optimum.
    pub optimal_length: f64,
    /// Whether they match within [`REL_TOL`].
    pub ok: bool,
    /// Search time, microseconds.
    pub time_us: f64,
    /// Cells expanded.
    pub expansions: u64,
    /// Why it does not match, in words (for failures).
    #[serde(skip)]
    pub why: Option<String>,
}

/// Per-bucket totals.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Bucket {
    /// Scenarios.
    pub count: u64,
    /// Matched.
    pub matched: u64,
    /// Total search time, microseconds.
    pub total_us: f64,
}

/// A whole replay: totals per bucket, the scenarios that did not match, the JPS+ table time.
#[derive(Debug, Clone, PartialEq)]
pub struct Replay {
    /// Totals per bucket.
    pub buckets: BTreeMap<u32, Bucket>,
    /// The scenarios that did not match.
    pub failures: Vec<Outcome>,
    /// One-off preparation (the JPS+ table, the contraction hierarchy; for `auto` also the
    /// map's statistics and the pick), ms.
    pub table_ms: f64,
    /// What `auto` picked for this map and this many scenarios, and why.
    pub auto: Option<AutoPick>,
}

/// A MovingAI map as a grid in file row order (row = y, column = x, as the scenarios count).
pub fn file_order_grid(map: &MovingAiMap) -> Result<Grid2, skyplan_cspace::GridError> {
    Grid2::from_passable(map.height as u32, map.width as u32, &map.passable)
}

/// The first scenario whose start or goal is off the map, as a message.
pub fn first_off_map(map: &MovingAiMap, scenarios: &[Scenario]) -> Option<String> {
    scenarios.iter().find_map(|s| {
        [
            ("start", s.start_x, s.start_y),
            ("goal", s.goal_x, s.goal_y),
        ]
        .into_iter()
        .find(|&(_, x, y)| x >= map.width || y >= map.height)
        .map(|(what, x, y)| {
            format!(
                "line {}: {what} ({x}, {y}) is outside the {} × {} map",
                s.line, map.width, map.height
            )
        })
    })
}

/// Replays every scenario with `planner` (JPS+ builds its table once: returned in ms; `auto`
/// picks for the number of scenarios), calling `each` after every scenario.
pub fn replay(
    grid: &Grid2,
    scenarios: &[Scenario],
    planner: PlannerId,
    each: impl FnMut(&Outcome),
) -> Result<Replay, PlanFailure> {
    let search = CellSearch::for_queries(grid, planner, MoveModel::Octile, scenarios.len() as u64)?;
    Ok(replay_prepared(grid, search, scenarios, each))
}

/// [`replay`] with the search already prepared (e.g. a contraction hierarchy loaded from a
/// file: [`CellSearch::with_hierarchy`]).
pub fn replay_prepared(
    grid: &Grid2,
    mut search: CellSearch<'_>,
    scenarios: &[Scenario],
    mut each: impl FnMut(&Outcome),
) -> Replay {
    let table_ms = search.precompute_us() as f64 / 1e3;
    let mut buckets: BTreeMap<u32, Bucket> = BTreeMap::new();
    let mut failures = Vec::new();
    for s in scenarios {
        let start = Cell::new(s.start_y as u32, s.start_x as u32);
        let goal = Cell::new(s.goal_y as u32, s.goal_x as u32);
        let t = Instant::now();
        let result = search.search(start, goal);
        let time_us = t.elapsed().as_secs_f64() * 1e6;
        let (cost, expansions) = match &result {
            Ok(p) => (Some(p.cost_cells()), p.expansions),
            Err(_) => (None, 0),
        };
        let ok = cost
            .is_some_and(|c| (c - s.optimal_length).abs() <= REL_TOL * s.optimal_length.max(1.0));
        let why = (!ok).then(|| match cost {
            Some(c) => format!(
                "line {}: found {c:.8}, optimal {}",
                s.line, s.optimal_length
            ),
            None if grid.is_blocked(start) || grid.is_blocked(goal) => {
                format!(
                    "line {}: no path: the start or goal is on a blocked cell",
                    s.line
                )
            }
            None => format!(
                "line {}: no path found, optimal {}",
                s.line, s.optimal_length
            ),
        });
        let b = buckets.entry(s.bucket).or_default();
        b.count += 1;
        b.matched += u64::from(ok);
        b.total_us += time_us;
        let outcome = Outcome {
            line: s.line,
            bucket: s.bucket,
            cost,
            optimal_length: s.optimal_length,
            ok,
            time_us,
            expansions,
            why,
        };
        each(&outcome);
        if !ok {
            failures.push(outcome);
        }
    }
    Replay {
        buckets,
        failures,
        table_ms,
        auto: search.auto_pick().cloned(),
    }
}
