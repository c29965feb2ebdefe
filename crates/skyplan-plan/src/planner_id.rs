//! The planner registry: one row per planner (name, label, capabilities, the options it uses,
//! what it keeps, the [`Algorithm`](crate::algorithm::Algorithm) that runs it, a summary).
//!
//! Adding a planner is its module plus one row in [`planners!`]: the CLI's `--planner` values
//! and help, `--json`'s `planner`, serde, `FromStr`, the HTTP API's `/api/planners`, Python's
//! `skyplan.planners()`, which options it takes (the others are refused naming the planners
//! that use them), its memory estimate and its place in every test that iterates the registry
//! all come from that row.

use crate::algorithm::{Algorithm, CellFunction, JpsPlusCells, OnlineCells};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

/// How good the returned route is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Optimality {
    /// Shortest among grid paths under the move model (checked against an exact oracle).
    Exact,
    /// Shortest for its objective (length + weight · cost), not for length alone.
    ExactForObjective,
    /// Any-angle: shorter than any grid path, not guaranteed shortest.
    AnyAngle,
    /// The Euclidean-shortest path through the free cells (any angle, exact).
    ExactAnyAngle,
    /// A free route with no optimality guarantee (roadmaps, sampling planners).
    Feasible,
    /// Improves towards the optimum with more time (RRT\*).
    AsymptoticallyOptimal,
}

/// Which maps a planner takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MapKinds {
    /// Every map: colliders (as a grid at the altitude), images, MovingAI, random, grids.
    AnyGrid,
    /// Only maps of obstacles: FCND colliders, GeoJSON or OpenStreetMap footprints (it needs
    /// the boxes or the footprint prisms, not a fixed grid).
    Obstacles,
    /// Every map, as [`MapKinds::AnyGrid`], when its grid is small enough for the planner's
    /// per-grid table (the first-move table's size grows with the square of the free cells:
    /// [`crate::auto::FIRST_MOVE_MAX_BYTES`]); a larger one is refused, saying so.
    SmallGrid,
}

/// A group of request options that only some planners use. A request that gives an option of
/// a group its planner does not use is refused, naming the planners that use it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OptionGroup {
    /// The grid path's options: `connectivity`, `corner_cutting`, `prune`, `epsilon`, `shortcut`.
    GridPath,
    /// The 3D ends and flight volume: `start_alt_m`, `goal_alt_m`, `min_alt_m`, `max_alt_m`.
    ThreeD,
    /// `time_limit_ms`: a planning or preprocessing time budget.
    TimeLimit,
    /// The voxel lattice: `climb_weight`, `voxel_m`, `layer_m`.
    Lattice,
    /// The inflated cost map: `inscribed_radius_m`, `inflation_radius_m`, `cost_scaling`, `cost_weight`.
    Inflation,
    /// The wavefront's `field`.
    Field,
}

impl OptionGroup {
    /// Every group.
    pub const ALL: &'static [OptionGroup] = &[
        OptionGroup::GridPath,
        OptionGroup::ThreeD,
        OptionGroup::TimeLimit,
        OptionGroup::Lattice,
        OptionGroup::Inflation,
        OptionGroup::Field,
    ];
}

/// What a planner can do, for help texts, `--json`, `/api/planners` and clients that choose one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PlannerInfo {
    /// The CLI spelling.
    pub name: &'static str,
    /// Human label used in summaries (`JPS+`, `Theta*`, …).
    pub label: &'static str,
    /// 2 for routes at one altitude, 3 for routes that change altitude.
    pub dims: u8,
    /// How good the route is.
    pub optimality: Optimality,
    /// Which maps it takes.
    pub maps: MapKinds,
    /// The option groups it uses (beside the common ones: ends, altitude, margin, cell size).
    pub uses: &'static [OptionGroup],
    /// What a session keeps for it between requests (empty: nothing beyond the grid).
    pub keeps: &'static str,
    /// One line for help texts.
    pub summary: &'static str,
}

macro_rules! planners {
    ($( $(#[$doc:meta])* $variant:ident => $name:literal, $label:literal, $dims:literal, $opt:ident, $maps:ident, [$($uses:ident),*], $keeps:literal, $algorithm:expr, $summary:literal; )*) => {
        /// Every planner skyplan has, by its CLI spelling (`jps-plus`, `rrt-star`, …).
        ///
        /// ```
        /// use skyplan_plan::PlannerId;
        /// let p: PlannerId = "rrt-star".parse().unwrap();
        /// assert_eq!(p, PlannerId::RrtStar);
        /// assert_eq!(p.to_string(), "rrt-star");
        /// assert_eq!(p.info().dims, 3);
        /// ```
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
        pub enum PlannerId {
            $( $(#[$doc])* $variant, )*
        }

        impl PlannerId {
            /// Every planner, in registry order.
            pub const ALL: &'static [PlannerId] = &[$(PlannerId::$variant),*];

            /// What the planner is and can do.
            pub fn info(self) -> PlannerInfo {
                match self {
                    $(PlannerId::$variant => PlannerInfo {
                        name: $name,
                        label: $label,
                        dims: $dims,
                        optimality: Optimality::$opt,
                        maps: MapKinds::$maps,
                        uses: &[$(OptionGroup::$uses),*],
                        keeps: $keeps,
                        summary: $summary,
                    },)*
                }
            }

            /// The algorithm that answers its requests.
            pub(crate) fn algorithm(self) -> &'static dyn Algorithm {
                match self {
                    $(PlannerId::$variant => $algorithm,)*
                }
            }
        }
    };
}

use crate::algorithm as a;
use skyplan_sampling::PlannerKind as K;
use skyplan_search::Planner as G;

planners! {
    /// Jump Point Search (the default).
    #[default]
    Jps => "jps", "JPS", 2, Exact, AnyGrid, [GridPath], "", &OnlineCells(G::Jps),
        "Jump Point Search: A*'s optimal costs, far fewer expansions (the default)";
    /// JPS with precomputed jumps.
    JpsPlus => "jps-plus", "JPS+", 2, Exact, AnyGrid, [GridPath], "the JPS+ table per grid and corner rule", &JpsPlusCells,
        "JPS+: JPS with every scan precomputed per grid; pays off over many queries";
    /// Contraction hierarchy over the grid graph.
    Ch => "ch", "CH", 2, Exact, AnyGrid, [GridPath, TimeLimit], "the contraction hierarchy per grid and move model", &a::HierarchyCells,
        "contraction hierarchy: exact, shortcuts precomputed per grid; fastest on random obstacles and 1–2-cell mazes";
    /// Simple subgoal graph with a contraction hierarchy over it.
    Subgoal => "subgoal", "subgoal graph", 2, Exact, AnyGrid, [GridPath, TimeLimit], "the subgoal graph and its hierarchy per grid", &a::SubgoalCells,
        "subgoal graph: exact, a hierarchy over the obstacles' convex corners per grid; fastest on mazes with corridors a few cells wide";
    /// First-move table: the first move of a shortest path between every pair of free cells.
    FirstMove => "first-move", "first-move table", 2, Exact, SmallGrid, [GridPath, TimeLimit], "the first-move table per grid and move model", &a::FirstMoveCells,
        "first-move table: exact, one lookup per cell of the path, no search; for small maps (its size grows with the square of the free cells)";
    /// The fastest exact grid planner for the map and the number of queries (JPS, JPS+, CH, the
    /// subgoal graph or the first-move table).
    Auto => "auto", "auto", 2, Exact, AnyGrid, [GridPath, TimeLimit], "what the planner it picks keeps (the JPS+ table, the contraction hierarchy, the subgoal graph, the first-move table), and the map's statistics", &a::AutoCells,
        "the fastest exact grid planner for the map and the number of queries: JPS, JPS+, CH, the subgoal graph or the first-move table, from measured map statistics";
    /// A\* with the octile (or Manhattan) heuristic.
    Astar => "astar", "A*", 2, Exact, AnyGrid, [GridPath], "", &OnlineCells(G::AStar),
        "A* with the octile (8-connected) or Manhattan (4-connected) heuristic";
    /// Bidirectional A\*.
    BidirAstar => "bidir-astar", "bidirectional A*", 2, Exact, AnyGrid, [GridPath], "", &CellFunction(skyplan_search::bidirectional_astar),
        "bidirectional A*: searches from both ends at once, stops when neither side can improve the best meeting";
    /// Dijkstra.
    Dijkstra => "dijkstra", "Dijkstra", 2, Exact, AnyGrid, [GridPath], "", &OnlineCells(G::Dijkstra),
        "Dijkstra (A* without a heuristic)";
    /// Theta\*.
    Theta => "theta", "Theta*", 2, AnyAngle, AnyGrid, [GridPath], "", &OnlineCells(G::ThetaStar),
        "Theta*: any-angle routes through cell centres, shorter than any grid path";
    /// Exact any-angle shortest paths.
    AnyAngle => "any-angle", "exact any-angle", 2, ExactAnyAngle, AnyGrid, [], "the visibility graph per grid", &a::ANY_ANGLE,
        "exact any-angle: the Euclidean-shortest route through the free cells, turning at obstacle corners";
    /// Wavefront navigation function.
    Wavefront => "wavefront", "wavefront", 2, Exact, AnyGrid, [GridPath, Field], "", &a::WAVEFRONT,
        "wavefront navigation function: distance field from the goal, then gradient descent";
    /// Inflated cost map A\*.
    Costmap => "costmap", "costmap A*", 2, ExactForObjective, AnyGrid, [GridPath, Inflation], "", &a::COSTMAP,
        "inflated cost map (Nav2-style): A* minimising length + weight x cost";
    /// Voronoi roadmap.
    Voronoi => "voronoi", "Voronoi roadmap", 2, Feasible, Obstacles, [], "the roadmap per altitude, margin and cell size", &a::VORONOI,
        "Voronoi roadmap of the grown footprints at the altitude: exactly free edges, graph A*";
    /// Probabilistic roadmap in 3D.
    Prm => "prm", "PRM", 3, Feasible, Obstacles, [ThreeD, TimeLimit], "the roadmap per flight volume and seed", &a::Sampling(K::Prm),
        "3D probabilistic roadmap among the grown obstacles (grown until start and goal connect)";
    /// Lazy PRM in 3D.
    LazyPrm => "lazy-prm", "lazy PRM", 3, Feasible, Obstacles, [ThreeD, TimeLimit], "the roadmap per flight volume and seed", &a::Sampling(K::LazyPrm),
        "3D lazy PRM: edges checked only on found paths";
    /// RRT-Connect in 3D.
    RrtConnect => "rrt-connect", "RRT-Connect", 3, Feasible, Obstacles, [ThreeD, TimeLimit], "the grown obstacles per flight volume", &a::Sampling(K::RrtConnect),
        "3D RRT-Connect: bidirectional trees, stops at the first path";
    /// Informed RRT\* in 3D.
    RrtStar => "rrt-star", "RRT*", 3, AsymptoticallyOptimal, Obstacles, [ThreeD, TimeLimit], "the grown obstacles per flight volume", &a::Sampling(K::RrtStar),
        "3D Informed RRT*: improves the path until the time limit";
    /// Voxel A\* in 3D.
    Voxel => "voxel", "voxel A*", 3, ExactForObjective, Obstacles, [ThreeD, TimeLimit, Lattice], "the grown obstacles per flight volume", &a::Voxel,
        "3D voxel A* (26-connected, altitude layers, climb cost): may climb over low buildings";
}

impl PlannerId {
    /// The CLI spelling (`jps-plus`).
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The names of the planners `keep` holds for, in registry order, for messages and help
    /// (`prm, lazy-prm, …`): derived, so a new planner is listed where it belongs.
    ///
    /// ```
    /// use skyplan_plan::PlannerId;
    /// assert_eq!(PlannerId::names_where(|p| p.info().dims == 3), "prm, lazy-prm, rrt-connect, rrt-star, voxel");
    /// ```
    pub fn names_where(keep: impl Fn(PlannerId) -> bool) -> String {
        let names: Vec<&str> = (Self::ALL.iter().copied())
            .filter(|&p| keep(p))
            .map(Self::name)
            .collect();
        names.join(", ")
    }

    /// Whether the planner uses the options of `group` (the others are refused).
    pub fn uses(self, group: OptionGroup) -> bool {
        self.info().uses.contains(&group)
    }

    /// Whether the planner's route is a path through grid cells (the cell searches, the
    /// wavefront and the cost map): it takes the grid-path options (connectivity, corner
    /// cutting, pruning, shortcut) and has a grid path to report and draw.
    pub fn is_cell_planner(self) -> bool {
        self.uses(OptionGroup::GridPath)
    }

    /// Whether the planner answers cell-to-cell queries on a grid ([`CellSearch`](crate::CellSearch):
    /// MovingAI replays, benchmarks), then prunes and shortcuts its path.
    pub fn is_cell_search(self) -> bool {
        self.algorithm().cells().is_some()
    }

    /// Whether the planner's route comes with a navigation field (a value per cell: the
    /// wavefront's distances, the cost map's cost to go) that a heat map can show.
    pub fn has_field(self) -> bool {
        self.algorithm().has_field()
    }

    /// Whether the planner's route is exactly shortest among grid paths under the move model
    /// (checked against the exact oracle).
    pub fn is_exact_on_grids(self) -> bool {
        self.info().optimality == Optimality::Exact
    }

    /// The planners that take a map: every one on a map of obstacles (colliders or footprints),
    /// the grid planners on a fixed grid.
    pub fn for_maps(obstacles: bool) -> impl Iterator<Item = PlannerId> {
        Self::ALL
            .iter()
            .copied()
            .filter(move |p| obstacles || p.info().maps != MapKinds::Obstacles)
    }

    /// Every name, comma-separated (for messages).
    pub fn all_names() -> String {
        Self::ALL
            .iter()
            .map(|p| p.name())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl fmt::Display for PlannerId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An unknown planner name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown planner {given:?}; expected one of {expected}")]
pub struct UnknownPlanner {
    /// What was given.
    pub given: String,
    /// The names there are.
    pub expected: String,
}

impl FromStr for PlannerId {
    type Err = UnknownPlanner;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        Self::ALL
            .iter()
            .copied()
            .find(|p| p.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| UnknownPlanner {
                given: s.to_string(),
                expected: Self::all_names(),
            })
    }
}

impl Serialize for PlannerId {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for PlannerId {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_through_text_and_json() {
        for &p in PlannerId::ALL {
            assert_eq!(p.name().parse::<PlannerId>(), Ok(p));
            let json = serde_json::to_string(&p).unwrap();
            assert_eq!(json, format!("\"{}\"", p.name()));
            assert_eq!(serde_json::from_str::<PlannerId>(&json).unwrap(), p);
        }
    }

    #[test]
    fn names_are_unique_and_kebab_case() {
        let mut names: Vec<_> = PlannerId::ALL.iter().map(|p| p.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), PlannerId::ALL.len());
        assert!(
            names
                .iter()
                .all(|n| n.chars().all(|c| c.is_ascii_lowercase() || c == '-'))
        );
    }

    #[test]
    fn unknown_names_list_the_known_ones() {
        let e = "rrt".parse::<PlannerId>().unwrap_err();
        assert!(e.to_string().contains("rrt-connect"));
    }
}
