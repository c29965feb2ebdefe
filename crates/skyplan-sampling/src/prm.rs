//! PRM in 3D: free samples, k-nearest neighbours (kiddo), every edge checked exactly, graph A\*.
//! A [`Roadmap`] is built once and answers many queries; [`solve`] grows it until the start and
//! goal connect or the budget is spent (OMPL's PRM). With [`PrmConfig::lazy`] it is Lazy PRM
//! (Bohlin & Kavraki): edges join unchecked, [`Roadmap::query_lazy`] checks only the edges of a
//! found path, removes blocked ones and searches again. [`Roadmap::to_json`] saves a roadmap with
//! the [`WorldFingerprint`] of its world; [`Roadmap::from_json`] refuses it for any other world.
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
use serde::{Deserialize, Serialize};
use skyplan_world3::{BoxWorld3, distance_m};
use std::collections::HashSet;
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
    /// Lazy PRM (Bohlin & Kavraki): edges join the roadmap unchecked and only the edges of a
    /// found path are checked ([`Roadmap::query_lazy`]).
    pub lazy: bool,
}

impl Default for PrmConfig {
    fn default() -> Self {
        Self {
            samples: 1000,
            k: 10,
            seed: 1,
            max_draws_per_sample: 100,
            lazy: false,
        }
    }
}

/// Build statistics of a roadmap.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BuildStats {
    /// Samples drawn (free or not).
    pub draws: usize,
    /// Candidate edges considered while building (eager PRM: each one checked exactly).
    pub edge_checks: usize,
    /// Segment tests of roadmap edges actually run (eager: at build; lazy: on found paths).
    pub edges_tested: usize,
    /// Roadmap edges found blocked and removed (lazy PRM).
    pub edges_removed: usize,
    /// Segment tests of start/goal connectors (and the straight line) by `query_lazy`/`solve`.
    pub connector_tests: usize,
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
    seed: u64,
    rng: ChaCha8Rng,
    max_draws_per_sample: usize,
    lazy: bool,
    /// Edges `(a, b)`, `a < b`, in the adjacency lists but not yet checked (lazy PRM).
    unchecked: HashSet<(u32, u32)>,
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
            seed: config.seed,
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            max_draws_per_sample: config.max_draws_per_sample.max(1),
            lazy: config.lazy,
            unchecked: HashSet::new(),
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
                if self.lazy {
                    let d = distance_m(pa, pb);
                    self.adjacency[a as usize].push((b, d));
                    self.adjacency[b as usize].push((a, d));
                    self.unchecked.insert((a, b));
                    continue;
                }
                self.stats.edges_tested += 1;
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

    /// Whether edges join the roadmap unchecked (lazy PRM).
    pub fn is_lazy(&self) -> bool {
        self.lazy
    }

    /// Edges in the roadmap not yet checked (lazy PRM; 0 for an eager roadmap).
    pub fn unchecked_edges(&self) -> usize {
        self.unchecked.len()
    }

    /// Connects `start` and `goal` to their nearest vertices and runs graph A\* (the roadmap is
    /// not changed). `Timeout` if they do not connect. Eager roadmaps attach the ends by checked
    /// segments; lazy ones attach them unchecked, check the edges of each path found, drop the
    /// blocked ones and search again (on a copy: [`Roadmap::query_lazy`] keeps what it learned).
    pub fn query(&self, checker: &impl CollisionChecker, start: Neu, goal: Neu) -> Solution {
        self.search(checker, start, goal).0
    }

    /// Lazy PRM's query (Bohlin & Kavraki): as [`Roadmap::query`], and the roadmap keeps what
    /// the checks learned — blocked edges are removed, free ones are marked checked, so later
    /// queries never test an edge twice. On an eager roadmap the same as [`Roadmap::query`].
    pub fn query_lazy(
        &mut self,
        checker: &impl CollisionChecker,
        start: Neu,
        goal: Neu,
    ) -> Solution {
        let (solution, learned) = self.search(checker, start, goal);
        self.stats.edges_tested += learned.tested;
        self.stats.connector_tests += learned.connector_tests;
        for e in &learned.free {
            self.unchecked.remove(e);
        }
        for &(a, b) in &learned.blocked {
            if self.unchecked.remove(&(a, b)) {
                self.adjacency[a as usize].retain(|&(w, _)| w != b);
                self.adjacency[b as usize].retain(|&(w, _)| w != a);
                self.stats.edges_removed += 1;
            }
        }
        solution
    }

    fn search(
        &self,
        checker: &impl CollisionChecker,
        start: Neu,
        goal: Neu,
    ) -> (Solution, Learned) {
        let t0 = Instant::now();
        let n = self.vertices.len();
        let mut learned = Learned::default();
        let done = |mut s: Solution| {
            s.vertices = n;
            s.elapsed_us = t0.elapsed().as_micros() as u64;
            if s.status == Status::Exact {
                s.first_solution_us = Some(s.elapsed_us);
            }
            s
        };
        if !checker.is_free(start) {
            return (
                done(Solution::failed(Status::InvalidStart, 0, n, 0)),
                learned,
            );
        }
        if !checker.is_free(goal) {
            return (
                done(Solution::failed(Status::InvalidGoal, 0, n, 0)),
                learned,
            );
        }
        learned.connector_tests += 1;
        if checker.segment_is_free(start, goal) {
            let s = Solution::with_path(Status::Exact, vec![start, goal], goal);
            return (done(s), learned);
        }
        let k = k_for(self.k, n.max(2));
        let from_start = self.attach(checker, start, k, &mut learned.connector_tests);
        let to_goal = self.attach(checker, goal, k, &mut learned.connector_tests);
        if from_start.is_empty() || to_goal.is_empty() {
            return (done(Solution::failed(Status::Timeout, 0, n, 0)), learned);
        }
        let mut graph = QueryGraph::new(self, (start, from_start), (goal, to_goal));
        let (s, g) = (graph.s, graph.g);
        let mut connectors_free: HashSet<(u32, u32)> = HashSet::new();
        loop {
            let heuristic = |v| distance_m(graph.point(v), goal);
            let Some((nodes, _)) = astar(&graph.adjacency, s, g, heuristic) else {
                return (done(Solution::failed(Status::Timeout, 0, n, 0)), learned);
            };
            let checked = self.first_blocked_edge(
                checker,
                &graph,
                &nodes,
                &mut connectors_free,
                &mut learned,
            );
            let Some(((a, b), connector)) = checked else {
                let path = nodes.into_iter().map(|v| graph.point(v)).collect();
                return (
                    done(Solution::with_path(Status::Exact, path, goal)),
                    learned,
                );
            };
            graph.adjacency[a as usize].retain(|&(w, _)| w != b);
            graph.adjacency[b as usize].retain(|&(w, _)| w != a);
            if !connector {
                learned.blocked.push((a, b));
            }
        }
    }

    /// The vertices an end `p` joins, with the distances. Eager: up to k free vertices among its
    /// 3k nearest (checked, each test counted in `tests`). Lazy: its k nearest, unchecked.
    fn attach(
        &self,
        checker: &impl CollisionChecker,
        p: Neu,
        k: usize,
        tests: &mut usize,
    ) -> Vec<(u32, f64)> {
        if self.lazy {
            return self
                .nearest(p, k)
                .into_iter()
                .map(|v| (v, distance_m(p, self.vertices[v as usize])))
                .collect();
        }
        self.nearest(p, 3 * k)
            .into_iter()
            .filter(|&v| {
                *tests += 1;
                checker.segment_is_free(p, self.vertices[v as usize])
            })
            .take(k)
            .map(|v| (v, distance_m(p, self.vertices[v as usize])))
            .collect()
    }

    /// Checks the path's unchecked edges in order (what is learned goes in `connectors_free`
    /// and `learned`); the first blocked one and whether it is a connector, if any.
    fn first_blocked_edge(
        &self,
        checker: &impl CollisionChecker,
        graph: &QueryGraph,
        nodes: &[u32],
        connectors_free: &mut HashSet<(u32, u32)>,
        learned: &mut Learned,
    ) -> Option<((u32, u32), bool)> {
        for w in nodes.windows(2) {
            let e = (w[0].min(w[1]), w[0].max(w[1]));
            let connector = e.1 >= graph.s;
            let unchecked = if connector {
                self.lazy && !connectors_free.contains(&e)
            } else {
                self.unchecked.contains(&e) && !learned.free.contains(&e)
            };
            if !unchecked {
                continue;
            }
            if connector {
                learned.connector_tests += 1;
            } else {
                learned.tested += 1;
            }
            if checker.segment_is_free(graph.point(e.0), graph.point(e.1)) {
                if connector {
                    connectors_free.insert(e);
                } else {
                    learned.free.insert(e);
                }
            } else {
                return Some((e, connector));
            }
        }
        None
    }
}

/// The roadmap with a query's ends joined: nodes n (start) and n + 1 (goal) on a copy of the
/// adjacency lists.
struct QueryGraph<'r> {
    vertices: &'r [Neu],
    adjacency: Vec<Vec<(u32, f64)>>,
    start: Neu,
    goal: Neu,
    /// The start's and the goal's node.
    s: u32,
    g: u32,
}

impl<'r> QueryGraph<'r> {
    /// Joins the start and the goal, each with the vertices it attaches to and the distances.
    fn new(
        roadmap: &'r Roadmap,
        (start, from_start): (Neu, Vec<(u32, f64)>),
        (goal, to_goal): (Neu, Vec<(u32, f64)>),
    ) -> Self {
        let n = roadmap.vertices.len();
        let (s, g) = (n as u32, n as u32 + 1);
        let mut adjacency = roadmap.adjacency.clone();
        for &(v, d) in &from_start {
            adjacency[v as usize].push((s, d));
        }
        for &(v, d) in &to_goal {
            adjacency[v as usize].push((g, d));
        }
        adjacency.push(from_start);
        adjacency.push(to_goal);
        QueryGraph {
            vertices: &roadmap.vertices,
            adjacency,
            start,
            goal,
            s,
            g,
        }
    }

    /// A node's point.
    fn point(&self, v: u32) -> Neu {
        match v {
            v if v == self.s => self.start,
            v if v == self.g => self.goal,
            v => self.vertices[v as usize],
        }
    }
}

/// What one lazy search learned about the roadmap's unchecked edges.
#[derive(Debug, Default)]
struct Learned {
    free: HashSet<(u32, u32)>,
    blocked: Vec<(u32, u32)>,
    tested: usize,
    connector_tests: usize,
}

/// Builds a roadmap, queries it, and while the query fails grows the roadmap by half its size
/// until it succeeds or the budget is spent (an iteration is one sample). With `config.lazy`,
/// Lazy PRM: edges are checked only on found paths ([`Roadmap::query_lazy`]).
pub fn solve(
    checker: &impl CollisionChecker,
    start: Neu,
    goal: Neu,
    config: &PrmConfig,
    budget: Budget,
) -> (Roadmap, Solution) {
    let roadmap = Roadmap::build(
        checker,
        &PrmConfig {
            samples: 0,
            ..*config
        },
    );
    solve_from(checker, roadmap, start, goal, config.samples.max(1), budget)
}

/// [`solve`] on an existing roadmap (built earlier or loaded): first grows it by `first_batch`
/// samples (0: queries it as it is), then while the query fails by half its size, until the
/// query succeeds or the budget is spent.
pub fn solve_from(
    checker: &impl CollisionChecker,
    mut roadmap: Roadmap,
    start: Neu,
    goal: Neu,
    first_batch: usize,
    budget: Budget,
) -> (Roadmap, Solution) {
    let mut clock = Clock::start(budget);
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
    let mut batch = first_batch;
    loop {
        let mut granted = 0;
        while granted < batch && clock.tick() {
            granted += 1;
        }
        if granted > 0 {
            roadmap.grow(checker, granted);
        }
        let s = roadmap.query_lazy(checker, start, goal);
        if s.status == Status::Exact || granted < batch {
            let s = finish(s, &clock, &roadmap);
            return (roadmap, s);
        }
        batch = (roadmap.vertices.len() / 2).max(1);
    }
}

/// What a saved roadmap was built for: the world's margin, flight volume and boxes. A roadmap
/// is only valid for the world it was checked against; [`Roadmap::from_json`] refuses others.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorldFingerprint {
    /// The safety margin the boxes were grown by, metres.
    pub safety_m: f64,
    /// The flight volume's lowest corner `[north, east, alt]`, metres.
    pub bounds_min: Neu,
    /// The flight volume's highest corner, metres.
    pub bounds_max: Neu,
    /// Number of boxes.
    pub boxes: usize,
    /// FNV-1a (64 bits, hexadecimal) of the grown boxes' coordinates, then the grown prisms'
    /// bounding boxes and rings, bit for bit.
    pub boxes_fnv1a: String,
}

impl WorldFingerprint {
    /// The fingerprint of a box world.
    pub fn of(world: &BoxWorld3) -> Self {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut add = |v: f64| {
            for byte in v.to_bits().to_le_bytes() {
                h ^= u64::from(byte);
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        for b in world.inflated_boxes() {
            b.min.iter().chain(b.max.iter()).for_each(|&v| add(v));
        }
        // Footprint prisms (none on a colliders map, whose hash stays as it was).
        for p in world.prisms() {
            let b = p.bbox();
            b.min.iter().chain(b.max.iter()).for_each(|&v| add(v));
            p.rings().iter().flatten().flatten().for_each(|&v| add(v));
        }
        let bounds = world.bounds();
        Self {
            safety_m: world.spec().safety_m,
            bounds_min: bounds.min,
            bounds_max: bounds.max,
            boxes: world.inflated_boxes().len(),
            boxes_fnv1a: format!("{h:016x}"),
        }
    }

    /// Why a roadmap built for `self` does not fit `other` (`None`: it fits).
    fn mismatch(&self, other: &Self) -> Option<String> {
        if self.safety_m.to_bits() != other.safety_m.to_bits() {
            return Some(format!(
                "a safety margin of {} m, not {} m",
                self.safety_m, other.safety_m
            ));
        }
        if self.boxes != other.boxes || self.boxes_fnv1a != other.boxes_fnv1a {
            return Some(format!(
                "another map ({} boxes, hash {}; this map: {} boxes, hash {})",
                self.boxes, self.boxes_fnv1a, other.boxes, other.boxes_fnv1a
            ));
        }
        if self.bounds_min != other.bounds_min || self.bounds_max != other.bounds_max {
            let fmt = |a: Neu| format!("[{}, {}, {}]", a[0], a[1], a[2]);
            return Some(format!(
                "another flight volume ({} to {}; this one: {} to {})",
                fmt(self.bounds_min),
                fmt(self.bounds_max),
                fmt(other.bounds_min),
                fmt(other.bounds_max)
            ));
        }
        None
    }
}

/// Why a saved roadmap cannot be loaded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RoadmapFileError {
    /// Not JSON of the expected shape.
    #[error("not a skyplan roadmap: {0}")]
    Parse(String),
    /// A format or version this build does not read.
    #[error("roadmap format {found:?} version {version}; expected {FORMAT:?} version {VERSION}")]
    Version {
        /// The `format` field found.
        found: String,
        /// The `version` field found.
        version: u32,
    },
    /// Built for another world (margin, map or flight volume).
    #[error("the roadmap was built for {0}")]
    OtherWorld(String),
    /// Inconsistent contents (indices out of range, one-sided edges, non-finite points).
    #[error("invalid roadmap: {0}")]
    Invalid(String),
}

const FORMAT: &str = "skyplan-roadmap";
const VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
struct SavedStats {
    draws: usize,
    edge_checks: usize,
    edges_tested: usize,
    edges_removed: usize,
    connector_tests: usize,
    build_us: u64,
}

/// The file: adjacency lists in their exact order, so a loaded roadmap answers every query
/// exactly as the saved one did.
#[derive(Serialize, Deserialize)]
struct SavedRoadmap {
    format: String,
    version: u32,
    world: WorldFingerprint,
    k: usize,
    seed: u64,
    lazy: bool,
    max_draws_per_sample: usize,
    /// The sampler's position (ChaCha8 word position, decimal), so a loaded roadmap grows on
    /// with the samples the saved one would have drawn.
    rng_word_pos: String,
    stats: SavedStats,
    vertices: Vec<Neu>,
    neighbours: Vec<Vec<u32>>,
    /// Lazy PRM: edges `[a, b]` (`a < b`) not checked yet.
    unchecked: Vec<[u32; 2]>,
}

impl Roadmap {
    /// The roadmap as compact JSON (bit-exact floats), with the fingerprint of the world it was
    /// built in, its parameters and the sampler's state. No I/O.
    pub fn to_json(&self, world: &BoxWorld3) -> Vec<u8> {
        let mut unchecked: Vec<[u32; 2]> = self.unchecked.iter().map(|&(a, b)| [a, b]).collect();
        unchecked.sort_unstable();
        let saved = SavedRoadmap {
            format: FORMAT.to_string(),
            version: VERSION,
            world: WorldFingerprint::of(world),
            k: self.k,
            seed: self.seed,
            lazy: self.lazy,
            max_draws_per_sample: self.max_draws_per_sample,
            rng_word_pos: self.rng.get_word_pos().to_string(),
            stats: SavedStats {
                draws: self.stats.draws,
                edge_checks: self.stats.edge_checks,
                edges_tested: self.stats.edges_tested,
                edges_removed: self.stats.edges_removed,
                connector_tests: self.stats.connector_tests,
                build_us: self.stats.build_us,
            },
            vertices: self.vertices.clone(),
            neighbours: self
                .adjacency
                .iter()
                .map(|l| l.iter().map(|&(w, _)| w).collect())
                .collect(),
            unchecked,
        };
        // Serialising plain numbers, strings and vectors cannot fail.
        serde_json::to_vec(&saved).unwrap_or_default()
    }

    /// Loads a roadmap saved by [`Roadmap::to_json`], refusing one built for another world
    /// (margin, boxes or flight volume) or with inconsistent contents. No I/O.
    pub fn from_json(bytes: &[u8], world: &BoxWorld3) -> Result<Self, RoadmapFileError> {
        let saved: SavedRoadmap =
            serde_json::from_slice(bytes).map_err(|e| RoadmapFileError::Parse(e.to_string()))?;
        if saved.format != FORMAT || saved.version != VERSION {
            return Err(RoadmapFileError::Version {
                found: saved.format,
                version: saved.version,
            });
        }
        if let Some(why) = saved.world.mismatch(&WorldFingerprint::of(world)) {
            return Err(RoadmapFileError::OtherWorld(why));
        }
        let invalid = |m: String| Err(RoadmapFileError::Invalid(m));
        let n = saved.vertices.len();
        if saved.neighbours.len() != n {
            return invalid(format!(
                "{} vertices but {} neighbour lists",
                n,
                saved.neighbours.len()
            ));
        }
        if n > u32::MAX as usize - 2 {
            return invalid(format!("{n} vertices: too many"));
        }
        if let Some(i) = saved
            .vertices
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite()))
        {
            return invalid(format!("vertex {i} is not finite"));
        }
        let mut directed: HashSet<(u32, u32)> = HashSet::new();
        for (a, list) in saved.neighbours.iter().enumerate() {
            for &b in list {
                if b as usize >= n || b as usize == a {
                    return invalid(format!("vertex {a}: neighbour {b} out of range"));
                }
                if !directed.insert((a as u32, b)) {
                    return invalid(format!("vertex {a}: neighbour {b} listed twice"));
                }
            }
        }
        if let Some(&(a, b)) = directed.iter().find(|&&(a, b)| !directed.contains(&(b, a))) {
            return invalid(format!("edge {a}–{b} is listed on one side only"));
        }
        let mut unchecked = HashSet::new();
        for &[a, b] in &saved.unchecked {
            if a >= b || !directed.contains(&(a, b)) {
                return invalid(format!("unchecked edge {a}–{b} is not an edge"));
            }
            unchecked.insert((a, b));
        }
        if !saved.lazy && !unchecked.is_empty() {
            return invalid("unchecked edges in an eager roadmap".to_string());
        }
        let Ok(word_pos) = saved.rng_word_pos.parse::<u128>() else {
            return invalid(format!("rng_word_pos {:?}", saved.rng_word_pos));
        };
        let mut rng = ChaCha8Rng::seed_from_u64(saved.seed);
        rng.set_word_pos(word_pos);
        let vertices = saved.vertices;
        let adjacency = saved
            .neighbours
            .iter()
            .enumerate()
            .map(|(a, list)| {
                list.iter()
                    .map(|&b| (b, distance_m(vertices[a], vertices[b as usize])))
                    .collect()
            })
            .collect();
        let st = saved.stats;
        let mut roadmap = Self {
            vertices,
            adjacency,
            tree: ImmutableKdTree::default(),
            k: saved.k,
            seed: saved.seed,
            rng,
            max_draws_per_sample: saved.max_draws_per_sample.max(1),
            lazy: saved.lazy,
            unchecked,
            stats: BuildStats {
                draws: st.draws,
                edge_checks: st.edge_checks,
                edges_tested: st.edges_tested,
                edges_removed: st.edges_removed,
                connector_tests: st.connector_tests,
                build_us: st.build_us,
            },
        };
        roadmap.rebuild_tree();
        Ok(roadmap)
    }
}
