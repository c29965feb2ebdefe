//! PRM in 3D: free samples, k-nearest neighbours (kiddo), every edge checked exactly, graph A\*.
//! A [`Roadmap`] is built once and answers many queries; [`solve`] grows it until the start and
//! goal connect or the budget is spent (OMPL's PRM).
//!
//! ```
//! use skyplan_map::colliders::ObstacleBox;
//! use skyplan_sampling::prm::{PrmConfig, Roadmap};
//! use skyplan_sampling::Status;
//! use skyplan_world3::{BoxWorld3, WorldSpec};
//! let tower = ObstacleBox { north_m: 50.0, east_m: 50.0, up_m: 20.0, half_north_m: 10.0, half_east_m: 10.0, half_up_m: 20.0 };
//! let spec = WorldSpec { safety_m: 2.0, min_alt_m: 0.0, max_alt_m: 50.0, margin_bounds_m: 40.0 };
//! let world = BoxWorld3::new(&[tower], &spec)?;
//! let roadmap = Roadmap::build(&world, &PrmConfig { samples: 300, ..PrmConfig::default() });
//! assert!(roadmap.edges() > 300);
//! let s = roadmap.query(&world, [20.0, 50.0, 10.0], [80.0, 50.0, 10.0]);
//! assert_eq!(s.status, Status::Exact);
//! assert!(s.cost_m > 60.0);
//! # Ok::<(), skyplan_world3::WorldError>(())
//! ```

use crate::graph::astar;
use crate::{Budget, Clock, CollisionChecker, Neu, Solution, Status, sample_in};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use skyplan_world3::distance_m;
use std::num::NonZeroUsize;
use std::time::Instant;

/// How to build a roadmap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrmConfig {
    /// Free samples of the first build.
    pub samples: usize,
    /// Neighbours tried per vertex; 0: OMPL's PRM\* rule `⌈e·(1 + 1/3)·ln n⌉`.
    pub k: usize,
    /// Seed of the samples.
    pub seed: u64,
    /// Draws allowed per free sample before giving up (a nearly full world).
    pub max_draws_per_sample: usize,
}

impl Default for PrmConfig {
    fn default() -> Self {
        Self {
            samples: 1000,
            k: 10,
            seed: 1,
            max_draws_per_sample: 100,
        }
    }
}

/// Build statistics of a roadmap.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BuildStats {
    /// Samples drawn (free or not).
    pub draws: usize,
    /// Candidate edges checked.
    pub edge_checks: usize,
    /// Wall time of all builds and growths, microseconds.
    pub build_us: u64,
}

/// A roadmap: vertices in free space and exactly free edges between them.
#[derive(Debug)]
pub struct Roadmap {
    vertices: Vec<Neu>,
    adjacency: Vec<Vec<(u32, f64)>>,
    tree: ImmutableKdTree<f64, 3>,
    k: usize,
    rng: ChaCha8Rng,
    max_draws_per_sample: usize,
    /// Build statistics.
    pub stats: BuildStats,
}

fn k_for(config_k: usize, n: usize) -> usize {
    if config_k > 0 {
        return config_k;
    }
    let e_ratio = std::f64::consts::E * (1.0 + 1.0 / 3.0);
    ((e_ratio * (n.max(2) as f64).ln()).ceil() as usize).max(1)
}

impl Roadmap {
    /// Samples `config.samples` free points and connects each to its k nearest neighbours by
    /// exactly free edges.
    pub fn build(checker: &impl CollisionChecker, config: &PrmConfig) -> Self {
        let mut roadmap = Self {
            vertices: Vec::new(),
            adjacency: Vec::new(),
            tree: ImmutableKdTree::default(),
            k: config.k,
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            max_draws_per_sample: config.max_draws_per_sample.max(1),
            stats: BuildStats::default(),
        };
        roadmap.grow(checker, config.samples);
        roadmap
    }

    /// Adds up to `samples` more free vertices and connects them; returns how many were added.
    pub fn grow(&mut self, checker: &impl CollisionChecker, samples: usize) -> usize {
        let t0 = Instant::now();
        let bounds = checker.bounds();
        let first_new = self.vertices.len();
        let mut draws_left = samples.saturating_mul(self.max_draws_per_sample);
        while self.vertices.len() < first_new + samples && draws_left > 0 {
            draws_left -= 1;
            self.stats.draws += 1;
            let p = sample_in(&bounds, &mut self.rng);
            if checker.is_free(p) {
                self.vertices.push(p);
                self.adjacency.push(Vec::new());
            }
        }
        let added = self.vertices.len() - first_new;
        if added > 0 {
            self.rebuild_tree();
            let k = k_for(self.k, self.vertices.len());
            let mut pairs: Vec<(u32, u32)> = Vec::new();
            for i in first_new..self.vertices.len() {
                for j in self.nearest(self.vertices[i], k + 1) {
                    if j as usize != i {
                        pairs.push(((i as u32).min(j), (i as u32).max(j)));
                    }
                }
            }
            pairs.sort_unstable();
            pairs.dedup();
            for (a, b) in pairs {
                let (pa, pb) = (self.vertices[a as usize], self.vertices[b as usize]);
                self.stats.edge_checks += 1;
                if self.adjacency[a as usize].iter().any(|&(w, _)| w == b) {
                    continue;
                }
                if checker.segment_is_free(pa, pb) {
                    let d = distance_m(pa, pb);
                    self.adjacency[a as usize].push((b, d));
                    self.adjacency[b as usize].push((a, d));
                }
            }
        }
        self.stats.build_us += t0.elapsed().as_micros() as u64;
        added
    }

    fn rebuild_tree(&mut self) {
        // A k-d tree over distinct random floats always builds; an empty tree on failure only
        // costs neighbours, never correctness.
        self.tree = ImmutableKdTree::new_from_slice(&self.vertices).unwrap_or_default();
    }

    fn nearest(&self, p: Neu, k: usize) -> Vec<u32> {
        let Some(k) = NonZeroUsize::new(k) else {
            return Vec::new();
        };
        if self.tree.size() == 0 {
            return Vec::new();
        }
        self.tree
            .query(&p)
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute()
            .into_iter()
            .map(|r| r.item)
            .collect()
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Neu] {
        &self.vertices
    }

    /// The undirected edges `(a, b)` with `a < b`.
    pub fn edge_list(&self) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for (a, list) in self.adjacency.iter().enumerate() {
            for &(b, _) in list {
                if (a as u32) < b {
                    out.push((a as u32, b));
                }
            }
        }
        out
    }

    /// Number of undirected edges.
    pub fn edges(&self) -> usize {
        self.adjacency.iter().map(Vec::len).sum::<usize>() / 2
    }

    /// Number of connected components (isolated vertices included).
    pub fn components(&self) -> usize {
        let mut seen = vec![false; self.vertices.len()];
        let mut count = 0;
        let mut stack = Vec::new();
        for s in 0..self.vertices.len() {
            if seen[s] {
                continue;
            }
            count += 1;
            seen[s] = true;
            stack.push(s);
            while let Some(v) = stack.pop() {
                for &(w, _) in &self.adjacency[v] {
                    if !seen[w as usize] {
                        seen[w as usize] = true;
                        stack.push(w as usize);
                    }
                }
            }
        }
        count
    }

    /// Connects `start` and `goal` to their nearest vertices by checked segments and runs graph
    /// A\* (the roadmap is not changed). `Timeout` if they do not connect.
    pub fn query(&self, checker: &impl CollisionChecker, start: Neu, goal: Neu) -> Solution {
        let t0 = Instant::now();
        let n = self.vertices.len();
        let done = |mut s: Solution| {
            s.vertices = n;
            s.elapsed_us = t0.elapsed().as_micros() as u64;
            if s.status == Status::Exact {
                s.first_solution_us = Some(s.elapsed_us);
            }
            s
        };
        if !checker.is_free(start) {
            return done(Solution::failed(Status::InvalidStart, 0, n, 0));
        }
        if !checker.is_free(goal) {
            return done(Solution::failed(Status::InvalidGoal, 0, n, 0));
        }
        if checker.segment_is_free(start, goal) {
            return done(Solution::with_path(Status::Exact, vec![start, goal], goal));
        }
        // Attach each end to up to k free vertices among its 3k nearest.
        let k = k_for(self.k, n.max(2));
        let attach = |p: Neu| -> Vec<(u32, f64)> {
            self.nearest(p, 3 * k)
                .into_iter()
                .filter(|&v| checker.segment_is_free(p, self.vertices[v as usize]))
                .take(k)
                .map(|v| (v, distance_m(p, self.vertices[v as usize])))
                .collect()
        };
        let from_start = attach(start);
        let to_goal = attach(goal);
        if from_start.is_empty() || to_goal.is_empty() {
            return done(Solution::failed(Status::Timeout, 0, n, 0));
        }
        // Nodes n (start) and n + 1 (goal) join a copy of the adjacency lists.
        let (s, g) = (n as u32, n as u32 + 1);
        let mut adjacency = self.adjacency.clone();
        adjacency.push(from_start.clone());
        adjacency.push(to_goal.clone());
        for &(v, d) in &from_start {
            adjacency[v as usize].push((s, d));
        }
        for &(v, d) in &to_goal {
            adjacency[v as usize].push((g, d));
        }
        let point = |v: u32| match v {
            v if v == s => start,
            v if v == g => goal,
            v => self.vertices[v as usize],
        };
        match astar(&adjacency, s, g, |v| distance_m(point(v), goal)) {
            Some((nodes, _)) => done(Solution::with_path(
                Status::Exact,
                nodes.into_iter().map(point).collect(),
                goal,
            )),
            None => done(Solution::failed(Status::Timeout, 0, n, 0)),
        }
    }
}

/// Builds a roadmap, queries it, and while the query fails grows the roadmap by half its size
/// until it succeeds or the budget is spent (an iteration is one sample).
pub fn solve(
    checker: &impl CollisionChecker,
    start: Neu,
    goal: Neu,
    config: &PrmConfig,
    budget: Budget,
) -> (Roadmap, Solution) {
    let mut clock = Clock::start(budget);
    let mut roadmap = Roadmap::build(
        checker,
        &PrmConfig {
            samples: 0,
            ..*config
        },
    );
    let finish = |mut s: Solution, clock: &Clock, roadmap: &Roadmap| {
        s.iterations = clock.iterations();
        s.vertices = roadmap.vertices.len();
        s.elapsed_us = clock.elapsed_us();
        if s.status == Status::Exact {
            s.first_solution_us = Some(s.elapsed_us);
        }
        s
    };
    if !checker.is_free(start) {
        let s = Solution::failed(Status::InvalidStart, 0, 0, 0);
        let s = finish(s, &clock, &roadmap);
        return (roadmap, s);
    }
    if !checker.is_free(goal) {
        let s = Solution::failed(Status::InvalidGoal, 0, 0, 0);
        let s = finish(s, &clock, &roadmap);
        return (roadmap, s);
    }
    let mut batch = config.samples.max(1);
    loop {
        let mut granted = 0;
        while granted < batch && clock.tick() {
            granted += 1;
        }
        if granted > 0 {
            roadmap.grow(checker, granted);
        }
        let s = roadmap.query(checker, start, goal);
        if s.status == Status::Exact || granted < batch {
            let s = finish(s, &clock, &roadmap);
            return (roadmap, s);
        }
        batch = (roadmap.vertices.len() / 2).max(1);
    }
}
