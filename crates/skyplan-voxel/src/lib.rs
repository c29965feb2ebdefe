//! 2.5D / voxel planning for skyplan: a height map of the city and an exactly optimal
//! 26-connected A\* over a lattice of voxel centres, so a route may climb over low buildings when
//! that is cheaper than going around them.
//!
//! The lattice has a horizontal pitch `cell_m` and a vertical pitch `layer_m` (the altitude
//! layers); its points are the multiples of the pitches inside the world's flight volume (the
//! lowest layer is the lowest multiple of `layer_m` that is ≥ the floor and > 0). A lattice point
//! is usable iff it lies outside every inflated box of the [`BoxWorld3`]; an edge joins two
//! usable points that differ by at most one step on each axis (26 neighbours) and is usable iff
//! world3's exact segment test passes ([`CollisionChecker::segment_is_free`]). The start and the
//! goal join the lattice through the usable points within one step of them on every axis
//! (again exactly checked), and to each other directly when that segment is free.
//!
//! The cost of a segment is its 3D length plus `climb_weight` × the altitude it gains
//! ([`edge_cost`]), so climbing is paid for and descending is not. [`VoxelGrid::plan`] returns
//! the cheapest path in that graph (A\* with an admissible, consistent heuristic), checks every
//! edge of it again, and shortcuts it with exactly re-checked segments that never raise the cost.
//!
//! Checking all 26 edges of every voxel would cost tens of millions of segment tests on the city,
//! so the grid marks the voxels whose neighbourhood box (the lattice points one step away on every
//! axis, widened by 1 µm) meets no inflated box: every edge out of such a voxel lies inside that
//! box and is free without a test. Only the edges out of the other voxels are tested, lazily, when
//! the search reaches them.
//!
//! ```
//! use skyplan_map::colliders::ObstacleBox;
//! use skyplan_voxel::{Query, VoxelGrid, VoxelSpec};
//! use skyplan_world3::{BoxWorld3, CollisionChecker, WorldSpec, first_blocked_segment};
//! // A low, wide wall (10 m tall) across the way: around it is long, over it is short.
//! let wall = ObstacleBox { north_m: 50.0, east_m: 50.0, up_m: 5.0, half_north_m: 2.0, half_east_m: 45.0, half_up_m: 5.0 };
//! let spec = WorldSpec { safety_m: 2.0, min_alt_m: 0.0, max_alt_m: 40.0, margin_bounds_m: 45.0 };
//! let world = BoxWorld3::new(&[wall], &spec)?;
//! let grid = VoxelGrid::build(&world, &VoxelSpec { cell_m: 5.0, layer_m: 5.0 })?;
//! let query = Query { start: [10.0, 50.0, 5.0], goal: [90.0, 50.0, 5.0], climb_weight: 1.0, shortcut: true };
//! let route = grid.plan(&query)?;
//! assert_eq!(route.path.first(), Some(&query.start));
//! assert_eq!(route.path.last(), Some(&query.goal));
//! assert!(route.path.iter().any(|p| p[2] >= 15.0));            // it climbed over the wall
//! assert_eq!(first_blocked_segment(&world.brute_force(), &route.path), None);
//! assert!(route.cost <= route.raw_cost);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use skyplan_search::{OpenEntry, OpenList};
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, distance_m};
use std::time::Instant;

/// Slack added around a voxel's neighbourhood box before calling it clear of every inflated box,
/// metres: it keeps floating-point rounding in the slab test from ever disagreeing.
const CLEAR_SLACK_M: f64 = 1e-6;

/// Voxel states.
const CLEAR: u8 = 0;
const NEAR: u8 = 1;
const BLOCKED: u8 = 2;

/// The lattice's pitches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VoxelSpec {
    /// Horizontal pitch (north and east), metres (> 0).
    pub cell_m: f64,
    /// Vertical pitch between altitude layers, metres (> 0).
    pub layer_m: f64,
}

impl Default for VoxelSpec {
    /// 5 m horizontally, 5 m between layers.
    fn default() -> Self {
        Self {
            cell_m: 5.0,
            layer_m: 5.0,
        }
    }
}

/// Which end of a query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// The start.
    Start,
    /// The goal.
    Goal,
}

impl End {
    /// `"start"` or `"goal"`.
    pub fn name(self) -> &'static str {
        match self {
            End::Start => "start",
            End::Goal => "goal",
        }
    }
}

/// Why a grid could not be built or a query answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VoxelError {
    /// A pitch or weight is not a finite positive number, or the lattice would be empty or huge.
    #[error("invalid voxel spec: {0}")]
    InvalidSpec(String),
    /// The start or goal is not in free space (inside a grown box, under the floor or outside).
    #[error("the {} is not in free space", .0.name())]
    Invalid(End),
    /// No usable lattice point sees the start or goal within one step on every axis.
    #[error(
        "no free voxel centre within one voxel of the {} is reachable by a free segment",
        .0.name()
    )]
    NoConnector(End),
    /// The goal is not reachable from the start in the lattice graph.
    #[error("no path: the goal is unreachable in the voxel graph ({expansions} voxels reached)")]
    NoPath {
        /// Nodes expanded before the search ran out.
        expansions: usize,
    },
    /// A returned segment failed the final exact check (a bug).
    #[error("internal error: segment {0} of the voxel path failed the exact re-check")]
    Internal(usize),
}

/// The highest inflated-box top over each lattice column (the height map of the city, grown by
/// the margin), metres; the floor where no box covers the column.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightMap {
    /// Columns along north and east.
    pub dims: [usize; 2],
    /// Row-major (north index major) tops, metres.
    pub top_m: Vec<f64>,
}

impl HeightMap {
    /// The top over column `(i_north, j_east)`.
    pub fn top_m(&self, i_north: usize, j_east: usize) -> f64 {
        self.top_m[i_north * self.dims[1] + j_east]
    }
}

/// One query for [`VoxelGrid::plan`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Query {
    /// Start point `[north, east, alt]`.
    pub start: Neu,
    /// Goal point (may be above a roof).
    pub goal: Neu,
    /// Extra cost per metre of altitude gained (≥ 0); 0 minimises length alone.
    pub climb_weight: f64,
    /// Shortcut the lattice path with exactly re-checked segments (never more expensive).
    pub shortcut: bool,
}

/// A planned route.
#[derive(Debug, Clone, PartialEq)]
pub struct VoxelPath {
    /// The optimal lattice path: start, voxel centres, goal.
    pub raw: Vec<Neu>,
    /// The returned path (`raw` shortcut, or `raw` itself).
    pub path: Vec<Neu>,
    /// Cost of `raw` ([`path_cost`]): the optimum of the voxel graph.
    pub raw_cost: f64,
    /// Cost of `path` (≤ `raw_cost`).
    pub cost: f64,
    /// 3D length of `path`, metres.
    pub length_m: f64,
    /// Altitude gained along `path` (sum of the climbs), metres.
    pub climb_m: f64,
    /// Nodes expanded by A\*.
    pub expansions: usize,
    /// Exact segment tests made during the search.
    pub edge_checks: usize,
    /// Wall time of the search and post-processing, microseconds.
    pub search_us: u64,
}

/// Cost of the segment `a → b`: its length plus `climb_weight` × the altitude gained.
///
/// ```
/// assert_eq!(skyplan_voxel::edge_cost([0.0, 0.0, 0.0], [3.0, 0.0, 4.0], 2.0), 5.0 + 8.0);
/// assert_eq!(skyplan_voxel::edge_cost([3.0, 0.0, 4.0], [0.0, 0.0, 0.0], 2.0), 5.0);
/// ```
pub fn edge_cost(a: Neu, b: Neu, climb_weight: f64) -> f64 {
    distance_m(a, b) + climb_weight * (b[2] - a[2]).max(0.0)
}

/// Cost of a polyline: the sum of [`edge_cost`] over its segments.
pub fn path_cost(path: &[Neu], climb_weight: f64) -> f64 {
    path.windows(2)
        .map(|w| edge_cost(w[0], w[1], climb_weight))
        .sum()
}

/// The sum of the altitude gains along a polyline, metres.
pub fn climb_m(path: &[Neu]) -> f64 {
    path.windows(2).map(|w| (w[1][2] - w[0][2]).max(0.0)).sum()
}

/// The voxel lattice over a [`BoxWorld3`], with each voxel classified as blocked (its centre is
/// inside an inflated box), clear (no inflated box near it: its edges need no test) or near.
#[derive(Debug, Clone)]
pub struct VoxelGrid<'w> {
    world: &'w BoxWorld3,
    origin: Neu,
    step: Neu,
    dims: [usize; 3],
    state: Vec<u8>,
    heights: HeightMap,
    build_us: u64,
}

/// Most voxels a grid may have.
pub const MAX_VOXELS: usize = 50_000_000;

/// The 26 neighbour offsets, in the order of nested loops over north, east and altitude.
const OFFSETS: [[i64; 3]; 26] = offsets();

const fn offsets() -> [[i64; 3]; 26] {
    let mut out = [[0; 3]; 26];
    let mut n = 0;
    let mut a = -1;
    while a <= 1 {
        let mut b = -1;
        while b <= 1 {
            let mut c = -1;
            while c <= 1 {
                if !(a == 0 && b == 0 && c == 0) {
                    out[n] = [a, b, c];
                    n += 1;
                }
                c += 1;
            }
            b += 1;
        }
        a += 1;
    }
    out
}

/// An inclusive range of lattice indices per axis.
type IndexRanges = [(usize, usize); 3];

/// The lattice along axis `a` at pitch `step[a]`: its first coordinate and point count, every
/// point inside the bounds (the lowest layer above the ground).
fn lattice_axis(bounds: &Aabb, step: Neu, a: usize) -> Result<(f64, usize), VoxelError> {
    let none_fits = || {
        VoxelError::InvalidSpec(format!(
            "no lattice point fits in the flight volume on axis {a} (pitch {} m)",
            step[a]
        ))
    };
    let mut first = (bounds.min[a] / step[a]).ceil();
    if a == 2 && first < 1.0 && bounds.min[2] >= 0.0 {
        // No layer on or under the ground at altitude 0 (over terrain the volume reaches below
        // home, and the ground is among the boxes).
        first = 1.0;
    }
    let mut origin = first * step[a];
    let span = ((bounds.max[a] - origin) / step[a]).floor();
    if span.is_nan() || span < 0.0 {
        return Err(none_fits());
    }
    let mut n = span as usize + 1;
    // Every lattice point must lie inside the bounds, as computed.
    while n > 0 && origin + (n - 1) as f64 * step[a] > bounds.max[a] {
        n -= 1;
    }
    while origin < bounds.min[a] {
        origin += step[a];
        n = n.saturating_sub(1);
    }
    if n == 0 {
        return Err(none_fits());
    }
    Ok((origin, n))
}

impl<'w> VoxelGrid<'w> {
    /// Lays the lattice over the world's flight volume and classifies every voxel by rasterising
    /// the inflated boxes (no segment tests; these happen during queries).
    pub fn build(world: &'w BoxWorld3, spec: &VoxelSpec) -> Result<Self, VoxelError> {
        let t0 = Instant::now();
        for (name, v) in [("cell_m", spec.cell_m), ("layer_m", spec.layer_m)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(VoxelError::InvalidSpec(format!(
                    "{name}: expected a finite number > 0, found {v}"
                )));
            }
        }
        let bounds = world.bounds();
        let step = [spec.cell_m, spec.cell_m, spec.layer_m];
        let mut origin = [0.0; 3];
        let mut dims = [0usize; 3];
        for a in 0..3 {
            (origin[a], dims[a]) = lattice_axis(&bounds, step, a)?;
        }
        let total = dims[0]
            .checked_mul(dims[1])
            .and_then(|v| v.checked_mul(dims[2]))
            .filter(|&v| v <= MAX_VOXELS)
            .ok_or_else(|| {
                VoxelError::InvalidSpec(format!(
                    "{} × {} × {} voxels is more than {MAX_VOXELS}; use larger pitches",
                    dims[0], dims[1], dims[2]
                ))
            })?;
        let mut grid = Self {
            world,
            origin,
            step,
            dims,
            state: vec![CLEAR; total],
            heights: HeightMap {
                dims: [dims[0], dims[1]],
                top_m: vec![bounds.min[2]; dims[0] * dims[1]],
            },
            build_us: 0,
        };
        for b in world.inflated_boxes() {
            grid.rasterise(b);
        }
        for p in world.prisms() {
            grid.rasterise_prism(p);
        }
        grid.build_us = t0.elapsed().as_micros() as u64;
        Ok(grid)
    }

    /// Per axis, the lattice index ranges of a box: those whose neighbourhood meets it (near),
    /// and those whose coordinate lies within it (the centre is inside iff on all three axes;
    /// an empty range is `(i, j)` with `i > j`). `None` if no voxel is near the box.
    fn box_ranges(&self, b: &Aabb) -> Option<(IndexRanges, IndexRanges)> {
        let mut near = [(0usize, 0usize); 3];
        let mut inside = [(1usize, 0usize); 3];
        for a in 0..3 {
            let lo = ((b.min[a] - self.origin[a]) / self.step[a]).floor() as i64 - 2;
            let hi = ((b.max[a] - self.origin[a]) / self.step[a]).ceil() as i64 + 2;
            let lo = lo.clamp(0, self.dims[a] as i64 - 1) as usize;
            let hi = hi.clamp(0, self.dims[a] as i64 - 1) as usize;
            let (mut n0, mut n1) = (usize::MAX, 0);
            let (mut i0, mut i1) = (usize::MAX, 0);
            for i in lo..=hi {
                let below = self.coord(a, i as f64 - 1.0) - CLEAR_SLACK_M;
                let above = self.coord(a, i as f64 + 1.0) + CLEAR_SLACK_M;
                if below <= b.max[a] && above >= b.min[a] {
                    n0 = n0.min(i);
                    n1 = n1.max(i);
                }
                let c = self.coord(a, i as f64);
                if c >= b.min[a] && c <= b.max[a] {
                    i0 = i0.min(i);
                    i1 = i1.max(i);
                }
            }
            if n0 == usize::MAX {
                return None;
            }
            near[a] = (n0, n1);
            inside[a] = (i0, i1);
        }
        Some((near, inside))
    }

    /// Marks the voxels of the index ranges `near` that are clear as near an obstacle (their
    /// edges need a test).
    fn mark_near(&mut self, near: &IndexRanges) {
        for i in near[0].0..=near[0].1 {
            for j in near[1].0..=near[1].1 {
                for k in near[2].0..=near[2].1 {
                    let v = self.index([i, j, k]);
                    if self.state[v] == CLEAR {
                        self.state[v] = NEAR;
                    }
                }
            }
        }
    }

    /// Marks the voxels near an inflated box (their edges need a test), blocks those inside it
    /// and raises the height map under it.
    fn rasterise(&mut self, b: &Aabb) {
        let Some((near, inside)) = self.box_ranges(b) else {
            return;
        };
        self.mark_near(&near);
        if inside[0].0 > inside[0].1 || inside[1].0 > inside[1].1 {
            return;
        }
        for i in inside[0].0..=inside[0].1 {
            for j in inside[1].0..=inside[1].1 {
                let t = &mut self.heights.top_m[i * self.dims[1] + j];
                *t = t.max(b.max[2]);
                for k in inside[2].0..=inside[2].1 {
                    let v = self.index([i, j, k]);
                    self.state[v] = BLOCKED;
                }
            }
        }
    }

    /// Marks the voxels near a grown prism's bounding box (their edges need a test), blocks
    /// those whose centre lies in the prism and raises the height map under them.
    fn rasterise_prism(&mut self, p: &skyplan_world3::Prism) {
        let bbox = p.bbox();
        let Some((near, inside)) = self.box_ranges(&bbox) else {
            return;
        };
        self.mark_near(&near);
        if inside[0].0 > inside[0].1 || inside[1].0 > inside[1].1 || inside[2].0 > inside[2].1 {
            return;
        }
        for i in inside[0].0..=inside[0].1 {
            for j in inside[1].0..=inside[1].1 {
                let centre = [
                    self.coord(0, i as f64),
                    self.coord(1, j as f64),
                    bbox.min[2],
                ];
                if !p.contains(centre) {
                    continue; // the column misses the grown footprint
                }
                let t = &mut self.heights.top_m[i * self.dims[1] + j];
                *t = t.max(bbox.max[2]);
                for k in inside[2].0..=inside[2].1 {
                    let v = self.index([i, j, k]);
                    self.state[v] = BLOCKED;
                }
            }
        }
    }

    fn coord(&self, axis: usize, i: f64) -> f64 {
        self.origin[axis] + i * self.step[axis]
    }

    /// Lattice points along north, east and altitude.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.state.len()
    }

    /// Whether the lattice has no voxel (never true for a built grid).
    pub fn is_empty(&self) -> bool {
        self.state.is_empty()
    }

    /// The pitches `[north, east, alt]`, metres.
    pub fn step(&self) -> Neu {
        self.step
    }

    /// The altitudes of the layers, lowest first, metres.
    pub fn layers_m(&self) -> Vec<f64> {
        (0..self.dims[2]).map(|k| self.coord(2, k as f64)).collect()
    }

    /// The voxel index of lattice indices `[north, east, layer]`.
    pub fn index(&self, ijk: [usize; 3]) -> usize {
        (ijk[0] * self.dims[1] + ijk[1]) * self.dims[2] + ijk[2]
    }

    /// The lattice indices `[north, east, layer]` of a voxel.
    pub fn ijk(&self, v: usize) -> [usize; 3] {
        let k = v % self.dims[2];
        let r = v / self.dims[2];
        [r / self.dims[1], r % self.dims[1], k]
    }

    /// The centre (lattice point) of a voxel, `[north, east, alt]`.
    pub fn point(&self, v: usize) -> Neu {
        let [i, j, k] = self.ijk(v);
        [
            self.coord(0, i as f64),
            self.coord(1, j as f64),
            self.coord(2, k as f64),
        ]
    }

    /// Whether the voxel's centre is inside an inflated box.
    pub fn is_blocked(&self, v: usize) -> bool {
        self.state[v] == BLOCKED
    }

    /// Number of blocked voxels.
    pub fn blocked_count(&self) -> usize {
        self.state.iter().filter(|&&s| s == BLOCKED).count()
    }

    /// Number of voxels whose edges need no test (no inflated box near them).
    pub fn clear_count(&self) -> usize {
        self.state.iter().filter(|&&s| s == CLEAR).count()
    }

    /// The height map (highest inflated top per lattice column).
    pub fn height_map(&self) -> &HeightMap {
        &self.heights
    }

    /// Wall time of [`VoxelGrid::build`], microseconds.
    pub fn build_us(&self) -> u64 {
        self.build_us
    }

    /// The world the grid was built on.
    pub fn world(&self) -> &'w BoxWorld3 {
        self.world
    }

    /// The unblocked voxels within one step of `p` on every axis (`|q − p| ≤ step` per axis):
    /// the candidates to join `p` to the lattice (their segments still need a test).
    pub fn connector_candidates(&self, p: Neu) -> Vec<usize> {
        let mut range = [(0usize, 0usize); 3];
        for (a, r) in range.iter_mut().enumerate() {
            let lo = ((p[a] - self.step[a] - self.origin[a]) / self.step[a]).floor() as i64 - 1;
            let hi = ((p[a] + self.step[a] - self.origin[a]) / self.step[a]).ceil() as i64 + 1;
            if hi < 0 || lo > self.dims[a] as i64 - 1 {
                return Vec::new();
            }
            *r = (lo.max(0) as usize, hi.min(self.dims[a] as i64 - 1) as usize);
        }
        let mut out = Vec::new();
        for i in range[0].0..=range[0].1 {
            for j in range[1].0..=range[1].1 {
                for k in range[2].0..=range[2].1 {
                    let v = self.index([i, j, k]);
                    let q = self.point(v);
                    if !self.is_blocked(v) && (0..3).all(|a| (q[a] - p[a]).abs() <= self.step[a]) {
                        out.push(v);
                    }
                }
            }
        }
        out
    }

    /// The cheapest path from `query.start` to `query.goal` in the voxel graph (see the crate
    /// docs), then shortcut if asked. Every segment of `raw` and `path` passes world3's exact
    /// segment test.
    pub fn plan(&self, query: &Query) -> Result<VoxelPath, VoxelError> {
        let t0 = Instant::now();
        let w = query.climb_weight;
        if !(w.is_finite() && w >= 0.0) {
            return Err(VoxelError::InvalidSpec(format!(
                "climb weight: expected a finite number ≥ 0, found {w}"
            )));
        }
        let (start, goal) = (query.start, query.goal);
        if !self.world.is_free(start) {
            return Err(VoxelError::Invalid(End::Start));
        }
        if !self.world.is_free(goal) {
            return Err(VoxelError::Invalid(End::Goal));
        }
        let mut edge_checks = 0;
        let joins = self.joins(start, goal, w, &mut edge_checks)?;
        let mut search = Search::new(self, start, goal, w);
        search.edge_checks = edge_checks;
        let raw = search.run(&joins)?;
        let expansions = search.open.expansions() as usize;
        if let Some(k) = skyplan_world3::first_blocked_segment(self.world, &raw) {
            return Err(VoxelError::Internal(k));
        }
        let raw_cost = path_cost(&raw, w);
        let mut path = raw.clone();
        if query.shortcut {
            let short = skyplan_sampling::shortcut::reduce_vertices(self.world, &raw);
            if path_cost(&short, w) <= raw_cost {
                path = short;
            }
            if let Some(k) = skyplan_world3::first_blocked_segment(self.world, &path) {
                return Err(VoxelError::Internal(k));
            }
        }
        Ok(VoxelPath {
            cost: path_cost(&path, w),
            length_m: skyplan_world3::path_length_m(&path),
            climb_m: climb_m(&path),
            raw,
            path,
            raw_cost,
            expansions,
            edge_checks: search.edge_checks,
            search_us: t0.elapsed().as_micros() as u64,
        })
    }

    /// The voxels `p` joins with a free segment, and their costs (from `p` if `forward`, else to
    /// it); each segment tested counts in `checks`.
    fn join(&self, p: Neu, forward: bool, w: f64, checks: &mut usize) -> Vec<(usize, f64)> {
        self.connector_candidates(p)
            .into_iter()
            .filter_map(|v| {
                let q = self.point(v);
                *checks += 1;
                let (a, b) = if forward { (p, q) } else { (q, p) };
                self.world
                    .segment_is_free(a, b)
                    .then(|| (v, edge_cost(a, b, w)))
            })
            .collect()
    }

    /// The start and goal joined to the lattice (an error if one has no connector and the
    /// straight segment between them is blocked).
    fn joins(
        &self,
        start: Neu,
        goal: Neu,
        w: f64,
        checks: &mut usize,
    ) -> Result<Joins, VoxelError> {
        let from_start = self.join(start, true, w, checks);
        let mut to_goal = self.join(goal, false, w, checks);
        *checks += 1;
        let direct = self.world.segment_is_free(start, goal);
        if !direct {
            if from_start.is_empty() {
                return Err(VoxelError::NoConnector(End::Start));
            }
            if to_goal.is_empty() {
                return Err(VoxelError::NoConnector(End::Goal));
            }
        }
        to_goal.sort_unstable_by_key(|&(v, _)| v);
        Ok(Joins {
            from_start,
            to_goal,
            direct,
        })
    }
}

/// The start and goal joined to the lattice.
struct Joins {
    /// The voxels the start reaches and the costs.
    from_start: Vec<(usize, f64)>,
    /// The voxels that reach the goal and the costs, by voxel.
    to_goal: Vec<(usize, f64)>,
    /// Whether the straight segment from start to goal is free.
    direct: bool,
}

/// One A\* over the voxel graph, with the start and goal as two extra nodes after the voxels.
struct Search<'g, 'w> {
    grid: &'g VoxelGrid<'w>,
    start: Neu,
    goal: Neu,
    /// The climb weight.
    w: f64,
    start_id: usize,
    goal_id: usize,
    g: Vec<f64>,
    parent: Vec<u32>,
    open: OpenList,
    /// Segments tested so far (joins included).
    edge_checks: usize,
}

impl<'g, 'w> Search<'g, 'w> {
    fn new(grid: &'g VoxelGrid<'w>, start: Neu, goal: Neu, w: f64) -> Self {
        let n = grid.len();
        Search {
            grid,
            start,
            goal,
            w,
            start_id: n,
            goal_id: n + 1,
            g: vec![f64::INFINITY; n + 2],
            parent: vec![u32::MAX; n + 2],
            open: OpenList::new(n + 2),
            edge_checks: 0,
        }
    }

    /// The point of a node: a voxel's centre, the start or the goal.
    #[inline(always)]
    fn point_of(&self, id: usize) -> Neu {
        if id == self.start_id {
            self.start
        } else if id == self.goal_id {
            self.goal
        } else {
            self.grid.point(id)
        }
    }

    /// The heuristic: distance to the goal plus the weighted climb still needed.
    #[inline(always)]
    fn h(&self, p: Neu) -> f64 {
        distance_m(p, self.goal) + self.w * (self.goal[2] - p[2]).max(0.0)
    }

    /// Offers `to` reached from `from` over an edge of `cost`.
    #[inline(always)]
    fn relax(&mut self, from: usize, to: usize, cost: f64) {
        let ng = self.g[from] + cost;
        if ng < self.g[to] {
            self.g[to] = ng;
            self.parent[to] = from as u32;
            let f = ng + self.h(self.point_of(to));
            self.open.push(OpenEntry {
                f,
                g: ng,
                node: to as u32,
            });
        }
    }

    /// Searches from the start until the goal is closed; the raw path (start to goal, no
    /// repeated point).
    fn run(&mut self, joins: &Joins) -> Result<Vec<Neu>, VoxelError> {
        let (start_id, goal_id) = (self.start_id, self.goal_id);
        self.g[start_id] = 0.0;
        self.open.push(OpenEntry {
            f: self.h(self.start),
            g: 0.0,
            node: start_id as u32,
        });
        while let Some(OpenEntry { node: u, .. }) = self.open.pop() {
            let u = u as usize;
            if u == goal_id {
                break;
            }
            if u == start_id {
                if joins.direct {
                    let cost = edge_cost(self.start, self.goal, self.w);
                    self.relax(u, goal_id, cost);
                }
                for &(v, c) in &joins.from_start {
                    self.relax(u, v, c);
                }
                continue;
            }
            if let Ok(k) = joins.to_goal.binary_search_by_key(&u, |&(v, _)| v) {
                self.relax(u, goal_id, joins.to_goal[k].1);
            }
            self.expand(u);
        }
        if !self.open.is_closed(goal_id as u32) {
            let expansions = self.open.expansions() as usize;
            return Err(VoxelError::NoPath { expansions });
        }
        Ok(self.raw_path())
    }

    /// Relaxes the 26 lattice neighbours of voxel `u` (testing the edge's segment when `u` is
    /// near a box).
    #[inline(always)]
    fn expand(&mut self, u: usize) {
        let grid = self.grid;
        let p = grid.point(u);
        let ijk = grid.ijk(u);
        let near = grid.state[u] == NEAR;
        for d in OFFSETS {
            let mut nb = [0usize; 3];
            let mut inside = true;
            for a in 0..3 {
                let c = ijk[a] as i64 + d[a];
                if c < 0 || c >= grid.dims[a] as i64 {
                    inside = false;
                    break;
                }
                nb[a] = c as usize;
            }
            if !inside {
                continue;
            }
            let v = grid.index(nb);
            if self.open.is_closed(v as u32) || grid.state[v] == BLOCKED {
                continue;
            }
            let q = grid.point(v);
            let cost = edge_cost(p, q, self.w);
            if self.g[u] + cost >= self.g[v] {
                continue;
            }
            if near {
                self.edge_checks += 1;
                if !grid.world.segment_is_free(p, q) {
                    continue;
                }
            }
            self.relax(u, v, cost);
        }
    }

    /// The points from the start to the closed goal along the parents, without repeats.
    fn raw_path(&self) -> Vec<Neu> {
        let mut ids = vec![self.goal_id];
        let mut last = self.goal_id;
        while last != self.start_id {
            last = self.parent[last] as usize;
            ids.push(last);
        }
        ids.reverse();
        let mut raw: Vec<Neu> = Vec::with_capacity(ids.len());
        for &id in &ids {
            let p = self.point_of(id);
            if raw.last() != Some(&p) {
                raw.push(p);
            }
        }
        if raw.len() == 1 {
            raw.push(self.goal);
        }
        raw
    }
}
