//! `skyplan bench`'s grid runs without the terminal: the grid from a map's text, the queries,
//! the contenders, timed runs with their peak memory, the records as bytes, JPS+ tables as
//! bytes. The caller reads and writes the files and prints.

use crate::{Contender, Record, Run, random_far_queries, run_prepared};
use serde_json::json;
use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_plan::CellSearch;
use skyplan_search::{JpsPlusTable, MoveModel};
use std::sync::Arc;
use std::time::Instant;

/// A map's grid and how the tables name it.
pub struct Source {
    /// The map's name (its file, or the bundled map), with the slice for colliders maps.
    pub name: String,
    /// The grid searched (shared with a JPS+ table built or loaded for it: no second copy).
    pub grid: Arc<Grid2>,
}

/// The grid of a map's text: a MovingAI `.map` as it is (`movingai`), else an FCND colliders
/// map sliced at `spec`. Errors name the map.
pub fn load_grid(name: &str, text: &str, movingai: bool, spec: GridSpec) -> Result<Source, String> {
    let fail = |e: &dyn std::fmt::Display| format!("{name}: {e}");
    if movingai {
        let map = skyplan_map::movingai::parse_map(text).map_err(|e| fail(&e))?;
        let grid = crate::replay::file_order_grid(&map).map_err(|e| fail(&e))?;
        return Ok(Source {
            name: name.to_string(),
            grid: Arc::new(grid),
        });
    }
    let map = skyplan_map::colliders::parse_colliders(text).map_err(|e| fail(&e))?;
    let grid = Grid2::from_colliders(&map, spec).map_err(|e| fail(&e))?;
    Ok(Source {
        name: format!("{name} at {} m, {} m margin", spec.alt_m, spec.safety_m),
        grid: Arc::new(grid),
    })
}

/// Where the queries come from.
pub enum QuerySource<'a> {
    /// A MovingAI `.scen` file's name and text, at most `limit` of its scenarios.
    Scen(&'a str, &'a str, Option<usize>),
    /// `count` random far-apart queries, `min_distance_m` apart [default: half the diagonal].
    Random {
        /// How many.
        count: usize,
        /// Their seed.
        seed: u64,
        /// Least start-goal distance, metres.
        min_distance_m: Option<f64>,
    },
}

/// The queries and how they were drawn, in words.
pub fn queries(
    grid: &Grid2,
    model: MoveModel,
    from: QuerySource,
) -> Result<(Vec<(Cell, Cell)>, String), String> {
    let (count, seed, min_distance_m) = match from {
        QuerySource::Scen(name, text, limit) => {
            let list =
                skyplan_map::movingai::parse_scen(text).map_err(|e| format!("{name}: {e}"))?;
            let mut out = Vec::new();
            for s in list.iter().take(limit.unwrap_or(usize::MAX)) {
                let (a, b) = (
                    Cell::new(s.start_y as u32, s.start_x as u32),
                    Cell::new(s.goal_y as u32, s.goal_x as u32),
                );
                if !grid.contains(a) || !grid.contains(b) {
                    return Err(format!(
                        "{name}: line {}: a scenario endpoint is off the map",
                        s.line
                    ));
                }
                out.push((a, b));
            }
            return Ok((out, format!("scenarios of {name}")));
        }
        QuerySource::Random {
            count,
            seed,
            min_distance_m,
        } => (count, seed, min_distance_m),
    };
    let diagonal = f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let min_cells = min_distance_m.map_or(0.5 * diagonal, |m| m / grid.frame().cell_m);
    let q = random_far_queries(grid, model, count, seed, min_cells);
    if q.len() < count {
        return Err(
            "the map has fewer than two connected free cells to draw queries from".to_string(),
        );
    }
    Ok((
        q,
        format!("{count} random queries (seed {seed}) ≥ {min_cells:.0} cells apart"),
    ))
}

/// The planners of `--planners` (a comma-separated list), or [`crate::default_contenders`]: ch
/// first on MovingAI maps (`movingai`), jps-plus, jps, astar, and the Rust peer with `peers`.
pub fn contenders(
    list: Option<&str>,
    movingai: bool,
    peers: bool,
) -> Result<Vec<Contender>, String> {
    let Some(list) = list else {
        return Ok(crate::default_contenders(movingai, peers));
    };
    list.split(',')
        .map(|n| {
            Contender::from_name(n.trim()).ok_or_else(|| {
                format!(
                    "--planners: unknown planner {n:?}; expected some of ch, jps-plus, jps, astar, dijkstra, theta, rust-pathfinding-astar"
                )
            })
        })
        .collect()
}

/// [`run_prepared`] with the process's peak resident set measured around it (Linux), from
/// before the planner is prepared: `prepare` gives an engine (e.g. JPS+ from a table file), or
/// `None` to build the contender's own.
pub fn run_measured<'g, E>(
    grid: &'g Grid2,
    model: MoveModel,
    contender: Contender,
    prepare: impl FnOnce() -> Result<Option<CellSearch<'g>>, E>,
    queries: &[(Cell, Cell)],
    progress: impl FnMut(usize),
) -> Result<Run, E> {
    let measured = reset_peak_rss();
    let engine = match (prepare()?, contender) {
        (Some(e), _) => Some(e),
        (None, Contender::Skyplan(p)) => CellSearch::new(grid, p, model).ok(),
        (None, Contender::PathfindingCrateAStar) => None,
    };
    let mut r = run_prepared(grid, model, contender, engine, queries, progress);
    r.peak_rss_bytes = measured.then(peak_rss_bytes).flatten();
    Ok(r)
}

/// Resets the process's peak resident set (Linux: `5` to /proc/self/clear_refs), so that VmHWM
/// then measures one planner; false where that is not possible.
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// VmHWM of /proc/self/status (the peak resident set since the last reset), bytes.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// Every record (planner, query, time, expansions, cost) as JSON (`json`) or CSV bytes.
pub fn records_bytes(
    json: bool,
    map: &str,
    described: &str,
    runs: &[Run],
) -> Result<Vec<u8>, String> {
    let records: Vec<&Record> = runs.iter().flat_map(|r| &r.records).collect();
    if json {
        return serde_json::to_vec_pretty(
            &json!({ "map": map, "queries": described, "records": records }),
        )
        .map_err(|e| e.to_string());
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in &records {
        w.serialize(r).map_err(|e| e.to_string())?;
    }
    w.into_inner().map_err(|e| e.to_string())
}

/// The JPS+ table of `grid` (sharing it) and its build time, microseconds. The caller streams
/// it to a file with [`JpsPlusTable::write_to`] (`spec`: alt, margin, cell size the grid was
/// built with, `NaN` for a MovingAI map).
pub fn build_jps_plus_table(grid: &Arc<Grid2>, model: MoveModel) -> (JpsPlusTable, u64) {
    let t = Instant::now();
    let table = JpsPlusTable::build(Arc::clone(grid), model);
    (table, micros_since(t))
}

/// Microseconds since `t`.
fn micros_since(t: Instant) -> u64 {
    u64::try_from(t.elapsed().as_micros()).unwrap_or(u64::MAX)
}

/// JPS+ prepared from a table file streamed from `input` straight into the table's memory
/// (read since `started`: the load time is its preparation time); refused if built for another
/// grid or move model.
pub fn jps_plus_from_table<'g>(
    input: impl std::io::Read,
    grid: &'g Arc<Grid2>,
    model: MoveModel,
    started: Instant,
) -> Result<CellSearch<'g>, String> {
    let table = JpsPlusTable::read_from(input, Arc::clone(grid))
        .map_err(|e| format!("{e}; rebuild it with --save-preprocess"))?;
    let rule = |m: MoveModel| {
        if m == MoveModel::OctileCornerCutting {
            "with corner cutting (--corner-cutting)"
        } else {
            "without corner cutting"
        }
    };
    if table.model() != model {
        return Err(format!(
            "the JPS+ table was built {}; this run is {}",
            rule(table.model()),
            rule(model)
        ));
    }
    jps_plus_engine(grid, table, micros_since(started))
}

/// JPS+ over a table already built or loaded (`us`: what preparing it took).
pub fn jps_plus_engine(
    grid: &Grid2,
    table: JpsPlusTable,
    us: u64,
) -> Result<CellSearch<'_>, String> {
    CellSearch::with_jps_plus_table(grid, Arc::new(table), us).map_err(|e| e.to_string())
}
