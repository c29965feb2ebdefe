//! Voronoi roadmaps for skyplan at one flight altitude.
//!
//! The roadmap is built from the obstacles' *geometry*, not their centres: the footprint of every
//! box that counts at the altitude (grown by the safety margin, exactly as the occupancy grid does)
//! is sampled along its boundary ([`boundary_sites`]), and the Voronoi diagram of those samples
//! (the dual of their Delaunay triangulation, computed with `spade`) approximates the medial axis
//! of the free space. Only Voronoi vertices in free cells and Voronoi edges that pass the exact
//! segment test [`Grid2::segment_is_free_ne`] with [`Touch::Closed`] are kept.
//!
//! A query ([`Roadmap::query`]) links the start and the goal to several candidate nodes through
//! connectors that are themselves checked, runs A\* with a binary heap over the graph (the direct
//! segment is an edge too when it is free), shortens the route greedily with checked segments,
//! and falls back to Jump Point Search on the grid when the graph cannot connect the two, saying
//! so in [`Route::fallback`]. Every segment of a returned route is free under the same exact test.
//!
//! ```
//! use skyplan_cspace::{Grid2, Touch};
//! use skyplan_roadmap::{Roadmap, RoadmapSpec, grid_boundary_sites};
//! // A 30 × 30 grid with a wall in the middle and a gap at the top.
//! let mut rows = vec![".".repeat(30); 30];
//! for r in 0..24 { rows[r].replace_range(14..16, "##"); }
//! let grid = Grid2::from_ascii(&rows.join("\n"))?;
//! let roadmap = Roadmap::from_sites(&grid, &grid_boundary_sites(&grid), &RoadmapSpec::default());
//! assert!(roadmap.component_count() >= 1);
//! let route = roadmap.query(&grid, [5.5, 5.5], [5.5, 25.5])?;
//! assert_eq!(route.points_ne.first(), Some(&[5.5, 5.5]));
//! assert_eq!(route.points_ne.last(), Some(&[5.5, 25.5]));
//! for w in route.points_ne.windows(2) {
//!     assert!(grid.segment_is_free_ne((w[0][0], w[0][1]), (w[1][0], w[1][1]), Touch::Closed));
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use skyplan_cspace::{Cell, Grid2, Touch};
use skyplan_map::colliders::CollidersMap;
use skyplan_search::{GridSearch, MoveModel, OpenEntry, OpenList, Planner};
use spade::{DelaunayTriangulation, Point2, Triangulation};
use std::collections::HashMap;
use std::time::Instant;

/// A local `[north_m, east_m]` point.
pub type Ne = [f64; 2];

/// How a roadmap is built and queried.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoadmapSpec {
    /// Largest distance between two boundary samples of an obstacle footprint, metres.
    pub sample_spacing_m: f64,
    /// How many free connectors to graph nodes are kept for the start and for the goal.
    pub candidates: usize,
    /// How many of the nearest nodes are tried to find those connectors.
    pub max_tries: usize,
}

impl Default for RoadmapSpec {
    /// 2 m samples, 8 connectors per end out of the 64 nearest nodes.
    fn default() -> Self {
        Self {
            sample_spacing_m: 2.0,
            candidates: 8,
            max_tries: 64,
        }
    }
}

/// Counts from building a roadmap.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BuildStats {
    /// Voronoi sites (boundary samples).
    pub sites: usize,
    /// Inner Delaunay triangles (= finite Voronoi vertices, before merging).
    pub triangles: usize,
    /// Finite Voronoi edges considered.
    pub voronoi_edges: usize,
    /// Voronoi edges dropped because a point of them is not free.
    pub dropped_edges: usize,
    /// Build time, microseconds.
    pub build_us: u64,
}

/// A Voronoi roadmap: nodes in free space, every edge exactly free.
#[derive(Debug, Clone)]
pub struct Roadmap {
    nodes: Vec<Ne>,
    adj_start: Vec<u32>,
    adj: Vec<(u32, f64)>,
    component: Vec<u32>,
    component_sizes: Vec<usize>,
    spec: RoadmapSpec,
    stats: BuildStats,
}

/// Why a query failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RoadmapError {
    /// The start is off the grid or in a blocked cell.
    #[error("the start (N {0:.2}, E {1:.2}) is off the map or inside an obstacle's margin")]
    StartBlocked(f64, f64),
    /// The goal is off the grid or in a blocked cell.
    #[error("the goal (N {0:.2}, E {1:.2}) is off the map or inside an obstacle's margin")]
    GoalBlocked(f64, f64),
    /// Neither the graph nor the grid connects start and goal.
    #[error("no path: neither the Voronoi graph nor the grid connects start and goal")]
    NoPath,
}

/// A route from a query.
#[derive(Debug, Clone, PartialEq)]
pub struct Route {
    /// The waypoints, exactly the start first and exactly the goal last.
    pub points_ne: Vec<Ne>,
    /// Length of the polyline, metres.
    pub cost_m: f64,
    /// Length before the greedy shortcut, metres.
    pub graph_cost_m: f64,
    /// The route before the greedy shortcut: start, connector, graph nodes, connector, goal (or
    /// the JPS cells on a fallback). Its length is `graph_cost_m`.
    pub raw_ne: Vec<Ne>,
    /// `None` when the route runs on the Voronoi graph; otherwise why the grid (JPS) was used.
    pub fallback: Option<String>,
    /// Checked connectors from the start / to the goal that were kept.
    pub connectors: (usize, usize),
    /// Graph nodes expanded by A\*.
    pub expansions: usize,
}

fn dist(a: Ne, b: Ne) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Length of a polyline, metres.
///
/// ```
/// assert_eq!(skyplan_roadmap::polyline_length_m(&[[0.0, 0.0], [3.0, 4.0], [3.0, 5.0]]), 6.0);
/// ```
pub fn polyline_length_m(points: &[Ne]) -> f64 {
    points.windows(2).map(|w| dist(w[0], w[1])).sum()
}

fn free(grid: &Grid2, a: Ne, b: Ne) -> bool {
    grid.segment_is_free_ne((a[0], a[1]), (b[0], b[1]), Touch::Closed)
}

fn point_free(grid: &Grid2, p: Ne) -> bool {
    grid.cell_at_ne(p[0], p[1])
        .is_some_and(|c| !grid.is_blocked(c))
}

/// The index of the first segment of `points` that is not exactly free on `grid`
/// ([`Touch::Closed`]), or `None`. A single point is checked as a point.
///
/// ```
/// use skyplan_cspace::Grid2;
/// let grid = Grid2::from_ascii("...\n.#.\n...")?;
/// assert_eq!(skyplan_roadmap::first_blocked_segment(&grid, &[[0.5, 0.5], [0.5, 2.5], [2.5, 2.5]]), None);
/// assert_eq!(skyplan_roadmap::first_blocked_segment(&grid, &[[0.5, 0.5], [2.5, 2.5]]), Some(0));
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn first_blocked_segment(grid: &Grid2, points: &[Ne]) -> Option<usize> {
    if let [p] = points {
        return (!point_free(grid, *p)).then_some(0);
    }
    points.windows(2).position(|w| !free(grid, w[0], w[1]))
}

/// Samples of the boundaries of the footprints that block the grid at `alt_m`: every box whose
/// vertical extent grown by `safety_m` contains the altitude, grown horizontally by `safety_m`,
/// sampled every `spacing_m` or closer (corners included). Samples buried inside other footprints
/// (no free cell among the 3 × 3 cells around them) are dropped; the grid's outer edge is sampled
/// too, so the diagram stays inside the map.
///
/// ```
/// use skyplan_cspace::{Grid2, GridSpec};
/// let text = "lat0 37.79, lon0 -122.39\n10,10,5,2,2,5\n30,30,5,2,2,5\n0,0,1,1,1,1\n";
/// let map = skyplan_map::colliders::parse_colliders(text).unwrap();
/// let spec = GridSpec { alt_m: 5.0, safety_m: 1.0, cell_m: 1.0 };
/// let grid = Grid2::from_colliders(&map, spec)?;
/// let sites = skyplan_roadmap::boundary_sites(&map, &grid, 5.0, 1.0, 2.0);
/// assert!(sites.contains(&[7.0, 7.0]) && sites.contains(&[13.0, 13.0])); // grown corners
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn boundary_sites(
    map: &CollidersMap,
    grid: &Grid2,
    alt_m: f64,
    safety_m: f64,
    spacing_m: f64,
) -> Vec<Ne> {
    let spacing_m = if spacing_m.is_finite() && spacing_m > 0.0 {
        spacing_m
    } else {
        RoadmapSpec::default().sample_spacing_m
    };
    let mut sites = Vec::new();
    let near_free = |p: Ne| {
        let f = grid.frame();
        let r = ((p[0] - f.origin_north_m) / f.cell_m).floor() as i64;
        let c = ((p[1] - f.origin_east_m) / f.cell_m).floor() as i64;
        (-1..=1).any(|dr| (-1..=1).any(|dc| grid.is_free_at(r + dr, c + dc)))
    };
    for b in &map.boxes {
        if !b.meets_altitude(alt_m, safety_m) {
            continue;
        }
        let (lo, hi) = b.grown(safety_m);
        rectangle_samples([lo[0], lo[1]], [hi[0], hi[1]], spacing_m, |p| {
            if near_free(p) {
                sites.push(p);
            }
        });
    }
    sites.extend(frame_sites(grid, spacing_m));
    sites
}

fn rectangle_samples(lo: Ne, hi: Ne, spacing_m: f64, mut emit: impl FnMut(Ne)) {
    let corners = [lo, [lo[0], hi[1]], hi, [hi[0], lo[1]]];
    for k in 0..4 {
        let (a, b) = (corners[k], corners[(k + 1) % 4]);
        let n = (dist(a, b) / spacing_m).ceil().max(1.0) as usize;
        for i in 0..n {
            let t = i as f64 / n as f64;
            emit([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]);
        }
    }
}

fn frame_sites(grid: &Grid2, spacing_m: f64) -> Vec<Ne> {
    let f = grid.frame();
    let lo = [f.origin_north_m, f.origin_east_m];
    let hi = [
        lo[0] + f64::from(grid.rows()) * f.cell_m,
        lo[1] + f64::from(grid.cols()) * f.cell_m,
    ];
    let mut out = Vec::new();
    rectangle_samples(lo, hi, spacing_m, |p| out.push(p));
    out
}

/// Sites for any grid (image maps, random grids): the centres of blocked cells that have a free
/// 4-neighbour, plus samples of the grid's outer edge every cell.
///
/// ```
/// let grid = skyplan_cspace::Grid2::from_ascii("....\n.##.\n....")?;
/// let sites = skyplan_roadmap::grid_boundary_sites(&grid);
/// assert!(sites.contains(&[1.5, 1.5]) && sites.contains(&[1.5, 2.5]));
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn grid_boundary_sites(grid: &Grid2) -> Vec<Ne> {
    let mut sites = Vec::new();
    for i in 0..grid.len() {
        let c = grid.cell(i);
        if !grid.is_blocked(c) {
            continue;
        }
        let (r, k) = (i64::from(c.row), i64::from(c.col));
        if [(1, 0), (-1, 0), (0, 1), (0, -1)]
            .iter()
            .any(|(dr, dc)| grid.is_free_at(r + dr, k + dc))
        {
            let (n, e) = grid.center_ne(c);
            sites.push([n, e]);
        }
    }
    sites.extend(frame_sites(grid, grid.frame().cell_m));
    sites
}

/// The Delaunay triangulation of the sites, deduplicated (the triangulation would merge them
/// anyway) and without the non-finite ones.
fn triangulate(sites: &[Ne], stats: &mut BuildStats) -> DelaunayTriangulation<Point2<f64>> {
    let mut seen = HashMap::new();
    let points: Vec<Point2<f64>> = sites
        .iter()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
        .filter(|p| seen.insert(key(**p), ()).is_none())
        .map(|p| Point2::new(p[0], p[1]))
        .collect();
    stats.sites = points.len();
    let triangulation: DelaunayTriangulation<Point2<f64>> =
        Triangulation::bulk_load(points).unwrap_or_default();
    stats.triangles = triangulation.num_inner_faces();
    triangulation
}

/// The Voronoi vertices in free cells: the node of each face (by face index; `None` for a
/// blocked circumcentre) and the nodes, merged by position.
fn voronoi_nodes(
    grid: &Grid2,
    triangulation: &DelaunayTriangulation<Point2<f64>>,
) -> (Vec<Option<u32>>, Vec<Ne>) {
    let mut node_of_face: Vec<Option<u32>> = vec![None; triangulation.num_all_faces()];
    let mut ids: HashMap<(i64, i64), u32> = HashMap::new();
    let mut nodes: Vec<Ne> = Vec::new();
    for face in triangulation.inner_faces() {
        let c = face.circumcenter();
        let p = [c.x, c.y];
        if !(p[0].is_finite() && p[1].is_finite() && point_free(grid, p)) {
            continue;
        }
        let id = *ids.entry(key(p)).or_insert_with(|| {
            nodes.push(p);
            (nodes.len() - 1) as u32
        });
        node_of_face[face.fix().index()] = Some(id);
    }
    (node_of_face, nodes)
}

/// The Voronoi edges between free nodes that are exactly free, once each, with their lengths.
fn voronoi_edges(
    grid: &Grid2,
    triangulation: &DelaunayTriangulation<Point2<f64>>,
    node_of_face: &[Option<u32>],
    nodes: &[Ne],
    stats: &mut BuildStats,
) -> Vec<(u32, u32, f64)> {
    let mut edges: Vec<(u32, u32, f64)> = Vec::new();
    let mut edge_seen: HashMap<(u32, u32), ()> = HashMap::new();
    for e in triangulation.undirected_edges() {
        let d = e.as_directed();
        let (Some(f1), Some(f2)) = (d.face().as_inner(), d.rev().face().as_inner()) else {
            continue;
        };
        stats.voronoi_edges += 1;
        let (Some(a), Some(b)) = (
            node_of_face[f1.fix().index()],
            node_of_face[f2.fix().index()],
        ) else {
            stats.dropped_edges += 1;
            continue;
        };
        if a == b {
            continue;
        }
        let k = (a.min(b), a.max(b));
        if edge_seen.contains_key(&k) {
            continue;
        }
        if !free(grid, nodes[a as usize], nodes[b as usize]) {
            stats.dropped_edges += 1;
            continue;
        }
        edge_seen.insert(k, ());
        edges.push((k.0, k.1, dist(nodes[a as usize], nodes[b as usize])));
    }
    edges
}

/// The adjacency of `n` nodes in compressed rows: where each node's neighbours start (n + 1
/// entries) and the (neighbour, length) pairs, each edge in both directions in edge order.
fn adjacency(n: usize, edges: &[(u32, u32, f64)]) -> (Vec<u32>, Vec<(u32, f64)>) {
    let mut degree = vec![0u32; n + 1];
    for &(a, b, _) in edges {
        degree[a as usize] += 1;
        degree[b as usize] += 1;
    }
    let mut adj_start = vec![0u32; n + 1];
    for i in 0..n {
        adj_start[i + 1] = adj_start[i] + degree[i];
    }
    let mut fill = adj_start.clone();
    let mut adj = vec![(0u32, 0.0); edges.len() * 2];
    for &(a, b, w) in edges {
        adj[fill[a as usize] as usize] = (b, w);
        fill[a as usize] += 1;
        adj[fill[b as usize] as usize] = (a, w);
        fill[b as usize] += 1;
    }
    (adj_start, adj)
}

/// The connected components of `n` nodes (union-find): each node's label, labels numbered in
/// the order of their lowest node, and each component's size.
fn components(n: usize, edges: &[(u32, u32, f64)]) -> (Vec<u32>, Vec<usize>) {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for &(a, b, _) in edges {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut label_of_root: HashMap<u32, u32> = HashMap::new();
    let mut component = vec![0u32; n];
    let mut component_sizes = Vec::new();
    for (v, slot) in component.iter_mut().enumerate() {
        let root = find(&mut parent, v as u32);
        let label = *label_of_root.entry(root).or_insert_with(|| {
            component_sizes.push(0);
            (component_sizes.len() - 1) as u32
        });
        component_sizes[label as usize] += 1;
        *slot = label;
    }
    (component, component_sizes)
}

impl Roadmap {
    /// The roadmap of a colliders map at `alt_m` on its grid (built by
    /// `Grid2::from_colliders` with the same altitude and margin): [`boundary_sites`], then
    /// [`Roadmap::from_sites`].
    pub fn build(
        map: &CollidersMap,
        grid: &Grid2,
        alt_m: f64,
        safety_m: f64,
        spec: &RoadmapSpec,
    ) -> Self {
        let t = Instant::now();
        let sites = boundary_sites(map, grid, alt_m, safety_m, spec.sample_spacing_m);
        let mut r = Self::from_sites(grid, &sites, spec);
        r.stats.build_us = t.elapsed().as_micros() as u64;
        r
    }

    /// The Voronoi roadmap of `sites` restricted to the free space of `grid`: Voronoi vertices
    /// (circumcentres of the Delaunay triangles) in free cells, merged when equal to 1 µm, joined
    /// by the Voronoi edges that are exactly free; nodes without edges are dropped.
    pub fn from_sites(grid: &Grid2, sites: &[Ne], spec: &RoadmapSpec) -> Self {
        let t = Instant::now();
        let mut stats = BuildStats::default();
        let triangulation = triangulate(sites, &mut stats);
        let (node_of_face, nodes) = voronoi_nodes(grid, &triangulation);
        let edges = voronoi_edges(grid, &triangulation, &node_of_face, &nodes, &mut stats);
        // Keep only nodes with an edge, renumbered.
        let mut new_id = vec![u32::MAX; nodes.len()];
        let mut kept = Vec::new();
        for &(a, b, _) in &edges {
            for v in [a, b] {
                if new_id[v as usize] == u32::MAX {
                    new_id[v as usize] = kept.len() as u32;
                    kept.push(nodes[v as usize]);
                }
            }
        }
        let edges: Vec<(u32, u32, f64)> = edges
            .into_iter()
            .map(|(a, b, w)| (new_id[a as usize], new_id[b as usize], w))
            .collect();
        let (adj_start, adj) = adjacency(kept.len(), &edges);
        let (component, component_sizes) = components(kept.len(), &edges);
        stats.build_us = t.elapsed().as_micros() as u64;
        Self {
            nodes: kept,
            adj_start,
            adj,
            component,
            component_sizes,
            spec: *spec,
            stats,
        }
    }

    /// The nodes, `[north_m, east_m]`.
    pub fn nodes(&self) -> &[Ne] {
        &self.nodes
    }

    /// Every edge once, as its two end points.
    pub fn edges(&self) -> impl Iterator<Item = (Ne, Ne)> + '_ {
        (0..self.nodes.len()).flat_map(move |a| {
            self.neighbours(a as u32)
                .iter()
                .filter(move |&&(b, _)| (b as usize) > a)
                .map(move |&(b, _)| (self.nodes[a], self.nodes[b as usize]))
        })
    }

    /// Number of edges.
    pub fn edge_count(&self) -> usize {
        self.adj.len() / 2
    }

    /// Number of connected components of the graph.
    pub fn component_count(&self) -> usize {
        self.component_sizes.len()
    }

    /// Nodes in the largest component.
    pub fn largest_component(&self) -> usize {
        self.component_sizes.iter().copied().max().unwrap_or(0)
    }

    /// What building it took.
    pub fn stats(&self) -> BuildStats {
        self.stats
    }

    fn neighbours(&self, v: u32) -> &[(u32, f64)] {
        &self.adj[self.adj_start[v as usize] as usize..self.adj_start[v as usize + 1] as usize]
    }

    /// Up to `spec.candidates` nodes joined to `p` by a free segment, among the `spec.max_tries`
    /// nearest; at most half of them from any one component while others are available, so a
    /// nearby fragment cannot crowd out the main graph.
    /// The graph nodes a query at `p` links to through checked connectors (the candidates
    /// [`Roadmap::query`] offers A\*); for pictures.
    pub fn connector_nodes(&self, grid: &Grid2, p: Ne) -> Vec<Ne> {
        if !point_free(grid, p) {
            return Vec::new();
        }
        self.connectors(grid, p)
            .into_iter()
            .map(|(v, _)| self.nodes[v as usize])
            .collect()
    }

    fn connectors(&self, grid: &Grid2, p: Ne) -> Vec<(u32, f64)> {
        let mut order: Vec<(f64, u32)> = self
            .nodes
            .iter()
            .enumerate()
            .map(|(i, &q)| (dist(p, q), i as u32))
            .collect();
        let tries = self.spec.max_tries.min(order.len());
        if tries == 0 {
            return Vec::new();
        }
        if tries < order.len() {
            order.select_nth_unstable_by(tries - 1, |a, b| a.0.total_cmp(&b.0));
            order.truncate(tries);
        }
        order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let want = self.spec.candidates.max(1);
        let per_component = want.div_ceil(2).max(1);
        let mut picked: Vec<(u32, f64)> = Vec::new();
        let mut skipped: Vec<(u32, f64)> = Vec::new();
        let mut count: HashMap<u32, usize> = HashMap::new();
        for (d, v) in order {
            if picked.len() >= want {
                break;
            }
            if !free(grid, p, self.nodes[v as usize]) {
                continue;
            }
            let c = count.entry(self.component[v as usize]).or_insert(0);
            if *c >= per_component {
                skipped.push((v, d));
                continue;
            }
            *c += 1;
            picked.push((v, d));
        }
        for s in skipped {
            if picked.len() >= want {
                break;
            }
            picked.push(s);
        }
        picked
    }

    /// A route from `start_ne` to `goal_ne` (local metres): checked connectors to several
    /// candidate nodes at each end, A\* over the graph (the direct segment counts when free),
    /// a greedy checked shortcut, and Jump Point Search on `grid` when the graph cannot connect
    /// them. Every segment of the result passes [`first_blocked_segment`].
    pub fn query(&self, grid: &Grid2, start_ne: Ne, goal_ne: Ne) -> Result<Route, RoadmapError> {
        if !point_free(grid, start_ne) {
            return Err(RoadmapError::StartBlocked(start_ne[0], start_ne[1]));
        }
        if !point_free(grid, goal_ne) {
            return Err(RoadmapError::GoalBlocked(goal_ne[0], goal_ne[1]));
        }
        let from_start = self.connectors(grid, start_ne);
        let to_goal = self.connectors(grid, goal_ne);
        let direct = free(grid, start_ne, goal_ne);
        let connectors = (from_start.len(), to_goal.len());
        let (graph_path, expansions) = self.astar(start_ne, goal_ne, &from_start, &to_goal, direct);
        let (raw, fallback) = match graph_path {
            Some(p) => (p, None),
            None => {
                let why = if from_start.is_empty() || to_goal.is_empty() {
                    format!(
                        "no free connector from the {} to the graph",
                        if from_start.is_empty() {
                            "start"
                        } else {
                            "goal"
                        }
                    )
                } else {
                    "the graph's components reached from start and goal differ".to_string()
                };
                match grid_route(grid, start_ne, goal_ne) {
                    Some(p) => (p, Some(format!("{why}; routed on the grid (JPS)"))),
                    None => return Err(RoadmapError::NoPath),
                }
            }
        };
        let graph_cost_m = polyline_length_m(&raw);
        let points_ne = shortcut(grid, &raw);
        debug_assert!(first_blocked_segment(grid, &points_ne).is_none());
        Ok(Route {
            cost_m: polyline_length_m(&points_ne),
            graph_cost_m,
            points_ne,
            raw_ne: raw,
            fallback,
            connectors,
            expansions,
        })
    }

    /// A\* over the graph plus a virtual start (`n`) and goal (`n + 1`).
    fn astar(
        &self,
        start: Ne,
        goal: Ne,
        from_start: &[(u32, f64)],
        to_goal: &[(u32, f64)],
        direct: bool,
    ) -> (Option<Vec<Ne>>, usize) {
        let n = self.nodes.len();
        let (s, g) = (n as u32, n as u32 + 1);
        let mut goal_link: HashMap<u32, f64> = HashMap::new();
        for &(v, d) in to_goal {
            goal_link.insert(v, d);
        }
        let pos = |v: u32| -> Ne {
            match v as usize {
                i if i < n => self.nodes[i],
                i if i == n => start,
                _ => goal,
            }
        };
        let mut best = vec![f64::INFINITY; n + 2];
        let mut parent = vec![u32::MAX; n + 2];
        let mut open = OpenList::new(n + 2);
        best[s as usize] = 0.0;
        open.push(OpenEntry {
            f: dist(start, goal),
            g: 0.0,
            node: s,
        });
        let mut relax = |open: &mut OpenList, from: u32, to: u32, g: f64| {
            if g < best[to as usize] {
                best[to as usize] = g;
                parent[to as usize] = from;
                open.push(OpenEntry {
                    f: g + dist(pos(to), goal),
                    g,
                    node: to,
                });
            }
        };
        while let Some(OpenEntry { g: gv, node, .. }) = open.pop() {
            if node == g {
                let mut path = vec![goal];
                let mut v = parent[g as usize];
                while v != s {
                    path.push(pos(v));
                    v = parent[v as usize];
                }
                path.push(start);
                path.reverse();
                return (Some(path), open.expansions() as usize);
            }
            if node == s {
                for &(v, d) in from_start {
                    relax(&mut open, s, v, d);
                }
                if direct {
                    relax(&mut open, s, g, dist(start, goal));
                }
                continue;
            }
            for &(v, w) in self.neighbours(node) {
                relax(&mut open, node, v, gv + w);
            }
            if let Some(&d) = goal_link.get(&node) {
                relax(&mut open, node, g, gv + d);
            }
        }
        (None, open.expansions() as usize)
    }
}

fn key(p: Ne) -> (i64, i64) {
    ((p[0] * 1e6).round() as i64, (p[1] * 1e6).round() as i64)
}

/// JPS on the grid (octile, no corner cutting) between the cells of two free points: the exact
/// start, the cell centres, the exact goal.
fn grid_route(grid: &Grid2, start: Ne, goal: Ne) -> Option<Vec<Ne>> {
    let a: Cell = grid.cell_at_ne(start[0], start[1])?;
    let b: Cell = grid.cell_at_ne(goal[0], goal[1])?;
    let path = GridSearch::new()
        .search(grid, a, b, MoveModel::Octile, Planner::Jps)
        .ok()?;
    let mut points = vec![start];
    points.extend(path.cells.iter().map(|&c| {
        let (n, e) = grid.center_ne(c);
        [n, e]
    }));
    points.push(goal);
    points.dedup();
    (first_blocked_segment(grid, &points).is_none()).then_some(points)
}

/// Greedy line-of-sight shortcut: from each kept point, go as far along the polyline as a free
/// segment reaches. Every new segment is checked exactly; the length never grows.
///
/// ```
/// let grid = skyplan_cspace::Grid2::from_ascii(&"....\n".repeat(4))?;
/// let p = skyplan_roadmap::shortcut(&grid, &[[0.5, 0.5], [0.5, 3.5], [3.5, 3.5]]);
/// assert_eq!(p, vec![[0.5, 0.5], [3.5, 3.5]]);
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn shortcut(grid: &Grid2, points: &[Ne]) -> Vec<Ne> {
    if points.len() <= 2 {
        return points.to_vec();
    }
    let mut out = vec![points[0]];
    let mut anchor = 0;
    let mut j = 1;
    while j < points.len() {
        // Extend while the segment anchor → j + 1 is free.
        while j + 1 < points.len() && free(grid, points[anchor], points[j + 1]) {
            j += 1;
        }
        out.push(points[j]);
        anchor = j;
        j += 1;
    }
    // A shortcut segment replaces a sub-polyline between the same points: never longer, but keep
    // the original if rounding made it so.
    if polyline_length_m(&out) <= polyline_length_m(points) {
        out
    } else {
        points.to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enclosed_goal_is_no_path() {
        let grid = Grid2::from_ascii("......\n.####.\n.#..#.\n.####.\n......").unwrap();
        let r = Roadmap::from_sites(&grid, &grid_boundary_sites(&grid), &RoadmapSpec::default());
        let (n, e) = grid.center_ne(Cell::new(2, 2));
        assert_eq!(
            r.query(&grid, [0.5, 0.5], [n, e]),
            Err(RoadmapError::NoPath)
        );
    }

    #[test]
    fn blocked_ends_are_refused() {
        let grid = Grid2::from_ascii("...\n.#.\n...").unwrap();
        let r = Roadmap::from_sites(&grid, &grid_boundary_sites(&grid), &RoadmapSpec::default());
        assert!(matches!(
            r.query(&grid, [1.5, 1.5], [0.5, 0.5]),
            Err(RoadmapError::StartBlocked(..))
        ));
        assert!(matches!(
            r.query(&grid, [0.5, 0.5], [9.5, 0.5]),
            Err(RoadmapError::GoalBlocked(..))
        ));
    }

    #[test]
    fn empty_graph_falls_back_to_the_grid() {
        let grid = Grid2::from_ascii("....\n.##.\n....").unwrap();
        let r = Roadmap::from_sites(&grid, &[], &RoadmapSpec::default());
        assert_eq!(r.component_count(), 0);
        let route = r.query(&grid, [0.5, 0.5], [2.5, 3.5]).unwrap();
        assert!(route.fallback.is_some());
        assert_eq!(first_blocked_segment(&grid, &route.points_ne), None);
    }
}
