//! `--planner auto`: the fastest exact grid planner (JPS, JPS+, CH, the subgoal graph or the
//! first-move table) for a
//! grid and a number of queries, chosen from measured map statistics ([`MapStats`]) by [`pick`]
//! (and [`pick_for`], which knows the move model); the rule follows `skyplan scen` and `skyplan
//! bench` on the bundled MovingAI maps and generated mazes (docs/BENCHMARKS.md, ARCHITECTURE
//! "How auto decides").

use crate::planner_id::PlannerId;
use serde::Serialize;
use skyplan_cspace::Grid2;
use skyplan_search::MoveModel;

/// Queries on one grid from which a JPS+ table pays for itself: building it costs ≈ 40 ns per
/// cell and it saves ≈ 0.3–0.5 ns per cell on every query against JPS (`skyplan scen`, release:
/// den312d 0.2 ms build / 2 µs saved, Paris 2.5 ms / 31 µs, Boston 12 ms / 70 µs, the 32-cell
/// maze 9 ms / 60 µs), so it pays after ≈ 100–170 queries whatever the map's size.
pub const JPS_PLUS_QUERIES: u64 = 150;

/// The mean free run (cells) at or below which obstacles are scattered or corridors narrow
/// (random512-40-5: 2.7) rather than open ground, rooms and wide corridors (den312d 9.1, Paris
/// 19.6, Boston 39.7, the 32-cell maze 48.2): there, and only there, the contraction
/// hierarchy's queries beat JPS+'s (random512-40-5: 27–32 µs against 2.3–2.5 ms) and it builds
/// in half a second (elsewhere 48 ms on den312d to 35–42 s on the 512 × 512 maps, and its
/// queries are 2–20× slower than JPS+'s).
pub const CH_MAX_RUN: f64 = 5.0;

/// Queries on one grid from which a contraction hierarchy pays for itself on such a map: on
/// random512-40-5 it builds in 0.47–0.51 s and saves ≈ 2.3 ms per query against JPS+, so it
/// pays after ≈ 220 queries.
pub const CH_QUERIES: u64 = 250;

/// The mean free run (cells) above [`CH_MAX_RUN`] and at most this where, on large maps, the
/// subgoal graph answers fastest: corridors a few cells wide keep few convex corners (the
/// generated 4-cell maze, mean run 7.7: 7,234 subgoals among 209,242 free cells; the 8-cell
/// one, 15.9: 2,231) and each sees only the corners near it, so the graph builds in ≈ 50–60
/// ms and a query reads a few hundred hub label entries and walks the path (25 µs against
/// JPS+'s 330 µs on the 4-cell maze, 17 against 100 µs on the 8-cell one; 8-cell rooms, 9.2:
/// 14 against 230 µs after a 0.7 s build). On open ground (den312d 9.1 is small; Paris 19.6,
/// Boston 39.7, the 32-cell maze 48.2) and on rooms 16 cells wide (18.3: 2.6 s to build) the
/// corners see far and the graph is dense: it pays only over tens of thousands of queries,
/// or saved ([`pick_with_subgoal_graph`]).
pub const SUBGOAL_MAX_RUN: f64 = 16.0;

/// The mean free run (cells) up to which a subgoal graph at hand (loaded from a file, or kept
/// from earlier queries) answers faster than JPS+, when it has hub labels and every cell's
/// roots kept (`SubgoalGraph::label_entries`, `kept_roots`): rooms 16 cells wide (mean run
/// 18.3: 19 µs a query against JPS+'s 49 µs, but 2.5 s to build), the 8-cell maze (15.9: 22
/// against 99 µs). Not maze512-32-9 (48.2: 18 against 12 µs) nor Boston_0_512 (39.7); on
/// Paris_1_256 (19.6) the corners see too far for kept roots (its queries flood: 1.6 ms).
pub const SUBGOAL_KEPT_MAX_RUN: f64 = 24.0;

/// Free cells from which the subgoal graph is worth building on such a map: on small maps
/// (den312d, 2,445 free cells) every query is short and JPS+ answers it in a few µs, less than
/// a subgoal query's floods at both ends.
pub const SUBGOAL_MIN_FREE: u64 = 65_536;

/// The largest first-move table `auto` (and `--planner first-move`) builds: 64 MiB, half a byte
/// per cell for every free cell (den312d's is 6.4 MB; a 128 × 128 map with 8,000 free cells
/// reaches 66 MB; the city at 5 m would take 192 MB and is refused). A server keeps one per
/// grid in each of its sessions, so the cap is per table, kept small.
pub const FIRST_MOVE_MAX_BYTES: u64 = 64 << 20;

/// Queries per (free cell)² from which a first-move table pays for itself: building it costs
/// ≈ 8–16 ns per pair of free cells on this project's 2-core machine (den312d: 2,445 free
/// cells, 50–100 ms) and it saves ≈ 1 µs per query against JPS+ there (≈ 0.5 µs against
/// ≈ 1.5 µs), so it pays after ≈ free² / 100 queries (60,000 on den312d). A table at hand
/// (loaded from a file, or built for earlier queries) is used whatever the count.
pub const FIRST_MOVE_PAIRS_PER_QUERY: u64 = 100;

/// Whether `queries` queries pay for a first-move table of a map with `stats`
/// ([`FIRST_MOVE_MAX_BYTES`], [`FIRST_MOVE_PAIRS_PER_QUERY`]).
///
/// ```
/// use skyplan_plan::auto::{MapStats, first_move_pays};
/// let den312d = MapStats { cells: 5_265, free: 2_445, mean_run: 9.1 };
/// assert!(!first_move_pays(&den312d, 290));
/// assert!(first_move_pays(&den312d, 100_000));
/// let boston = MapStats { cells: 262_144, free: 196_725, mean_run: 39.7 };
/// assert!(!first_move_pays(&boston, u64::MAX)); // 26 GB
/// ```
pub fn first_move_pays(stats: &MapStats, queries: u64) -> bool {
    let bytes =
        skyplan_search::FirstMoveTable::bytes_for(stats.cells as usize, stats.free as usize);
    bytes <= FIRST_MOVE_MAX_BYTES
        && queries >= stats.free.saturating_mul(stats.free) / FIRST_MOVE_PAIRS_PER_QUERY
}

/// Whether a map is one where the subgoal graph answers fastest ([`SUBGOAL_MAX_RUN`],
/// [`SUBGOAL_MIN_FREE`]).
pub fn subgoal_map(stats: &MapStats) -> bool {
    stats.mean_run > CH_MAX_RUN
        && stats.mean_run <= SUBGOAL_MAX_RUN
        && stats.free >= SUBGOAL_MIN_FREE
}

/// What `auto` measures of a grid before it picks.
///
/// ```
/// use skyplan_plan::auto::MapStats;
/// let grid = skyplan_cspace::Grid2::from_ascii("....\n.##.\n....")?;
/// let s = MapStats::of(&grid);
/// assert_eq!((s.cells, s.free), (12, 10));
/// // Rows: 10 free cells in 4 runs (4 | 1, 1 | 4); columns: in 6 runs (3 | 1, 1 | 1, 1 | 3).
/// assert_eq!(s.mean_run, 10.0 / 6.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MapStats {
    /// Cells of the grid.
    pub cells: u64,
    /// Free cells.
    pub free: u64,
    /// The mean length of a maximal run of free cells, along rows or along columns (the
    /// shorter of the two means): corridor width between obstacles.
    pub mean_run: f64,
}

impl MapStats {
    /// Counts the free cells and the free runs along rows and columns (one pass each).
    pub fn of(grid: &Grid2) -> Self {
        let (rows, cols) = (grid.rows() as usize, grid.cols() as usize);
        let blocked = grid.blocked_cells();
        let free = blocked.iter().filter(|&&b| !b).count() as u64;
        let mut row_runs = 0u64;
        for row in blocked.chunks(cols.max(1)) {
            let mut prev = true;
            for &b in row {
                row_runs += u64::from(prev && !b);
                prev = b;
            }
        }
        let mut col_runs = 0u64;
        let mut prev = vec![true; cols];
        for row in blocked.chunks(cols.max(1)).take(rows) {
            for (p, &b) in prev.iter_mut().zip(row) {
                col_runs += u64::from(*p && !b);
                *p = b;
            }
        }
        let mean = |runs: u64| {
            if runs == 0 {
                0.0
            } else {
                free as f64 / runs as f64
            }
        };
        Self {
            cells: blocked.len() as u64,
            free,
            mean_run: mean(row_runs).min(mean(col_runs)),
        }
    }
}

/// What `auto` picked, for the report: the planner, the statistics and query count it went by,
/// and why, in words.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AutoPick {
    /// The planner that answers (jps, jps-plus, ch or subgoal).
    pub planner: PlannerId,
    /// The grid's statistics.
    pub stats: MapStats,
    /// The queries on this grid it planned for (a batch's size, or a session's count so far).
    pub queries: u64,
    /// Why, in one line.
    pub why: String,
}

/// The pick for `queries` queries on a grid with `stats`:
///
/// - fewer than [`JPS_PLUS_QUERIES`]: **JPS** — no preprocessing would pay for itself;
/// - a small map and enough queries to pay for its table ([`first_move_pays`]): the
///   **first-move table**;
/// - a mean free run ≤ [`CH_MAX_RUN`] (corridors, scattered obstacles) and at least
///   [`CH_QUERIES`] queries: **CH**;
/// - a large map of corridors a few cells wide ([`subgoal_map`]): the **subgoal graph**;
/// - otherwise **JPS+**.
///
/// The subgoal graph is for the 8-connected model without corner cutting: [`pick_for`] gives
/// JPS+ instead under the others.
///
/// ```
/// use skyplan_plan::{PlannerId, auto::{MapStats, pick}};
/// let scattered = MapStats { cells: 262_144, free: 104_350, mean_run: 2.7 };
/// assert_eq!(pick(&scattered, 1).planner, PlannerId::Jps);
/// assert_eq!(pick(&scattered, 200).planner, PlannerId::JpsPlus);
/// assert_eq!(pick(&scattered, 5_240).planner, PlannerId::Ch);
/// let city = MapStats { free: 196_725, mean_run: 39.7, ..scattered };
/// assert_eq!(pick(&city, 5_240).planner, PlannerId::JpsPlus);
/// let maze = MapStats { free: 209_242, mean_run: 7.7, ..scattered };
/// assert_eq!(pick(&maze, 1_000).planner, PlannerId::Subgoal);
/// ```
pub fn pick(stats: &MapStats, queries: u64) -> AutoPick {
    let corridors = stats.mean_run <= CH_MAX_RUN;
    let shape = if corridors {
        "scattered obstacles or narrow corridors"
    } else {
        "open ground, rooms or wide corridors"
    };
    let (planner, why) = if queries < JPS_PLUS_QUERIES {
        (
            PlannerId::Jps,
            format!(
                "{queries} {} < {JPS_PLUS_QUERIES}: no preprocessing pays for itself",
                plural(queries)
            ),
        )
    } else if first_move_pays(stats, queries) {
        (
            PlannerId::FirstMove,
            format!(
                "a small map ({} free cells: a {} table) and {queries} queries ≥ free² / {FIRST_MOVE_PAIRS_PER_QUERY}: the first-move table pays for itself",
                stats.free,
                crate::human_bytes(skyplan_search::FirstMoveTable::bytes_for(
                    stats.cells as usize,
                    stats.free as usize
                )),
            ),
        )
    } else if corridors && queries >= CH_QUERIES {
        (
            PlannerId::Ch,
            format!(
                "{shape} (mean free run {:.1} ≤ {CH_MAX_RUN} cells) and {queries} queries ≥ {CH_QUERIES}: the contraction hierarchy pays for itself",
                stats.mean_run
            ),
        )
    } else if subgoal_map(stats) {
        (
            PlannerId::Subgoal,
            format!(
                "corridors a few cells wide (mean free run {:.1} cells, in ({CH_MAX_RUN}, {SUBGOAL_MAX_RUN}]) on a large map ({} free cells ≥ {SUBGOAL_MIN_FREE}) and {queries} queries ≥ {JPS_PLUS_QUERIES}: the subgoal graph pays for itself",
                stats.mean_run, stats.free
            ),
        )
    } else {
        let also = if corridors {
            format!(", < {CH_QUERIES} for a contraction hierarchy")
        } else {
            String::new()
        };
        (
            PlannerId::JpsPlus,
            format!(
                "{shape} (mean free run {:.1} cells) and {queries} queries ≥ {JPS_PLUS_QUERIES}{also}: the JPS+ table pays for itself",
                stats.mean_run
            ),
        )
    };
    AutoPick {
        planner,
        stats: *stats,
        queries,
        why,
    }
}

/// [`pick`] for the move model `model`: the subgoal graph is defined for the 8-connected model
/// without corner cutting, so under the other two its pick becomes JPS+ (said in `why`).
///
/// ```
/// use skyplan_plan::{PlannerId, auto::{MapStats, pick_for}};
/// use skyplan_search::MoveModel;
/// let maze = MapStats { cells: 262_144, free: 209_242, mean_run: 7.7 };
/// assert_eq!(pick_for(&maze, 1_000, MoveModel::Octile).planner, PlannerId::Subgoal);
/// let cutting = pick_for(&maze, 1_000, MoveModel::OctileCornerCutting);
/// assert_eq!(cutting.planner, PlannerId::JpsPlus);
/// assert!(cutting.why.ends_with("JPS+ instead"));
/// ```
pub fn pick_for(stats: &MapStats, queries: u64, model: MoveModel) -> AutoPick {
    let mut rule = pick(stats, queries);
    if rule.planner == PlannerId::Subgoal && model != MoveModel::Octile {
        rule.planner = PlannerId::JpsPlus;
        rule.why = format!(
            "{}, but it needs 8-connected moves without corner cutting: JPS+ instead",
            rule.why
        );
    }
    rule
}

/// The pick when a first-move table is at hand with no build to pay (loaded from a file, or
/// kept from earlier queries): the table, on any map, since its queries search nothing.
///
/// ```
/// use skyplan_plan::{PlannerId, auto::{MapStats, pick_with_first_move_table}};
/// let den312d = MapStats { cells: 5_265, free: 2_445, mean_run: 9.1 };
/// assert_eq!(pick_with_first_move_table(&den312d, 290).planner, PlannerId::FirstMove);
/// ```
pub fn pick_with_first_move_table(stats: &MapStats, queries: u64) -> AutoPick {
    AutoPick {
        planner: PlannerId::FirstMove,
        stats: *stats,
        queries,
        why: "a first-move table at hand (built or loaded): one lookup per cell of the path, no search".to_string(),
    }
}

/// The pick when a contraction hierarchy is at hand with no build to pay (loaded from a file):
/// CH on maps whose mean free run is ≤ [`CH_MAX_RUN`], where its queries are the fastest;
/// `None` elsewhere, where [`pick`]'s JPS or JPS+ answer faster.
///
/// ```
/// use skyplan_plan::{PlannerId, auto::{MapStats, pick_with_hierarchy}};
/// let scattered = MapStats { cells: 262_144, free: 104_350, mean_run: 2.7 };
/// assert_eq!(pick_with_hierarchy(&scattered, 1).map(|p| p.planner), Some(PlannerId::Ch));
/// assert_eq!(pick_with_hierarchy(&MapStats { mean_run: 39.7, ..scattered }, 1), None);
/// ```
pub fn pick_with_hierarchy(stats: &MapStats, queries: u64) -> Option<AutoPick> {
    (stats.mean_run <= CH_MAX_RUN).then(|| AutoPick {
        planner: PlannerId::Ch,
        stats: *stats,
        queries,
        why: format!(
            "scattered obstacles or narrow corridors (mean free run {:.1} ≤ {CH_MAX_RUN} cells) and a contraction hierarchy at hand: the fastest queries, nothing to build",
            stats.mean_run
        ),
    })
}

/// The pick when a subgoal graph is at hand with no build to pay (loaded from a file, or kept
/// from earlier queries): the graph where [`pick`] builds one ([`subgoal_map`]), and, when it
/// reads hub labels from kept roots (`labelled`), on every large map (≥ [`SUBGOAL_MIN_FREE`]
/// free cells) whose mean free run is ≤ [`SUBGOAL_KEPT_MAX_RUN`]; `None` elsewhere (on small
/// maps JPS+ answers in a few µs too).
///
/// ```
/// use skyplan_plan::{PlannerId, auto::{MapStats, pick_with_subgoal_graph}};
/// let rooms = MapStats { cells: 262_144, free: 216_935, mean_run: 18.3 };
/// let pick = pick_with_subgoal_graph(&rooms, 1_000, true).unwrap();
/// assert_eq!(pick.planner, PlannerId::Subgoal);
/// assert_eq!(pick_with_subgoal_graph(&rooms, 1_000, false), None);
/// let boston = MapStats { free: 196_725, mean_run: 39.7, ..rooms };
/// assert_eq!(pick_with_subgoal_graph(&boston, 1_000, true), None);
/// let den312d = MapStats { cells: 5_265, free: 2_445, mean_run: 9.1 };
/// assert_eq!(pick_with_subgoal_graph(&den312d, 1_000, true), None);
/// ```
pub fn pick_with_subgoal_graph(stats: &MapStats, queries: u64, labelled: bool) -> Option<AutoPick> {
    let fits = subgoal_map(stats)
        || (labelled && stats.mean_run <= SUBGOAL_KEPT_MAX_RUN && stats.free >= SUBGOAL_MIN_FREE);
    fits.then(|| AutoPick {
        planner: PlannerId::Subgoal,
        stats: *stats,
        queries,
        why: format!(
            "a subgoal graph at hand (built or loaded){} and a mean free run of {:.1} cells: nothing to build, the fastest queries",
            if labelled { " with hub labels" } else { "" },
            stats.mean_run
        ),
    })
}

/// The pick when a JPS+ table is at hand with no build to pay (loaded from a file): JPS+ with
/// it where [`pick_for`] would answer with JPS or JPS+ (its queries are never slower than
/// JPS's, and with landmarks kept in the table, faster still); `None` where the rule picks a
/// hierarchy, a subgoal graph or a first-move table.
///
/// ```
/// use skyplan_plan::{PlannerId, auto::{MapStats, pick_with_jps_plus_table}};
/// use skyplan_search::MoveModel;
/// let paris = MapStats { cells: 65_536, free: 47_240, mean_run: 19.6 };
/// let pick = pick_with_jps_plus_table(&paris, 1, MoveModel::Octile, true).unwrap();
/// assert_eq!(pick.planner, PlannerId::JpsPlus);
/// assert!(pick.why.contains("landmarks"));
/// let scattered = MapStats { cells: 262_144, free: 104_350, mean_run: 2.7 };
/// assert_eq!(pick_with_jps_plus_table(&scattered, 5_240, MoveModel::Octile, false), None);
/// ```
pub fn pick_with_jps_plus_table(
    stats: &MapStats,
    queries: u64,
    model: MoveModel,
    landmarks: bool,
) -> Option<AutoPick> {
    let rule = pick_for(stats, queries, model);
    matches!(rule.planner, PlannerId::Jps | PlannerId::JpsPlus).then(|| AutoPick {
        planner: PlannerId::JpsPlus,
        stats: *stats,
        queries,
        why: format!(
            "a JPS+ table at hand{} (built or loaded): nothing to build, and {} otherwise",
            if landmarks { " with landmarks" } else { "" },
            rule.planner
        ),
    })
}

fn plural(n: u64) -> &'static str {
    if n == 1 { "query" } else { "queries" }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: usize, cols: usize, blocked: impl Fn(usize, usize) -> bool) -> Grid2 {
        let text: Vec<String> = (0..rows)
            .map(|r| {
                (0..cols)
                    .map(|c| if blocked(r, c) { '#' } else { '.' })
                    .collect()
            })
            .collect();
        Grid2::from_ascii(&text.join("\n")).unwrap()
    }

    /// A switchback maze of 2-cell corridors: a wall every third row, its 2-cell gap at
    /// alternate ends.
    fn maze() -> Grid2 {
        grid(128, 128, |r, c| {
            let gap = if (r / 3) % 2 == 0 { c < 2 } else { c >= 126 };
            r % 3 == 2 && !gap
        })
    }

    /// Open ground with a few large blocks.
    fn open() -> Grid2 {
        grid(128, 128, |r, c| (r % 64) < 8 && (c % 64) < 8)
    }

    #[test]
    fn a_maze_is_corridors_and_open_ground_is_not() {
        let m = MapStats::of(&maze());
        let o = MapStats::of(&open());
        assert!(m.mean_run <= CH_MAX_RUN, "maze: {m:?}");
        assert!(o.mean_run > CH_MAX_RUN, "open: {o:?}");
        assert_eq!(o.cells, 128 * 128);
        assert_eq!(o.free, 128 * 128 - 4 * 64);
    }

    #[test]
    fn the_pick_follows_the_rule_on_a_maze_and_on_open_ground() {
        let m = MapStats::of(&maze());
        let o = MapStats::of(&open());
        assert_eq!(pick(&m, 1).planner, PlannerId::Jps);
        assert_eq!(pick(&o, 1).planner, PlannerId::Jps);
        assert_eq!(pick(&m, JPS_PLUS_QUERIES).planner, PlannerId::JpsPlus);
        assert_eq!(pick(&o, JPS_PLUS_QUERIES).planner, PlannerId::JpsPlus);
        assert_eq!(pick(&m, CH_QUERIES).planner, PlannerId::Ch);
        assert_eq!(pick(&o, CH_QUERIES).planner, PlannerId::JpsPlus);
        assert!(pick(&m, CH_QUERIES).why.contains("contraction hierarchy"));
        assert!(pick(&o, 1).why.starts_with("1 query < 150"));
    }

    /// The generated MovingAI-shaped mazes (`skyplan map maze`, 512 × 512, seed 1) and what
    /// `auto` picks for 1,000 queries there: measured fastest including preprocessing
    /// (docs/BENCHMARKS.md, "Generated mazes"): CH on 1- and 2-cell corridors, the subgoal graph
    /// on 4 and 8 (where CH's 4–12 s build pays only after ≈ 13,000 queries or never).
    #[test]
    fn on_generated_mazes_auto_picks_what_was_measured_fastest_for_1000_queries() {
        use skyplan_map::maze::{MazeSpec, generate};
        for (corridor_cells, expected) in [
            (1, PlannerId::Ch),
            (2, PlannerId::Ch),
            (4, PlannerId::Subgoal),
            (8, PlannerId::Subgoal),
        ] {
            let spec = MazeSpec {
                width: 512,
                height: 512,
                corridor_cells,
                seed: 1,
            };
            let map = generate(&spec).unwrap();
            let blocked: Vec<bool> = map.passable.iter().map(|&p| !p).collect();
            let grid = Grid2::new(512, 512, blocked, Default::default()).unwrap();
            let stats = MapStats::of(&grid);
            assert_eq!(
                pick(&stats, 1_000).planner,
                expected,
                "{corridor_cells}: {stats:?}"
            );
        }
    }
}
