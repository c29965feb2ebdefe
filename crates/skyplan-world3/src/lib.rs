//! Exact 3D collision checking for skyplan's box world.
//!
//! The world is the map's obstacle boxes, each grown by the safety margin in **all three axes**
//! (a route over a roof keeps the margin above it), plus two more obstacles: the ground (every
//! point below `min_alt_m`) and everything outside the map's bounds. Points are
//! `[north_m, east_m, alt_m]` about the map's home ([`Neu`]).
//!
//! A point is free iff it lies inside the bounds (faces included) and outside every closed
//! inflated box: touching a grown box counts as a collision. A segment is free iff every one of
//! its points is free; this is decided exactly by a slab test per box ([`segment_hits_box`]), not
//! by sampling. A uniform horizontal grid ([`BoxWorld3`]) limits the boxes tested to those near
//! the segment, so a check costs microseconds; [`BruteForce`] tests every box and is the
//! reference the index is property-tested against.
//!
//! ```
//! use skyplan_map::colliders::ObstacleBox;
//! use skyplan_world3::{BoxWorld3, CollisionChecker, WorldSpec};
//! // A 20 m tall tower at (50, 50), 10 m wide; 5 m margin.
//! let tower = ObstacleBox { north_m: 50.0, east_m: 50.0, up_m: 10.0, half_north_m: 5.0, half_east_m: 5.0, half_up_m: 10.0 };
//! let spec = WorldSpec { safety_m: 5.0, min_alt_m: 0.0, max_alt_m: 100.0, margin_bounds_m: 50.0 };
//! let world = BoxWorld3::new(&[tower], &spec)?;
//! assert!(!world.is_free([50.0, 50.0, 22.0]));                   // within 5 m of the roof
//! assert!(world.is_free([50.0, 50.0, 25.5]));                    // above roof + margin
//! assert!(!world.segment_is_free([0.0, 50.0, 10.0], [100.0, 50.0, 10.0])); // through the tower
//! assert!(world.segment_is_free([0.0, 50.0, 26.0], [100.0, 50.0, 26.0]));  // over it
//! assert!(!world.is_free([0.0, 0.0, -0.5]));                     // below the ground
//! # Ok::<(), skyplan_world3::WorldError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use skyplan_map::colliders::ObstacleBox;
use skyplan_map::footprints::Footprint;

mod prism;
pub use prism::Prism;

/// A point `[north_m, east_m, alt_m]` in metres about the map's home (altitude positive up).
pub type Neu = [f64; 3];

/// An axis-aligned box in the local frame, `[north, east, alt]` corners, metres (closed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// The corner with the smallest coordinates.
    pub min: Neu,
    /// The corner with the largest coordinates.
    pub max: Neu,
}

impl Aabb {
    /// Whether the closed box contains the point.
    ///
    /// ```
    /// let b = skyplan_world3::Aabb { min: [0.0; 3], max: [1.0; 3] };
    /// assert!(b.contains([1.0, 0.5, 0.0]) && !b.contains([1.0, 0.5, 1.5]));
    /// ```
    pub fn contains(&self, p: Neu) -> bool {
        (0..3).all(|i| p[i] >= self.min[i] && p[i] <= self.max[i])
    }

    /// The box grown by `by_m` on every side.
    pub fn grown(&self, by_m: f64) -> Self {
        Self {
            min: self.min.map(|v| v - by_m),
            max: self.max.map(|v| v + by_m),
        }
    }

    /// Whether two closed boxes share a point (touching counts).
    ///
    /// ```
    /// use skyplan_world3::Aabb;
    /// let a = Aabb { min: [0.0; 3], max: [1.0; 3] };
    /// assert!(a.meets(&Aabb { min: [1.0, 0.0, 0.0], max: [2.0; 3] }));
    /// assert!(!a.meets(&Aabb { min: [1.01, 0.0, 0.0], max: [2.0; 3] }));
    /// ```
    pub fn meets(&self, other: &Aabb) -> bool {
        (0..3).all(|i| self.min[i] <= other.max[i] && other.min[i] <= self.max[i])
    }

    /// Whether `other` lies inside this closed box.
    pub fn holds(&self, other: &Aabb) -> bool {
        (0..3).all(|i| self.min[i] <= other.min[i] && other.max[i] <= self.max[i])
    }

    /// Edge lengths `[north, east, alt]`, metres.
    pub fn extent_m(&self) -> Neu {
        [
            self.max[0] - self.min[0],
            self.max[1] - self.min[1],
            self.max[2] - self.min[2],
        ]
    }

    /// The box of an obstacle grown by a margin in all three axes.
    pub fn from_obstacle(b: &ObstacleBox, safety_m: f64) -> Self {
        let (min, max) = b.grown(safety_m);
        Self { min, max }
    }
}

/// Euclidean distance between two points, metres.
///
/// ```
/// assert_eq!(skyplan_world3::distance_m([0.0, 0.0, 0.0], [3.0, 0.0, 4.0]), 5.0);
/// ```
pub fn distance_m(a: Neu, b: Neu) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Length of a polyline, metres.
pub fn path_length_m(path: &[Neu]) -> f64 {
    path.windows(2).map(|w| distance_m(w[0], w[1])).sum()
}

/// Whether the segment `a → b` meets the closed box (slab test; exact up to floating point).
///
/// Touching a face, edge or corner counts as a hit. A degenerate segment (`a == b`) is a point
/// test.
///
/// ```
/// use skyplan_world3::{segment_hits_box, Aabb};
/// let b = Aabb { min: [0.0; 3], max: [1.0; 3] };
/// assert!(segment_hits_box([-1.0, 0.5, 0.5], [2.0, 0.5, 0.5], &b));  // through
/// assert!(segment_hits_box([-1.0, 1.0, 1.0], [2.0, 1.0, 1.0], &b));  // along an edge
/// assert!(!segment_hits_box([-1.0, 0.5, 1.01], [2.0, 0.5, 1.01], &b)); // just above
/// assert!(!segment_hits_box([-1.0, -1.0, 0.5], [0.9, -0.1, 0.5], &b)); // stops short
/// ```
pub fn segment_hits_box(a: Neu, b: Neu, bx: &Aabb) -> bool {
    let mut t_enter = 0.0_f64;
    let mut t_exit = 1.0_f64;
    for i in 0..3 {
        let d = b[i] - a[i];
        if d == 0.0 {
            if a[i] < bx.min[i] || a[i] > bx.max[i] {
                return false;
            }
        } else {
            let inv = 1.0 / d;
            let mut t0 = (bx.min[i] - a[i]) * inv;
            let mut t1 = (bx.max[i] - a[i]) * inv;
            if t0 > t1 {
                std::mem::swap(&mut t0, &mut t1);
            }
            t_enter = t_enter.max(t0);
            t_exit = t_exit.min(t1);
            if t_enter > t_exit {
                return false;
            }
        }
    }
    true
}

/// Errors building a world.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum WorldError {
    /// A number of the spec is negative, NaN or infinite, or the altitude band is empty.
    #[error("invalid world spec: {0}")]
    InvalidSpec(String),
    /// The map has no boxes to take bounds from.
    #[error("the map has no obstacle boxes")]
    NoBoxes,
}

/// How to build a [`BoxWorld3`] from the map's boxes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldSpec {
    /// Margin added to every box in all three axes, metres (≥ 0).
    pub safety_m: f64,
    /// Lowest flyable altitude: points below it are inside the ground, metres.
    pub min_alt_m: f64,
    /// Highest flyable altitude (the bounds' ceiling), metres.
    pub max_alt_m: f64,
    /// How far the horizontal bounds extend beyond the outermost box (no margin), metres (≥ 0).
    pub margin_bounds_m: f64,
}

impl Default for WorldSpec {
    /// 5 m margin, altitudes 0–120 m, bounds = the boxes' footprint.
    fn default() -> Self {
        Self {
            safety_m: 5.0,
            min_alt_m: 0.0,
            max_alt_m: 120.0,
            margin_bounds_m: 0.0,
        }
    }
}

/// The shared collision-checker interface: what every sampling planner and post-processing pass
/// sees (OMPL's state validity checker and motion validator).
pub trait CollisionChecker {
    /// Whether the point is in free space.
    fn is_free(&self, p: Neu) -> bool;
    /// Whether every point of the segment `a → b` is in free space.
    fn segment_is_free(&self, a: Neu, b: Neu) -> bool;
    /// The box in which free points are sampled (every free point lies inside it).
    fn bounds(&self) -> Aabb;
}

/// Size of the horizontal buckets of the index, metres.
const BUCKET_M: f64 = 10.0;

/// The box world with a uniform horizontal grid index (compressed rows of box indices per cell,
/// and the highest inflated top in each cell).
#[derive(Debug, Clone)]
pub struct BoxWorld3 {
    boxes: Vec<Aabb>,
    prisms: Vec<Prism>,
    bounds: Aabb,
    spec: WorldSpec,
    origin_ne: [f64; 2],
    cells_ne: [usize; 2],
    cell_start: Vec<u32>,
    cell_boxes: Vec<u32>,
    cell_top_m: Vec<f64>,
}

fn check_spec(spec: &WorldSpec) -> Result<(), WorldError> {
    let finite_nonneg = |name: &str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(WorldError::InvalidSpec(format!(
                "{name}: expected a finite number ≥ 0, found {v}"
            )))
        }
    };
    finite_nonneg("safety_m", spec.safety_m)?;
    finite_nonneg("margin_bounds_m", spec.margin_bounds_m)?;
    if !(spec.min_alt_m.is_finite() && spec.max_alt_m.is_finite())
        || spec.min_alt_m >= spec.max_alt_m
    {
        return Err(WorldError::InvalidSpec(format!(
            "altitude band: expected finite min_alt_m < max_alt_m, found {} and {}",
            spec.min_alt_m, spec.max_alt_m
        )));
    }
    Ok(())
}

impl BoxWorld3 {
    /// Inflates the boxes by the margin, takes the horizontal bounds from their footprint (plus
    /// `margin_bounds_m`) and the vertical bounds from the altitude band, and indexes the boxes.
    pub fn new(obstacles: &[ObstacleBox], spec: &WorldSpec) -> Result<Self, WorldError> {
        check_spec(spec)?;
        if obstacles.is_empty() {
            return Err(WorldError::NoBoxes);
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for b in obstacles {
            let raw = Aabb::from_obstacle(b, 0.0);
            for i in 0..2 {
                lo[i] = lo[i].min(raw.min[i]);
                hi[i] = hi[i].max(raw.max[i]);
            }
        }
        let m = spec.margin_bounds_m;
        let bounds = Aabb {
            min: [lo[0] - m, lo[1] - m, spec.min_alt_m],
            max: [hi[0] + m, hi[1] + m, spec.max_alt_m],
        };
        Self::with_bounds(obstacles, spec, bounds)
    }

    /// Like [`BoxWorld3::new`] with explicit bounds (their altitude range replaces the spec's
    /// band; `min_alt_m` is the ground).
    pub fn with_bounds(
        obstacles: &[ObstacleBox],
        spec: &WorldSpec,
        bounds: Aabb,
    ) -> Result<Self, WorldError> {
        Self::with_footprints(obstacles, &[], spec, bounds)
    }

    /// Like [`BoxWorld3::with_bounds`] with building footprints too: each a [`Prism`] grown by
    /// the margin (horizontally by a disc, vertically by the margin). Indices of obstacles
    /// count the boxes first, then the prisms.
    ///
    /// ```
    /// use skyplan_map::footprints::Footprint;
    /// use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, WorldSpec};
    /// // An L-shaped building 30 m tall; 2 m margin.
    /// let l_shape = vec![vec![[0.0, 0.0], [20.0, 0.0], [20.0, 5.0], [5.0, 5.0], [5.0, 20.0], [0.0, 20.0]]];
    /// let f = Footprint { feature: 0, rings: l_shape, min_height_m: 0.0, height_m: 30.0 };
    /// let spec = WorldSpec { safety_m: 2.0, ..WorldSpec::default() };
    /// let bounds = Aabb { min: [-50.0, -50.0, 0.0], max: [50.0, 50.0, 100.0] };
    /// let w = BoxWorld3::with_footprints(&[], &[f], &spec, bounds)?;
    /// assert!(w.is_free([15.0, 15.0, 10.0])); // in the L's notch
    /// assert!(!w.segment_is_free([15.0, 15.0, 10.0], [-5.0, -5.0, 10.0])); // through it
    /// assert!(w.segment_is_free([15.0, 15.0, 33.0], [-5.0, -5.0, 32.5])); // over the roof
    /// # Ok::<(), skyplan_world3::WorldError>(())
    /// ```
    pub fn with_footprints(
        obstacles: &[ObstacleBox],
        footprints: &[Footprint],
        spec: &WorldSpec,
        bounds: Aabb,
    ) -> Result<Self, WorldError> {
        let prisms = (footprints.iter())
            .map(|f| Prism::from_footprint(f, spec.safety_m))
            .collect();
        Self::with_prisms(obstacles, prisms, spec, bounds)
    }

    /// Like [`BoxWorld3::with_bounds`] with prisms grown already (footprints, no-fly zones):
    /// the boxes are grown by the spec's margin, the prisms are taken as they are.
    pub fn with_prisms(
        obstacles: &[ObstacleBox],
        prisms: Vec<Prism>,
        spec: &WorldSpec,
        bounds: Aabb,
    ) -> Result<Self, WorldError> {
        check_spec(spec)?;
        if !(0..3).all(|i| {
            bounds.min[i].is_finite() && bounds.max[i].is_finite() && bounds.min[i] < bounds.max[i]
        }) {
            return Err(WorldError::InvalidSpec(format!(
                "bounds: expected finite min < max on every axis, found {bounds:?}"
            )));
        }
        let mut bounds = bounds;
        bounds.min[2] = bounds.min[2].max(spec.min_alt_m);
        if bounds.min[2] >= bounds.max[2] {
            return Err(WorldError::InvalidSpec(
                "bounds: the ceiling is below the ground".into(),
            ));
        }
        let boxes: Vec<Aabb> = obstacles
            .iter()
            .map(|b| Aabb::from_obstacle(b, spec.safety_m))
            .collect();
        let origin_ne = [bounds.min[0], bounds.min[1]];
        let cells_ne = [
            (((bounds.max[0] - bounds.min[0]) / BUCKET_M).floor() as usize + 1).max(1),
            (((bounds.max[1] - bounds.min[1]) / BUCKET_M).floor() as usize + 1).max(1),
        ];
        let n_cells = cells_ne[0] * cells_ne[1];
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n_cells];
        let mut cell_top_m = vec![f64::NEG_INFINITY; n_cells];
        let cell_of = |v: f64, axis: usize| -> usize {
            let c = ((v - origin_ne[axis]) / BUCKET_M).floor();
            c.clamp(0.0, (cells_ne[axis] - 1) as f64) as usize
        };
        let extents = (boxes.iter().copied()).chain(prisms.iter().map(Prism::bbox));
        for (k, b) in extents.enumerate() {
            // Boxes entirely outside the bounds or below the ground can never be touched by a
            // free point; keep them anyway (they are clamped into the edge cells), it is cheap.
            let (r0, r1) = (cell_of(b.min[0], 0), cell_of(b.max[0], 0));
            let (c0, c1) = (cell_of(b.min[1], 1), cell_of(b.max[1], 1));
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let i = r * cells_ne[1] + c;
                    lists[i].push(k as u32);
                    cell_top_m[i] = cell_top_m[i].max(b.max[2]);
                }
            }
        }
        let mut cell_start = Vec::with_capacity(n_cells + 1);
        let mut cell_boxes = Vec::new();
        cell_start.push(0);
        for l in &lists {
            cell_boxes.extend_from_slice(l);
            cell_start.push(cell_boxes.len() as u32);
        }
        Ok(Self {
            boxes,
            prisms,
            bounds,
            spec: *spec,
            origin_ne,
            cells_ne,
            cell_start,
            cell_boxes,
            cell_top_m,
        })
    }

    /// The inflated boxes, in map order.
    pub fn inflated_boxes(&self) -> &[Aabb] {
        &self.boxes
    }

    /// The grown footprint prisms, in map order.
    pub fn prisms(&self) -> &[Prism] {
        &self.prisms
    }

    /// Whether obstacle `k` (boxes first, then prisms) contains the point.
    fn obstacle_contains(&self, k: usize, p: Neu) -> bool {
        match k.checked_sub(self.boxes.len()) {
            None => self.boxes[k].contains(p),
            Some(i) => self.prisms[i].contains(p),
        }
    }

    /// Whether obstacle `k` (boxes first, then prisms) meets the closed box.
    fn obstacle_meets(&self, k: usize, b: &Aabb) -> bool {
        match k.checked_sub(self.boxes.len()) {
            None => self.boxes[k].meets(b),
            Some(i) => self.prisms[i].meets(b),
        }
    }

    /// Whether obstacle `k` (boxes first, then prisms) meets the segment.
    fn obstacle_hit(&self, k: usize, a: Neu, b: Neu) -> bool {
        match k.checked_sub(self.boxes.len()) {
            None => segment_hits_box(a, b, &self.boxes[k]),
            Some(i) => self.prisms[i].segment_hits(a, b),
        }
    }

    /// The spec the world was built with.
    pub fn spec(&self) -> &WorldSpec {
        &self.spec
    }

    /// The reference checker over the same boxes and bounds, testing every box.
    pub fn brute_force(&self) -> BruteForce<'_> {
        BruteForce {
            boxes: &self.boxes,
            prisms: &self.prisms,
            bounds: self.bounds,
        }
    }

    /// The index of an inflated box or grown prism containing the point, if any (boxes first,
    /// then prisms; bounds and ground ignored).
    pub fn box_containing(&self, p: Neu) -> Option<usize> {
        let i = self.cell_index(p[0], p[1])?;
        self.cell(i)
            .iter()
            .map(|&k| k as usize)
            .find(|&k| self.obstacle_contains(k, p))
    }

    /// Whether the closed box `b` lies inside the bounds (above the ground) and meets no
    /// inflated box: every point of it is free. Exact; the index only picks candidates.
    ///
    /// ```
    /// use skyplan_map::colliders::ObstacleBox;
    /// use skyplan_world3::{Aabb, BoxWorld3, WorldSpec};
    /// let b = ObstacleBox { north_m: 0.0, east_m: 0.0, up_m: 10.0, half_north_m: 5.0, half_east_m: 5.0, half_up_m: 10.0 };
    /// let spec = WorldSpec { safety_m: 1.0, margin_bounds_m: 50.0, ..WorldSpec::default() };
    /// let w = BoxWorld3::new(&[b], &spec).unwrap();
    /// assert!(w.box_is_free(&Aabb { min: [6.5, -2.0, 5.0], max: [9.0, 2.0, 6.0] }));
    /// assert!(!w.box_is_free(&Aabb { min: [5.5, -2.0, 5.0], max: [9.0, 2.0, 6.0] })); // in the margin
    /// assert!(w.box_is_free(&Aabb { min: [-2.0, -2.0, 21.5], max: [2.0, 2.0, 30.0] })); // above it
    /// ```
    pub fn box_is_free(&self, b: &Aabb) -> bool {
        if !self.bounds.holds(b) {
            return false;
        }
        let cell = |v: f64, axis: usize| -> usize {
            let c = ((v - self.origin_ne[axis]) / BUCKET_M).floor();
            c.clamp(0.0, (self.cells_ne[axis] - 1) as f64) as usize
        };
        let (r0, r1) = (cell(b.min[0], 0), cell(b.max[0], 0));
        let (c0, c1) = (cell(b.min[1], 1), cell(b.max[1], 1));
        for r in r0..=r1 {
            for c in c0..=c1 {
                let i = r * self.cells_ne[1] + c;
                if self.cell_top_m[i] < b.min[2] {
                    continue;
                }
                if self
                    .cell(i)
                    .iter()
                    .any(|&k| self.obstacle_meets(k as usize, b))
                {
                    return false;
                }
            }
        }
        true
    }

    fn cell_index(&self, north_m: f64, east_m: f64) -> Option<usize> {
        let r = ((north_m - self.origin_ne[0]) / BUCKET_M).floor();
        let c = ((east_m - self.origin_ne[1]) / BUCKET_M).floor();
        if r < 0.0 || c < 0.0 || r >= self.cells_ne[0] as f64 || c >= self.cells_ne[1] as f64 {
            return None;
        }
        Some(r as usize * self.cells_ne[1] + c as usize)
    }

    fn cell(&self, i: usize) -> &[u32] {
        &self.cell_boxes[self.cell_start[i] as usize..self.cell_start[i + 1] as usize]
    }

    /// Whether any box registered in the cells covering the NE rectangle meets the segment.
    fn rect_hits(&self, a: Neu, b: Neu, lo: Neu, hi: Neu) -> bool {
        let cell = |v: f64, axis: usize| -> usize {
            let c = ((v - self.origin_ne[axis]) / BUCKET_M).floor();
            c.clamp(0.0, (self.cells_ne[axis] - 1) as f64) as usize
        };
        let (r0, r1) = (cell(lo[0], 0), cell(hi[0], 0));
        let (c0, c1) = (cell(lo[1], 1), cell(hi[1], 1));
        for r in r0..=r1 {
            for c in c0..=c1 {
                let i = r * self.cells_ne[1] + c;
                if self.cell_top_m[i] < lo[2] {
                    continue;
                }
                for &k in self.cell(i) {
                    if self.obstacle_hit(k as usize, a, b) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

impl CollisionChecker for BoxWorld3 {
    fn is_free(&self, p: Neu) -> bool {
        self.bounds.contains(p) && self.box_containing(p).is_none()
    }

    fn segment_is_free(&self, a: Neu, b: Neu) -> bool {
        // Bounds and ground are convex: a segment with both ends inside stays inside.
        if !self.bounds.contains(a) || !self.bounds.contains(b) {
            return false;
        }
        // Cover the segment by pieces no longer than a bucket horizontally; every point of the
        // segment lies in some piece's bounding rectangle, and every box meeting that rectangle
        // is registered in the cells it covers. The whole segment is tested against each
        // candidate box, so the pieces only choose candidates.
        let horizontal_m = (b[0] - a[0]).hypot(b[1] - a[1]);
        let pieces = ((horizontal_m / BUCKET_M).ceil() as usize).max(1);
        for s in 0..pieces {
            let t0 = s as f64 / pieces as f64;
            let t1 = (s + 1) as f64 / pieces as f64;
            let p0 = lerp(a, b, t0);
            let p1 = lerp(a, b, t1);
            // Widen by a hair so rounding in lerp never drops a cell the segment touches.
            let lo = [
                p0[0].min(p1[0]) - 1e-6,
                p0[1].min(p1[1]) - 1e-6,
                p0[2].min(p1[2]) - 1e-6,
            ];
            let hi = [
                p0[0].max(p1[0]) + 1e-6,
                p0[1].max(p1[1]) + 1e-6,
                p0[2].max(p1[2]) + 1e-6,
            ];
            if self.rect_hits(a, b, lo, hi) {
                return false;
            }
        }
        true
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

/// The point at parameter `t` of the segment `a → b` (`t = 0` gives `a`, `t = 1` gives `b`
/// exactly).
pub fn lerp(a: Neu, b: Neu, t: f64) -> Neu {
    if t >= 1.0 {
        return b;
    }
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// The reference checker: the same semantics as [`BoxWorld3`], testing every box (no index).
#[derive(Debug, Clone, Copy)]
pub struct BruteForce<'a> {
    /// The inflated boxes.
    pub boxes: &'a [Aabb],
    /// The grown footprint prisms.
    pub prisms: &'a [Prism],
    /// The flyable bounds (the ground is their floor).
    pub bounds: Aabb,
}

impl BruteForce<'_> {
    /// [`BoxWorld3::box_is_free`] testing every box.
    pub fn box_is_free(&self, b: &Aabb) -> bool {
        self.bounds.holds(b)
            && !self.boxes.iter().any(|o| o.meets(b))
            && !self.prisms.iter().any(|o| o.meets(b))
    }
}

impl CollisionChecker for BruteForce<'_> {
    fn is_free(&self, p: Neu) -> bool {
        self.bounds.contains(p)
            && !self.boxes.iter().any(|b| b.contains(p))
            && !self.prisms.iter().any(|o| o.contains(p))
    }

    fn segment_is_free(&self, a: Neu, b: Neu) -> bool {
        self.bounds.contains(a)
            && self.bounds.contains(b)
            && !self.boxes.iter().any(|bx| segment_hits_box(a, b, bx))
            && !self.prisms.iter().any(|o| o.segment_hits(a, b))
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

/// Checks a whole polyline: the index of the first segment that is not free (a single point
/// path is checked as a point), or `None` if the path is free.
pub fn first_blocked_segment(checker: &impl CollisionChecker, path: &[Neu]) -> Option<usize> {
    if let [p] = path {
        return (!checker.is_free(*p)).then_some(0);
    }
    path.windows(2)
        .position(|w| !checker.segment_is_free(w[0], w[1]))
}
