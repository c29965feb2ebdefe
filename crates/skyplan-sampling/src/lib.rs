//! Sampling-based 3D planners for skyplan: PRM ([`prm`]), RRT-Connect ([`rrt_connect`]),
//! RRT\* and Informed RRT\* ([`rrt_star`]), and 3D shortcutting ([`shortcut`]).
//!
//! Every planner sees the world only through [`CollisionChecker`] (`is_free`, `segment_is_free`,
//! `bounds`): every edge of a roadmap or tree is checked exactly as a continuous segment, so a
//! returned path is free if the checker is. Runs are seeded (ChaCha8) and reproducible, and end
//! with an OMPL-like [`Status`].
//!
//! ```
//! use skyplan_map::colliders::ObstacleBox;
//! use skyplan_sampling::{plan, Budget, PlannerKind, Request, Status};
//! use skyplan_world3::{BoxWorld3, CollisionChecker, WorldSpec, first_blocked_segment};
//! // A wall across the middle of a 100 m square, 30 m tall; fly over or around it.
//! let wall = ObstacleBox { north_m: 50.0, east_m: 50.0, up_m: 15.0, half_north_m: 2.0, half_east_m: 40.0, half_up_m: 15.0 };
//! let spec = WorldSpec { safety_m: 3.0, min_alt_m: 0.0, max_alt_m: 60.0, margin_bounds_m: 48.0 };
//! let world = BoxWorld3::new(&[wall], &spec)?;
//! for kind in [PlannerKind::Prm, PlannerKind::RrtConnect, PlannerKind::RrtStar] {
//!     let request = Request { start: [10.0, 50.0, 5.0], goal: [90.0, 50.0, 5.0], seed: 7,
//!                             budget: Budget::iterations(5_000), ..Request::default() };
//!     let solution = plan(&world, kind, &request);
//!     assert_eq!(solution.status, Status::Exact, "{kind:?}");
//!     assert_eq!(solution.path.first(), Some(&request.start));
//!     assert_eq!(solution.path.last(), Some(&request.goal));
//!     assert_eq!(first_blocked_segment(&world.brute_force(), &solution.path), None);
//! }
//! # Ok::<(), skyplan_world3::WorldError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod graph;
pub mod nearest;
pub mod prm;
pub mod rrt_connect;
pub mod rrt_star;
pub mod shortcut;
pub mod tree;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_world3::{Aabb, distance_m, path_length_m};
pub use skyplan_world3::{CollisionChecker, Neu};
use std::time::{Duration, Instant};

/// How a run ended, as in OMPL's `PlannerStatus`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Status {
    /// A path from the start to the goal.
    Exact,
    /// No path to the goal within the budget; the path ends at the reachable point found nearest
    /// to the goal.
    Approximate,
    /// No path within the budget, and nothing closer to the goal than the start.
    Timeout,
    /// The start is not in free space.
    InvalidStart,
    /// The goal is not in free space.
    InvalidGoal,
}

impl Status {
    /// The snake-case name used in JSON outputs: `exact`, `approximate`, `timeout`,
    /// `invalid_start`, `invalid_goal`.
    pub fn name(self) -> &'static str {
        match self {
            Status::Exact => "exact",
            Status::Approximate => "approximate",
            Status::Timeout => "timeout",
            Status::InvalidStart => "invalid_start",
            Status::InvalidGoal => "invalid_goal",
        }
    }
}

/// A budget: the run stops at whichever limit it reaches first (OMPL's composed termination
/// conditions).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Most iterations (samples drawn), if limited.
    pub max_iterations: Option<usize>,
    /// Most wall time, if limited.
    pub time_limit: Option<Duration>,
}

impl Budget {
    /// Only an iteration limit (fully reproducible results).
    pub fn iterations(n: usize) -> Self {
        Self {
            max_iterations: Some(n),
            time_limit: None,
        }
    }

    /// Only a time limit.
    pub fn time(limit: Duration) -> Self {
        Self {
            max_iterations: None,
            time_limit: Some(limit),
        }
    }
}

impl Default for Budget {
    /// 200,000 iterations or 1 s.
    fn default() -> Self {
        Self {
            max_iterations: Some(200_000),
            time_limit: Some(Duration::from_secs(1)),
        }
    }
}

/// Tracks a [`Budget`] during a run.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Clock {
    started: Instant,
    budget: Budget,
    iterations: usize,
}

impl Clock {
    pub(crate) fn start(budget: Budget) -> Self {
        Self {
            started: Instant::now(),
            budget,
            iterations: 0,
        }
    }

    /// Counts one iteration; false when the budget is spent.
    pub(crate) fn tick(&mut self) -> bool {
        if self
            .budget
            .max_iterations
            .is_some_and(|n| self.iterations >= n)
        {
            return false;
        }
        if self
            .budget
            .time_limit
            .is_some_and(|t| self.iterations.is_multiple_of(16) && self.started.elapsed() >= t)
        {
            return false;
        }
        self.iterations += 1;
        true
    }

    pub(crate) fn iterations(&self) -> usize {
        self.iterations
    }

    pub(crate) fn elapsed_us(&self) -> u64 {
        self.started.elapsed().as_micros() as u64
    }
}

/// The result of one planning run.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// How the run ended.
    pub status: Status,
    /// The path (`Exact`: start … goal; `Approximate`: start … nearest reachable point); empty
    /// otherwise.
    pub path: Vec<Neu>,
    /// Length of `path`, metres (infinite when empty).
    pub cost_m: f64,
    /// Distance from the path's end to the goal, metres (0 when exact, infinite when empty).
    pub goal_gap_m: f64,
    /// Iterations (samples) used.
    pub iterations: usize,
    /// Vertices of the roadmap or trees at the end.
    pub vertices: usize,
    /// Wall time until the first exact solution, microseconds.
    pub first_solution_us: Option<u64>,
    /// Wall time of the whole run, microseconds.
    pub elapsed_us: u64,
}

impl Solution {
    pub(crate) fn failed(
        status: Status,
        iterations: usize,
        vertices: usize,
        elapsed_us: u64,
    ) -> Self {
        Self {
            status,
            path: Vec::new(),
            cost_m: f64::INFINITY,
            goal_gap_m: f64::INFINITY,
            iterations,
            vertices,
            first_solution_us: None,
            elapsed_us,
        }
    }

    pub(crate) fn with_path(status: Status, path: Vec<Neu>, goal: Neu) -> Self {
        let goal_gap_m = path.last().map_or(f64::INFINITY, |&p| distance_m(p, goal));
        Self {
            status,
            cost_m: path_length_m(&path),
            path,
            goal_gap_m,
            iterations: 0,
            vertices: 0,
            first_solution_us: None,
            elapsed_us: 0,
        }
    }
}

/// The 3D planners (the planning API's registry names them: `prm`, `lazy-prm`, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlannerKind {
    /// Probabilistic roadmap (k-nearest, grown until start and goal connect), then graph A\*.
    Prm,
    /// Lazy PRM (Bohlin & Kavraki): the same roadmap with unchecked edges; only the edges of a
    /// found path are checked, blocked ones removed, and the search repeated.
    LazyPrm,
    /// Bidirectional RRT; stops at the first solution.
    RrtConnect,
    /// Asymptotically optimal RRT\* with informed sampling once a solution exists; uses the whole
    /// budget.
    RrtStar,
}

/// One planning request for [`plan`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Request {
    /// Start point.
    pub start: Neu,
    /// Goal point.
    pub goal: Neu,
    /// Seed of the random samples.
    pub seed: u64,
    /// When to stop.
    pub budget: Budget,
    /// Longest tree edge for the RRTs, metres; `None`: 20 % of the bounds' largest extent (OMPL's
    /// default range).
    pub range_m: Option<f64>,
    /// Shortcut the result (exactly re-checked, never longer).
    pub simplify: bool,
}

impl Default for Request {
    fn default() -> Self {
        Self {
            start: [0.0; 3],
            goal: [0.0; 3],
            seed: 1,
            budget: Budget::default(),
            range_m: None,
            simplify: true,
        }
    }
}

/// Runs one planner on one request, then (if asked) shortcuts an exact path.
///
/// The returned path's first point is `request.start` and, when the status is
/// [`Status::Exact`], its last point is `request.goal`, bit for bit.
pub fn plan(checker: &impl CollisionChecker, kind: PlannerKind, request: &Request) -> Solution {
    run_plan(checker, kind, request, None)
}

/// [`plan`], also returning what the planner grew, as segments for pictures: the trees' edges
/// for RRT-Connect (both trees) and RRT\*, the roadmap's edges for PRM (lazy PRM: also edges it
/// has not checked). They are collected after the run, so the solution (and its timings) is
/// that of [`plan`].
pub fn plan_with_tree(
    checker: &impl CollisionChecker,
    kind: PlannerKind,
    request: &Request,
) -> (Solution, Vec<(Neu, Neu)>) {
    let mut edges = Vec::new();
    let solution = run_plan(checker, kind, request, Some(&mut edges));
    (solution, edges)
}

fn run_plan(
    checker: &impl CollisionChecker,
    kind: PlannerKind,
    request: &Request,
    edges: Option<&mut Vec<(Neu, Neu)>>,
) -> Solution {
    let (start, goal, budget) = (request.start, request.goal, request.budget);
    let mut solution = match kind {
        PlannerKind::Prm | PlannerKind::LazyPrm => {
            let config = prm::PrmConfig {
                seed: request.seed,
                lazy: kind == PlannerKind::LazyPrm,
                ..prm::PrmConfig::default()
            };
            let (roadmap, solution) = prm::solve(checker, start, goal, &config, budget);
            if let Some(edges) = edges {
                let points = roadmap.vertices();
                edges.extend(
                    roadmap
                        .edge_list()
                        .into_iter()
                        .map(|(a, b)| (points[a as usize], points[b as usize])),
                );
            }
            solution
        }
        PlannerKind::RrtConnect => {
            let config = rrt_connect::RrtConnectConfig {
                seed: request.seed,
                range_m: request.range_m,
            };
            tree::run(checker, start, goal, &config, budget, edges)
        }
        PlannerKind::RrtStar => {
            let config = rrt_star::RrtStarConfig {
                seed: request.seed,
                range_m: request.range_m,
                ..rrt_star::RrtStarConfig::default()
            };
            tree::run(checker, start, goal, &config, budget, edges)
        }
    };
    if request.simplify && solution.status == Status::Exact {
        let mut rng = ChaCha8Rng::seed_from_u64(request.seed ^ 0x5eed_5eed);
        solution.path = shortcut::simplify(checker, &solution.path, &mut rng, 200);
        solution.cost_m = path_length_m(&solution.path);
    }
    solution
}

/// Default RRT range: 20 % of the bounds' largest extent.
pub(crate) fn default_range_m(bounds: &Aabb) -> f64 {
    let e = bounds.extent_m();
    0.2 * e[0].max(e[1]).max(e[2])
}

/// A uniform sample in the bounds.
pub(crate) fn sample_in(bounds: &Aabb, rng: &mut ChaCha8Rng) -> Neu {
    let mut p = [0.0; 3];
    for (i, v) in p.iter_mut().enumerate() {
        let u: f64 = rng.random();
        *v = bounds.min[i] + u * (bounds.max[i] - bounds.min[i]);
    }
    p
}

/// The point `range_m` from `from` towards `to`, or `to` itself if it is that close.
pub(crate) fn steer(from: Neu, to: Neu, range_m: f64) -> Neu {
    let d = distance_m(from, to);
    if d <= range_m {
        return to;
    }
    let s = range_m / d;
    [
        from[0] + (to[0] - from[0]) * s,
        from[1] + (to[1] - from[1]) * s,
        from[2] + (to[2] - from[2]) * s,
    ]
}

/// Every (child, parent) edge of a tree given by parent links (the root is its own parent).
pub(crate) fn tree_edges<'a>(
    points: &'a [Neu],
    parent: &'a [u32],
) -> impl Iterator<Item = (Neu, Neu)> + 'a {
    parent
        .iter()
        .enumerate()
        .filter(|&(v, &p)| p as usize != v)
        .map(|(v, &p)| (points[v], points[p as usize]))
}

/// Walks parent links from `node` to the root and returns the points root-first.
pub(crate) fn trace(points: &[Neu], parent: &[u32], node: u32) -> Vec<Neu> {
    let mut path = vec![points[node as usize]];
    let mut k = node;
    while parent[k as usize] != k {
        k = parent[k as usize];
        path.push(points[k as usize]);
    }
    path.reverse();
    path
}
