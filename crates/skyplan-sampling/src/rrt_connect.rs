//! RRT-Connect (Kuffner & LaValle 2000): two trees, one from the start and one from the goal,
//! each extending towards random samples and then greedily towards the other tree's newest
//! vertex. Stops at the first connection. Every tree edge is an exactly checked segment.
//!
//! ```
//! use skyplan_map::colliders::ObstacleBox;
//! use skyplan_sampling::rrt_connect::{solve, RrtConnectConfig};
//! use skyplan_sampling::{Budget, Status};
//! use skyplan_world3::{BoxWorld3, WorldSpec};
//! let tower = ObstacleBox { north_m: 50.0, east_m: 50.0, up_m: 20.0, half_north_m: 10.0, half_east_m: 10.0, half_up_m: 20.0 };
//! let spec = WorldSpec { safety_m: 2.0, min_alt_m: 0.0, max_alt_m: 50.0, margin_bounds_m: 40.0 };
//! let world = BoxWorld3::new(&[tower], &spec)?;
//! let s = solve(&world, [20.0, 50.0, 10.0], [80.0, 50.0, 10.0], &RrtConnectConfig::default(), Budget::iterations(10_000));
//! assert_eq!(s.status, Status::Exact);
//! // Enclosed goal: inside the inflated tower it is invalid.
//! let s = solve(&world, [20.0, 50.0, 10.0], [50.0, 50.0, 10.0], &RrtConnectConfig::default(), Budget::iterations(100));
//! assert_eq!(s.status, Status::InvalidGoal);
//! # Ok::<(), skyplan_world3::WorldError>(())
//! ```

use crate::nearest::NearIndex;
use crate::tree::{Run, TreeConfig};
pub use crate::tree::{solve, solve_with_tree};
use crate::{Clock, CollisionChecker, Neu, Solution, Status, sample_in, steer, trace, tree_edges};

/// RRT-Connect settings. [`solve`] with them returns `Exact` at the first connection, `Timeout`
/// if the budget runs out first (an iteration is one random sample).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RrtConnectConfig {
    /// Seed of the samples.
    pub seed: u64,
    /// Longest edge, metres; `None`: 20 % of the bounds' largest extent.
    pub range_m: Option<f64>,
}

#[derive(Debug, Default)]
struct Tree {
    points: Vec<Neu>,
    parent: Vec<u32>,
    index: NearIndex,
}

enum Extend {
    Trapped,
    Advanced(u32),
    Reached(u32),
}

impl Tree {
    fn rooted(p: Neu) -> Self {
        let mut t = Self::default();
        t.points.push(p);
        t.parent.push(0);
        t.index.add(p);
        t
    }

    fn extend(&mut self, checker: &impl CollisionChecker, q: Neu, range_m: f64) -> Extend {
        let Some(near) = self.index.nearest(q) else {
            return Extend::Trapped;
        };
        let from = self.points[near as usize];
        let to = steer(from, q, range_m);
        if to == from || !checker.segment_is_free(from, to) {
            return Extend::Trapped;
        }
        let id = self.points.len() as u32;
        self.points.push(to);
        self.parent.push(near);
        self.index.add(to);
        if to == q {
            Extend::Reached(id)
        } else {
            Extend::Advanced(id)
        }
    }
}

impl TreeConfig for RrtConnectConfig {
    fn seed_and_range_m(&self) -> (u64, Option<f64>) {
        (self.seed, self.range_m)
    }

    fn grow(&self, checker: &impl CollisionChecker, run: Run<'_>) -> Solution {
        let (start, goal, mut clock, bounds, range_m, mut rng, mut edges) = run.0;
        let mut keep = |a: &Tree, b: &Tree| {
            if let Some(edges) = edges.as_deref_mut() {
                for t in [a, b] {
                    edges.extend(tree_edges(&t.points, &t.parent));
                }
            }
        };
        let finish = |status, path: Vec<Neu>, clock: &Clock, vertices| {
            let mut s = Solution::with_path(status, path, goal);
            s.iterations = clock.iterations();
            s.vertices = vertices;
            s.elapsed_us = clock.elapsed_us();
            s.first_solution_us = Some(s.elapsed_us);
            s
        };
        if start == goal || checker.segment_is_free(start, goal) {
            let path = if start == goal {
                vec![start]
            } else {
                vec![start, goal]
            };
            return finish(Status::Exact, path, &clock, 2);
        }
        // `a` grows this round, `b` answers; `a_is_start` says which tree is which.
        let mut a = Tree::rooted(start);
        let mut b = Tree::rooted(goal);
        let mut a_is_start = true;
        while clock.tick() {
            let q = sample_in(&bounds, &mut rng);
            let new_a = match a.extend(checker, q, range_m) {
                Extend::Trapped => None,
                Extend::Advanced(id) | Extend::Reached(id) => Some(id),
            };
            if let Some(new_a) = new_a {
                let target = a.points[new_a as usize];
                // Connect: extend b towards the new vertex until reached or trapped.
                loop {
                    match b.extend(checker, target, range_m) {
                        Extend::Trapped => break,
                        Extend::Advanced(_) => continue,
                        Extend::Reached(new_b) => {
                            let mut from_a = trace(&a.points, &a.parent, new_a);
                            let mut from_b = trace(&b.points, &b.parent, new_b);
                            from_b.pop(); // the shared point
                            from_b.reverse();
                            from_a.extend(from_b);
                            if !a_is_start {
                                from_a.reverse();
                            }
                            let vertices = a.points.len() + b.points.len();
                            let solution = finish(Status::Exact, from_a, &clock, vertices);
                            keep(&a, &b);
                            return solution;
                        }
                    }
                }
            }
            std::mem::swap(&mut a, &mut b);
            a_is_start = !a_is_start;
        }
        let solution = Solution::failed(
            Status::Timeout,
            clock.iterations(),
            a.points.len() + b.points.len(),
            clock.elapsed_us(),
        );
        keep(&a, &b);
        solution
    }
}
