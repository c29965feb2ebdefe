//! `skyplan bench`'s grid runs without the terminal: the grid from a map's text, the queries,
//! the contenders, timed runs with their peak memory, the records as bytes, JPS+ tables as
//! bytes. The caller reads and writes the files and prints.

use crate::{Contender, Record, Run, random_far_queries, run_prepared};
use serde_json::json;
use skyplan_cspace::{Cell, Grid2, GridSpec};
use skyplan_plan::{CellSearch, PlannerId, Session, World};
use skyplan_search::{ContractionHierarchy, FirstMoveTable, JpsPlusTable, MoveModel};
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
/// map sliced at `spec` by the planning API ([`Session::grid`]). Errors name the map.
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
    // Sliced by the planning API, with its checks (altitude, margin, cell, memory).
    let mut session = Session::new(World::from_colliders_csv(name, text).map_err(|f| f.message)?);
    let grid = session
        .grid(spec.alt_m, spec.safety_m, spec.cell_m)
        .map_err(|f| f.message)?;
    Ok(Source {
        name: format!("{name} at {} m, {} m margin", spec.alt_m, spec.safety_m),
        grid,
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
                    "--planners: unknown planner {n:?}; expected some of {}",
                    contender_names()
                )
            })
        })
        .collect()
}

/// Every name `--planners` takes, comma-separated: the registry's grid-search planners, then the
/// peer (derived, so a new grid planner is named here without an edit).
///
/// ```
/// let names = skyplan_bench::grid_bench::contender_names();
/// assert!(names.contains("jps-plus, ") && names.ends_with(", rust-pathfinding-astar"));
/// ```
pub fn contender_names() -> String {
    let planners = PlannerId::ALL
        .iter()
        .filter_map(|&p| Contender::from_name(p.name()).map(Contender::name));
    let peer = std::iter::once(Contender::PathfindingCrateAStar.name());
    planners.chain(peer).collect::<Vec<_>>().join(", ")
}

/// [`run_prepared`] with the process's peak resident set measured around it (Linux), from
/// before the planner is prepared: `prepare` gives an engine (e.g. JPS+ from a table file), or
/// `None` to build the contender's own.
pub fn run_measured<'g>(
    grid: &'g Grid2,
    model: MoveModel,
    contender: Contender,
    prepare: impl FnOnce() -> Result<Option<CellSearch<'g>>, RunAllError>,
    queries: &[(Cell, Cell)],
    progress: impl FnMut(usize),
) -> Result<Run, RunAllError> {
    let measured = reset_peak_rss();
    let engine = match (prepare()?, contender) {
        (Some(e), _) => Some(e),
        (None, Contender::Skyplan(p)) => Some(
            CellSearch::for_queries(grid, p, model, queries.len() as u64).map_err(|e| {
                // "planner first-move: …" names the planner already.
                let own = format!("planner {p}: ");
                let why = e.message.strip_prefix(&own).unwrap_or(&e.message);
                RunAllError::Refused(format!("{p}: {why}"))
            })?,
        ),
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

/// VmHWM of /proc/self/status (the process's peak resident set since it started or since the
/// bench last reset it), bytes; `None` where it cannot be read (not Linux).
pub fn peak_rss_bytes() -> Option<u64> {
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
    let table = load_jps_plus_table(input, grid, model)?;
    jps_plus_engine(grid, table, micros_since(started))
}

/// Reads a JPS+ table file for `grid` and `model`; refused (saying why) if built for another
/// grid or corner rule, or damaged.
pub fn load_jps_plus_table(
    input: impl std::io::Read,
    grid: &Arc<Grid2>,
    model: MoveModel,
) -> Result<JpsPlusTable, String> {
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
    Ok(table)
}

/// JPS+ over a table already built or loaded (`us`: what preparing it took).
pub fn jps_plus_engine(
    grid: &Grid2,
    table: JpsPlusTable,
    us: u64,
) -> Result<CellSearch<'_>, String> {
    CellSearch::with_jps_plus_table(grid, Arc::new(table), us, None).map_err(|e| e.to_string())
}

/// What [`run_all`]'s planners start from: JPS+'s table, and a loaded first-move table,
/// contraction hierarchy or subgoal graph.
pub struct Preprocessing<R> {
    /// Where JPS+ gets its table.
    pub jps_plus: JpsPlusPrep<R>,
    /// A first-move table (loaded from a file) and its load time, µs: `first-move` and `auto`
    /// use it.
    pub first_move: Option<(Arc<FirstMoveTable>, u64)>,
    /// A contraction hierarchy (loaded from a file) and its load time, µs: `ch` uses it, and
    /// `auto` where its rule is the hierarchy's ([`skyplan_plan::auto::pick_with_hierarchy`]).
    pub hierarchy: Option<(Arc<ContractionHierarchy>, u64)>,
    /// A subgoal graph (loaded from a file) and its load time, µs: `subgoal` uses it, and
    /// `auto` where a graph at hand is the fastest
    /// ([`skyplan_plan::auto::pick_with_subgoal_graph`]).
    pub subgoal: Option<(Arc<skyplan_search::SubgoalGraph>, u64)>,
}

impl<R> From<JpsPlusPrep<R>> for Preprocessing<R> {
    /// JPS+'s table, no first-move table or hierarchy.
    fn from(jps_plus: JpsPlusPrep<R>) -> Self {
        Self {
            jps_plus,
            first_move: None,
            hierarchy: None,
            subgoal: None,
        }
    }
}

/// Where [`run_all`]'s JPS+ gets its table.
pub enum JpsPlusPrep<R> {
    /// JPS+ builds its own table (timed as its preparation).
    Build,
    /// A table the caller built (and saved) with [`build_jps_plus_table`], and its build time,
    /// µs: reused when JPS+ runs first, otherwise dropped before the runs so that it does not
    /// count in another planner's peak memory.
    Built(JpsPlusTable, u64),
    /// A table file (written by [`JpsPlusTable::write_to`]) to stream in, timed as the
    /// preparation.
    File(R),
    /// A table loaded before (e.g. from a file with landmarks) and what loading took, µs:
    /// `jps-plus` uses it, and so does `auto` where its rule picks JPS or JPS+
    /// ([`skyplan_plan::auto::pick_with_jps_plus_table`]); each reports the load as its
    /// preparation.
    Loaded(Arc<JpsPlusTable>, u64),
}

/// Why [`run_all`] stopped before running every contender.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RunAllError {
    /// The table file of [`JpsPlusPrep::File`] was refused (unreadable, another grid or move
    /// model): the input is wrong.
    Table(String),
    /// JPS+ could not use a table that was fine.
    Engine(String),
    /// A planner cannot run on this grid (e.g. a first-move table too large for it): the
    /// request is wrong.
    Refused(String),
}

impl std::fmt::Display for RunAllError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunAllError::Table(m) | RunAllError::Engine(m) | RunAllError::Refused(m) => {
                f.write_str(m)
            }
        }
    }
}

impl std::error::Error for RunAllError {}

/// Every contender on the same queries, one after the other, each measured by
/// [`run_measured`] from its preparation, as `prep` says ([`Preprocessing`]). `started` is told
/// each contender before its queries, `answered` after each query.
///
/// ```
/// use skyplan_bench::{Contender, grid_bench::{self, JpsPlusPrep}};
/// use skyplan_cspace::{Cell, Grid2};
/// use skyplan_search::MoveModel;
///
/// let grid = std::sync::Arc::new(Grid2::from_ascii("....\n....\n....").unwrap());
/// let contenders = [Contender::from_name("jps-plus").unwrap(), Contender::from_name("astar").unwrap()];
/// let queries = [(Cell::new(0, 0), Cell::new(2, 3))];
/// let none: JpsPlusPrep<&[u8]> = JpsPlusPrep::Build; // as `Preprocessing` without a first-move table
/// let runs = grid_bench::run_all(&grid, MoveModel::Octile, &contenders, &queries, none, |_| {}, || {})
///     .unwrap();
/// assert_eq!(runs.len(), 2);
/// assert_eq!(runs[0].records[0].cost, runs[1].records[0].cost);
/// ```
pub fn run_all<R: std::io::Read>(
    grid: &Arc<Grid2>,
    model: MoveModel,
    contenders: &[Contender],
    queries: &[(Cell, Cell)],
    prep: impl Into<Preprocessing<R>>,
    mut started: impl FnMut(Contender),
    mut answered: impl FnMut(),
) -> Result<Vec<Run>, RunAllError> {
    let Preprocessing {
        jps_plus,
        first_move,
        hierarchy,
        subgoal,
    } = prep.into();
    let jps_plus_id = Contender::Skyplan(skyplan_plan::PlannerId::JpsPlus);
    let mut prep = match jps_plus {
        JpsPlusPrep::Built(..) if contenders.first() != Some(&jps_plus_id) => JpsPlusPrep::Build,
        prep => prep,
    };
    let loaded = match &prep {
        JpsPlusPrep::Loaded(table, us) => Some((Arc::clone(table), *us)),
        _ => None,
    };
    let mut runs = Vec::with_capacity(contenders.len());
    for &contender in contenders {
        started(contender);
        let own = if contender == jps_plus_id {
            std::mem::replace(&mut prep, JpsPlusPrep::Build)
        } else {
            JpsPlusPrep::Build
        };
        let hierarchy_pick = || {
            let (ch, us) = hierarchy.as_ref()?;
            let auto = match contender {
                Contender::Skyplan(PlannerId::Ch) => None,
                Contender::Skyplan(PlannerId::Auto) => {
                    Some(skyplan_plan::auto::pick_with_hierarchy(
                        &skyplan_plan::auto::MapStats::of(grid),
                        queries.len() as u64,
                    )?)
                }
                _ => return None,
            };
            Some((Arc::clone(ch), *us, auto))
        };
        let with_hierarchy = hierarchy_pick();
        let subgoal_pick = || {
            let (graph, us) = subgoal.as_ref()?;
            let auto = match contender {
                Contender::Skyplan(PlannerId::Subgoal) => None,
                Contender::Skyplan(PlannerId::Auto) => {
                    Some(skyplan_plan::auto::pick_with_subgoal_graph(
                        &skyplan_plan::auto::MapStats::of(grid),
                        queries.len() as u64,
                        graph.labelled(),
                    )?)
                }
                _ => return None,
            };
            Some((Arc::clone(graph), *us, auto))
        };
        let with_subgoal = subgoal_pick();
        let prepare = || match (own, contender, &first_move) {
            _ if with_subgoal.is_some() => {
                let Some((graph, us, auto)) = with_subgoal else {
                    return Ok(None);
                };
                CellSearch::with_subgoal_graph(grid, graph, us, auto)
                    .map(Some)
                    .map_err(|e| RunAllError::Table(e.message))
            }
            _ if with_hierarchy.is_some() => {
                let Some((ch, us, auto)) = with_hierarchy else {
                    return Ok(None);
                };
                CellSearch::with_hierarchy(grid, ch, us, auto)
                    .map(Some)
                    .map_err(|e| RunAllError::Table(e.message))
            }
            (_, Contender::Skyplan(PlannerId::Auto), None) if loaded.is_some() => {
                let Some((table, us)) = loaded.clone() else {
                    return Ok(None);
                };
                let stats = skyplan_plan::auto::MapStats::of(grid);
                let landmarks = table.landmarks().is_some();
                let n = queries.len() as u64;
                match skyplan_plan::auto::pick_with_jps_plus_table(&stats, n, model, landmarks) {
                    Some(pick) => CellSearch::with_jps_plus_table(grid, table, us, Some(pick))
                        .map(Some)
                        .map_err(|e| RunAllError::Engine(e.message)),
                    None => Ok(None),
                }
            }
            (
                _,
                Contender::Skyplan(p @ (PlannerId::FirstMove | PlannerId::Auto)),
                Some((t, us)),
            ) => {
                let auto = (p == PlannerId::Auto).then(|| {
                    let stats = skyplan_plan::auto::MapStats::of(grid);
                    skyplan_plan::auto::pick_with_first_move_table(&stats, queries.len() as u64)
                });
                CellSearch::with_first_move_table(grid, Arc::clone(t), *us, auto)
                    .map(Some)
                    .map_err(|e| RunAllError::Table(e.message))
            }
            (own, ..) => match own {
                JpsPlusPrep::Build => Ok(None),
                JpsPlusPrep::Built(table, us) => jps_plus_engine(grid, table, us)
                    .map(Some)
                    .map_err(RunAllError::Engine),
                JpsPlusPrep::Loaded(table, us) => {
                    CellSearch::with_jps_plus_table(grid, table, us, None)
                        .map(Some)
                        .map_err(|e| RunAllError::Engine(e.message))
                }
                JpsPlusPrep::File(input) => {
                    jps_plus_from_table(std::io::BufReader::new(input), grid, model, Instant::now())
                        .map(Some)
                        .map_err(RunAllError::Table)
                }
            },
        };
        runs.push(run_measured(
            grid,
            model,
            contender,
            prepare,
            queries,
            |_| answered(),
        )?);
    }
    Ok(runs)
}

/// The grid benchmark's result as `skyplan bench` shows it: the map, the queries, the table
/// and notes (e.g. peers that did not run); [`Report::json`] or the text of its `Display`.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// The map's name ([`Source::name`]).
    pub map: String,
    /// Grid rows.
    pub rows: u32,
    /// Grid columns.
    pub cols: u32,
    /// Cell size, metres.
    pub cell_m: f64,
    /// How the queries were drawn, in words (from [`queries`]).
    pub queries: String,
    /// The move model.
    pub model: MoveModel,
    /// The table's rows ([`crate::table`]).
    pub table: Vec<crate::Row>,
    /// Notes printed under the table.
    pub notes: Vec<String>,
}

impl Report {
    /// The report of `runs` over `query_count` queries on `source`'s grid.
    pub fn new(
        source: &Source,
        described: &str,
        model: MoveModel,
        runs: &[Run],
        query_count: usize,
        notes: Vec<String>,
    ) -> Self {
        let grid = &source.grid;
        let cell_m = grid.frame().cell_m;
        Report {
            map: source.name.clone(),
            rows: grid.rows(),
            cols: grid.cols(),
            cell_m,
            queries: described.to_string(),
            model,
            table: crate::table(runs, query_count, cell_m),
            notes,
        }
    }

    /// One JSON object: `map`, `grid` (rows, columns), `queries`, `rows`, `notes`.
    pub fn json(&self) -> serde_json::Value {
        json!({ "map": self.map, "grid": [self.rows, self.cols], "queries": self.queries, "rows": self.table, "notes": self.notes })
    }
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "map      {}: {} × {} cells of {} m",
            self.map, self.rows, self.cols, self.cell_m
        )?;
        let model_name = skyplan_plan::model_name(self.model);
        writeln!(f, "queries  {}; move model {model_name}", self.queries)?;
        writeln!(f)?;
        write!(f, "{}", crate::format_table(&self.table))?;
        for n in &self.notes {
            writeln!(f, "note     {n}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open_grid() -> Arc<Grid2> {
        Arc::new(Grid2::from_ascii("......\n..##..\n......").unwrap())
    }

    const QUERIES: [(Cell, Cell); 2] = [
        (Cell { row: 0, col: 0 }, Cell { row: 2, col: 5 }),
        (Cell { row: 2, col: 0 }, Cell { row: 0, col: 5 }),
    ];

    fn names(list: &str) -> Vec<Contender> {
        contenders(Some(list), false, false).unwrap()
    }

    #[test]
    fn an_unknown_contender_is_named_with_every_name_that_is_taken() {
        let e = contenders(Some("jps,warp"), false, false)
            .err()
            .unwrap_or_default();
        let listed = e
            .strip_prefix("--planners: unknown planner \"warp\"; expected some of ")
            .unwrap_or_else(|| panic!("{e}"));
        // Every cell search of the registry, then the peer; each name parses back.
        let mut expected: Vec<&str> = (PlannerId::ALL.iter())
            .filter(|p| p.is_cell_search())
            .map(|p| p.name())
            .collect();
        expected.push("rust-pathfinding-astar");
        assert_eq!(listed.split(", ").collect::<Vec<_>>(), expected);
        for name in expected {
            assert_eq!(Contender::from_name(name).map(Contender::name), Some(name));
        }
    }

    #[test]
    fn colliders_slices_below_the_ground_or_above_the_ceiling_are_refused() {
        let spec = |alt_m| GridSpec {
            alt_m,
            safety_m: 5.0,
            cell_m: 10.0,
        };
        let city = skyplan_plan::FCND_CITY_CSV;
        for alt_m in [-5.0, 10_001.0] {
            let e = load_grid("city", city, false, spec(alt_m)).err();
            let expected = format!("city: alt_m {alt_m}: expected a number from 0 to 10000 m");
            assert_eq!(e.as_deref(), Some(expected.as_str()));
        }
        assert!(load_grid("city", city, false, spec(0.0)).is_ok());
    }

    #[test]
    fn run_all_reuses_a_built_table_only_when_jps_plus_runs_first() {
        let grid = open_grid();
        let model = MoveModel::Octile;
        let (table, _) = build_jps_plus_table(&grid, model);
        let prep: JpsPlusPrep<&[u8]> = JpsPlusPrep::Built(table, 4242);
        let (mut started, mut answered) = (Vec::new(), 0);
        let runs = run_all(
            &grid,
            model,
            &names("jps-plus,astar"),
            &QUERIES,
            prep,
            |c| started.push(c.name()),
            || answered += 1,
        )
        .unwrap();
        assert_eq!(started, ["jps-plus", "astar"]);
        assert_eq!(answered, 4);
        assert_eq!(runs[0].precompute_us, 4242.0);
        let costs = |r: &Run| r.records.iter().map(|x| x.cost).collect::<Vec<_>>();
        assert_eq!(costs(&runs[0]), costs(&runs[1]));

        let (table, _) = build_jps_plus_table(&grid, model);
        let prep: JpsPlusPrep<&[u8]> = JpsPlusPrep::Built(table, 4242);
        let runs = run_all(
            &grid,
            model,
            &names("astar,jps-plus"),
            &QUERIES,
            prep,
            |_| {},
            || {},
        )
        .unwrap();
        assert_ne!(runs[1].precompute_us, 4242.0);
    }

    #[test]
    fn run_all_loads_a_table_file_and_refuses_another_move_model() {
        let grid = open_grid();
        let (table, _) = build_jps_plus_table(&grid, MoveModel::Octile);
        let mut bytes = Vec::new();
        table.write_to(&mut bytes, [f64::NAN; 3]).unwrap();
        let list = names("jps-plus");
        let run = |model| {
            let file = JpsPlusPrep::File(&bytes[..]);
            run_all(&grid, model, &list, &QUERIES, file, |_| {}, || {})
        };
        let runs = run(MoveModel::Octile).unwrap();
        assert!(runs[0].records.iter().all(|r| r.cost.is_some()));
        let refused = run(MoveModel::OctileCornerCutting);
        assert!(matches!(refused, Err(RunAllError::Table(m)) if m.contains("corner cutting")));
    }

    #[test]
    fn report_text_and_json_name_the_map_queries_and_notes() {
        let source = Source {
            name: "test grid".into(),
            grid: open_grid(),
        };
        let list = names("astar");
        let none: JpsPlusPrep<&[u8]> = JpsPlusPrep::Build;
        let runs = run_all(
            &source.grid,
            MoveModel::Octile,
            &list,
            &QUERIES,
            none,
            |_| {},
            || {},
        )
        .unwrap();
        let notes = vec!["a peer did not run".to_string()];
        let report = Report::new(&source, "2 queries", MoveModel::Octile, &runs, 2, notes);
        let text = report.to_string();
        assert!(text.starts_with(
            "map      test grid: 3 × 6 cells of 1 m\nqueries  2 queries; move model "
        ));
        assert!(text.ends_with("note     a peer did not run\n"));
        let json = report.json();
        assert_eq!(json["grid"], json!([3, 6]));
        assert_eq!(json["rows"][0]["planner"], "astar");
        assert_eq!(json["notes"][0], "a peer did not run");
    }
}
