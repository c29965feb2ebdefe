//! What the tree planners ([`crate::rrt_connect`], [`crate::rrt_star`]) share: the entry points
//! [`solve`] and [`solve_with_tree`] (each planner's module re-exports them; the settings type
//! picks the planner), and the checks and settings every run starts with.

use crate::{Budget, Clock, CollisionChecker, Neu, Solution, Status, default_range_m};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use skyplan_world3::Aabb;

/// The settings of a tree planner: [`crate::rrt_connect::RrtConnectConfig`] or
/// [`crate::rrt_star::RrtStarConfig`].
pub trait TreeConfig {
    /// Seed of the samples, and the longest edge, metres, as set (`None`, or not finite and
    /// positive: 20 % of the bounds' largest extent).
    fn seed_and_range_m(&self) -> (u64, Option<f64>);
    /// Grows the tree(s) of a run whose start and goal are free.
    #[doc(hidden)]
    fn grow(&self, checker: &impl CollisionChecker, run: Run<'_>) -> Solution;
}

/// A run under way, as [`TreeConfig::grow`] receives it: start, goal, clock, bounds, longest
/// edge, samples, and where to put the tree edges (child, parent) after the run, when given.
#[doc(hidden)]
pub struct Run<'a>(pub(crate) Parts<'a>);

type Parts<'a> = (
    Neu,
    Neu,
    Clock,
    Aabb,
    f64,
    ChaCha8Rng,
    Option<&'a mut Vec<(Neu, Neu)>>,
);

/// Plans from `start` to `goal` with the planner `config` sets (an iteration is one random
/// sample); what it returns is said at each settings type.
pub fn solve(
    checker: &impl CollisionChecker,
    start: Neu,
    goal: Neu,
    config: &impl TreeConfig,
    budget: Budget,
) -> Solution {
    run(checker, start, goal, config, budget, None)
}

/// [`solve`], also returning the edges of the tree(s) (child, parent) for pictures; collected
/// after the run, so the timings are those of [`solve`].
pub fn solve_with_tree(
    checker: &impl CollisionChecker,
    start: Neu,
    goal: Neu,
    config: &impl TreeConfig,
    budget: Budget,
) -> (Solution, Vec<(Neu, Neu)>) {
    let mut edges = Vec::new();
    let solution = run(checker, start, goal, config, budget, Some(&mut edges));
    (solution, edges)
}

pub(crate) fn run(
    checker: &impl CollisionChecker,
    start: Neu,
    goal: Neu,
    config: &impl TreeConfig,
    budget: Budget,
    edges: Option<&mut Vec<(Neu, Neu)>>,
) -> Solution {
    let clock = Clock::start(budget);
    if !checker.is_free(start) {
        return Solution::failed(Status::InvalidStart, 0, 0, clock.elapsed_us());
    }
    if !checker.is_free(goal) {
        return Solution::failed(Status::InvalidGoal, 0, 0, clock.elapsed_us());
    }
    let bounds = checker.bounds();
    let (seed, range_m) = config.seed_and_range_m();
    let range_m = range_m
        .filter(|r| r.is_finite() && *r > 0.0)
        .unwrap_or_else(|| default_range_m(&bounds));
    let rng = ChaCha8Rng::seed_from_u64(seed);
    let run = Run((start, goal, clock, bounds, range_m, rng, edges));
    config.grow(checker, run)
}
