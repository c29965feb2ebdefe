//! RRT\* (Karaman & Frazzoli 2011, k-nearest variant as OMPL's default) with Informed RRT\*
//! sampling (Gammell et al. 2014): once a solution of cost `c` exists, samples are drawn from the
//! prolate spheroid of points whose start + goal distance is below `c`. Uses the whole budget.
//!
//! The goal is never a tree vertex: a vertex within range that sees the goal by a free segment
//! is a *goal link*, and the solution is the best link's branch plus that segment (costs are
//! kept current through rewiring).
//!
//! ```
//! use skyplan_map::colliders::ObstacleBox;
//! use skyplan_sampling::rrt_star::{solve, RrtStarConfig};
//! use skyplan_sampling::{Budget, Status};
//! use skyplan_world3::{BoxWorld3, WorldSpec, distance_m};
//! let tower = ObstacleBox { north_m: 50.0, east_m: 50.0, up_m: 20.0, half_north_m: 10.0, half_east_m: 10.0, half_up_m: 20.0 };
//! let spec = WorldSpec { safety_m: 2.0, min_alt_m: 0.0, max_alt_m: 50.0, margin_bounds_m: 40.0 };
//! let world = BoxWorld3::new(&[tower], &spec)?;
//! let (start, goal) = ([20.0, 50.0, 10.0], [80.0, 50.0, 10.0]);
//! let s = solve(&world, start, goal, &RrtStarConfig::default(), Budget::iterations(3_000));
//! assert_eq!(s.status, Status::Exact);
//! assert!(s.cost_m < 1.3 * distance_m(start, goal));
//! # Ok::<(), skyplan_world3::WorldError>(())
//! ```

use crate::nearest::NearIndex;
use crate::tree::{Run, TreeConfig};
pub use crate::tree::{solve, solve_with_tree};
use crate::{CollisionChecker, Neu, Solution, Status, sample_in, steer, trace, tree_edges};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use skyplan_world3::{Aabb, distance_m};

/// RRT\* settings. [`solve`] with them plans until the budget is spent (an iteration is one
/// sample): `Exact` with the best path found; otherwise `Approximate` with the branch to the
/// vertex nearest the goal, or `Timeout` if no vertex is nearer the goal than the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RrtStarConfig {
    /// Seed of the samples.
    pub seed: u64,
    /// Longest edge, metres; `None`: 20 % of the bounds' largest extent.
    pub range_m: Option<f64>,
    /// Probability of sampling the goal itself (before a solution exists).
    pub goal_bias: f64,
    /// Sample the informed set once a solution exists (Informed RRT\*).
    pub informed: bool,
}

impl Default for RrtStarConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            range_m: None,
            goal_bias: 0.05,
            informed: true,
        }
    }
}

struct Tree {
    points: Vec<Neu>,
    parent: Vec<u32>,
    cost_m: Vec<f64>,
    children: Vec<Vec<u32>>,
    index: NearIndex,
}

impl Tree {
    /// A tree of one vertex: the start (its own parent).
    fn new(start: Neu) -> Self {
        let mut tree = Tree {
            points: Vec::new(),
            parent: Vec::new(),
            cost_m: Vec::new(),
            children: Vec::new(),
            index: NearIndex::default(),
        };
        tree.add(start, 0, 0.0);
        tree
    }

    /// The goal link whose branch plus the segment to the goal is cheapest, and that cost.
    fn best_link(&self, links: &[u32], goal: Neu) -> Option<(u32, f64)> {
        links
            .iter()
            .map(|&v| {
                (
                    v,
                    self.cost_m[v as usize] + distance_m(self.points[v as usize], goal),
                )
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// The cheapest of the `near` vertices that sees `new` by a free segment, with the cost of
    /// `new` through it (cheapest first, the first free one wins).
    fn choose_parent(
        &self,
        checker: &impl CollisionChecker,
        near: &[u32],
        new: Neu,
    ) -> Option<(f64, u32)> {
        let mut candidates: Vec<(f64, u32)> = near
            .iter()
            .map(|&v| {
                let d = distance_m(self.points[v as usize], new);
                (self.cost_m[v as usize] + d, v)
            })
            .collect();
        candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
        candidates
            .into_iter()
            .find(|&(_, v)| checker.segment_is_free(self.points[v as usize], new))
    }

    /// Rewires the `near` vertices (but `parent`) that become cheaper through the new vertex
    /// `id`; true if any did.
    fn rewire(
        &mut self,
        checker: &impl CollisionChecker,
        near: &[u32],
        parent: u32,
        id: u32,
    ) -> bool {
        let (new, new_cost) = (self.points[id as usize], self.cost_m[id as usize]);
        let mut changed = false;
        for &v in near {
            if v == parent {
                continue;
            }
            let through = new_cost + distance_m(new, self.points[v as usize]);
            if through < self.cost_m[v as usize]
                && checker.segment_is_free(new, self.points[v as usize])
            {
                self.reparent(v, id, through);
                changed = true;
            }
        }
        changed
    }

    /// The best goal link's branch plus the goal (`Exact`), else the branch to the vertex
    /// nearest the goal (`Approximate`), or `Timeout` if that is the start.
    fn solution(&self, goal_links: &[u32], goal: Neu) -> Solution {
        match self.best_link(goal_links, goal) {
            Some((v, _)) => {
                let mut path = trace(&self.points, &self.parent, v);
                if path.last() != Some(&goal) {
                    path.push(goal);
                }
                Solution::with_path(Status::Exact, path, goal)
            }
            None => {
                let closest = (0..self.points.len() as u32)
                    .min_by(|&a, &b| {
                        distance_m(self.points[a as usize], goal)
                            .total_cmp(&distance_m(self.points[b as usize], goal))
                    })
                    .unwrap_or(0);
                if closest == 0 {
                    Solution::failed(Status::Timeout, 0, 0, 0)
                } else {
                    Solution::with_path(
                        Status::Approximate,
                        trace(&self.points, &self.parent, closest),
                        goal,
                    )
                }
            }
        }
    }

    fn add(&mut self, p: Neu, parent: u32, cost_m: f64) -> u32 {
        let id = self.points.len() as u32;
        self.points.push(p);
        self.parent.push(parent);
        self.cost_m.push(cost_m);
        self.children.push(Vec::new());
        if id != parent {
            self.children[parent as usize].push(id);
        }
        self.index.add(p);
        id
    }

    fn reparent(&mut self, v: u32, new_parent: u32, new_cost_m: f64) {
        let old = self.parent[v as usize];
        if let Some(pos) = self.children[old as usize].iter().position(|&c| c == v) {
            self.children[old as usize].swap_remove(pos);
        }
        self.children[new_parent as usize].push(v);
        self.parent[v as usize] = new_parent;
        let delta = new_cost_m - self.cost_m[v as usize];
        let mut stack = vec![v];
        while let Some(u) = stack.pop() {
            self.cost_m[u as usize] += delta;
            stack.extend_from_slice(&self.children[u as usize]);
        }
    }
}

/// Samples the informed set `{x : |x − start| + |x − goal| ≤ c_best}` within the bounds
/// (rejection; falls back to the whole bounds after 100 misses).
fn sample_informed(start: Neu, goal: Neu, c_best: f64, bounds: &Aabb, rng: &mut ChaCha8Rng) -> Neu {
    let c_min = distance_m(start, goal);
    if !(c_best.is_finite() && c_best > c_min && c_min > 0.0) {
        return sample_in(bounds, rng);
    }
    let a1 = [
        (goal[0] - start[0]) / c_min,
        (goal[1] - start[1]) / c_min,
        (goal[2] - start[2]) / c_min,
    ];
    // Complete a1 to an orthonormal basis (the spheroid is symmetric about a1).
    let helper = if a1[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let cross = |u: Neu, v: Neu| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let e2 = cross(a1, helper);
    let n2 = distance_m([0.0; 3], e2);
    let e2 = e2.map(|v| v / n2);
    let e3 = cross(a1, e2);
    let r1 = c_best / 2.0;
    let r2 = (c_best * c_best - c_min * c_min).sqrt() / 2.0;
    let centre = [
        (start[0] + goal[0]) / 2.0,
        (start[1] + goal[1]) / 2.0,
        (start[2] + goal[2]) / 2.0,
    ];
    for _ in 0..100 {
        let u: [f64; 3] = [
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        if u[0] * u[0] + u[1] * u[1] + u[2] * u[2] > 1.0 {
            continue;
        }
        let p = [0, 1, 2]
            .map(|i| centre[i] + r1 * u[0] * a1[i] + r2 * u[1] * e2[i] + r2 * u[2] * e3[i]);
        if bounds.contains(p) {
            return p;
        }
    }
    sample_in(bounds, rng)
}

impl TreeConfig for RrtStarConfig {
    fn seed_and_range_m(&self) -> (u64, Option<f64>) {
        (self.seed, self.range_m)
    }

    fn grow(&self, checker: &impl CollisionChecker, run: Run<'_>) -> Solution {
        let config = self;
        let (start, goal, mut clock, bounds, range_m, mut rng, edges) = run.0;
        let mut tree = Tree::new(start);
        let mut goal_links: Vec<u32> = Vec::new();
        let mut first_solution_us = None;
        if start == goal
            || (distance_m(start, goal) <= range_m && checker.segment_is_free(start, goal))
        {
            goal_links.push(0);
            first_solution_us = Some(clock.elapsed_us());
        }
        let k_rrg = std::f64::consts::E * (1.0 + 1.0 / 3.0);
        let mut c_best = tree
            .best_link(&goal_links, goal)
            .map_or(f64::INFINITY, |b| b.1);
        while clock.tick() {
            if c_best <= distance_m(start, goal) {
                break; // the straight line: nothing left to improve
            }
            let q = if c_best.is_finite() && config.informed {
                sample_informed(start, goal, c_best, &bounds, &mut rng)
            } else if !c_best.is_finite() && rng.random_bool(config.goal_bias.clamp(0.0, 1.0)) {
                goal
            } else {
                sample_in(&bounds, &mut rng)
            };
            let Some(nearest) = tree.index.nearest(q) else {
                break;
            };
            let new = steer(tree.points[nearest as usize], q, range_m);
            if new == goal || new == tree.points[nearest as usize] || !checker.is_free(new) {
                // The goal is reached through goal links, never added as a vertex.
                if new == goal
                    && !goal_links.contains(&nearest)
                    && checker.segment_is_free(tree.points[nearest as usize], goal)
                {
                    goal_links.push(nearest);
                    first_solution_us.get_or_insert(clock.elapsed_us());
                    c_best = tree
                        .best_link(&goal_links, goal)
                        .map_or(f64::INFINITY, |b| b.1);
                }
                continue;
            }
            let n = tree.points.len() as f64;
            let k = ((k_rrg * (n + 1.0).ln()).ceil() as usize).max(1);
            let mut near = tree.index.nearest_n(new, k);
            if !near.contains(&nearest) {
                near.push(nearest);
            }
            let Some((new_cost, parent)) = tree.choose_parent(checker, &near, new) else {
                continue;
            };
            let id = tree.add(new, parent, new_cost);
            let changed = tree.rewire(checker, &near, parent, id);
            let mut linked = false;
            if distance_m(new, goal) <= range_m && checker.segment_is_free(new, goal) {
                goal_links.push(id);
                first_solution_us.get_or_insert(clock.elapsed_us());
                linked = true;
            }
            if (changed || linked) && !goal_links.is_empty() {
                c_best = tree
                    .best_link(&goal_links, goal)
                    .map_or(f64::INFINITY, |b| b.1);
            }
        }
        let mut solution = tree.solution(&goal_links, goal);
        solution.iterations = clock.iterations();
        solution.vertices = tree.points.len();
        solution.elapsed_us = clock.elapsed_us();
        solution.first_solution_us = first_solution_us;
        if let Some(edges) = edges {
            edges.extend(tree_edges(&tree.points, &tree.parent));
        }
        solution
    }
}
