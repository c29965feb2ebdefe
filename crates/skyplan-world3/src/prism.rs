//! Building footprints as obstacles: prisms (a polygon with holes between a floor and a top)
//! grown by the margin — horizontally by a disc (the footprint's Minkowski sum with it,
//! shapely's `buffer`, as the 2D grids grow footprints) and vertically by the margin — with
//! exact point, segment and box tests.

use crate::{Aabb, Neu, lerp, segment_hits_box};
use skyplan_map::footprints::Footprint;
use skyplan_map::planar::{region_rect_m, region_segment_m};

/// A footprint prism grown by the margin (closed: touching it counts as a collision).
///
/// ```
/// use skyplan_world3::Prism;
/// // A 10 m square building 20 m tall with a 2 m margin.
/// let square = vec![vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]];
/// let p = Prism::new(square, 0.0, 20.0, 2.0);
/// assert!(p.contains([-1.5, 5.0, 10.0]) && !p.contains([-2.5, 5.0, 10.0]));
/// assert!(!p.contains([-1.5, -1.5, 10.0])); // the corner is rounded: 2.12 m away
/// assert!(p.contains([5.0, 5.0, 22.0]) && !p.contains([5.0, 5.0, 22.5]));
/// assert!(p.segment_hits([-5.0, 5.0, 30.0], [15.0, 5.0, 10.0])); // down through the roof
/// assert!(!p.segment_hits([-5.0, -2.5, 10.0], [15.0, -2.5, 10.0])); // along the side
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Prism {
    rings: Vec<Vec<[f64; 2]>>,
    grow_m: f64,
    bbox: Aabb,
}

impl Prism {
    /// The prism of the polygon `rings` (`[north, east]` metres, outer ring first, then holes,
    /// even-odd) between `floor_m` and `top_m`, grown by `grow_m` (≥ 0).
    pub fn new(rings: Vec<Vec<[f64; 2]>>, floor_m: f64, top_m: f64, grow_m: f64) -> Self {
        Self::with_growth(rings, floor_m, top_m, grow_m, grow_m)
    }

    /// The prism grown by `grow_ne_m` horizontally and `grow_up_m` vertically: a no-fly circle
    /// is the prism of its centre (a ring of one point) grown by its radius plus the margin
    /// horizontally and by the margin vertically.
    ///
    /// ```
    /// use skyplan_world3::Prism;
    /// let disc = Prism::with_growth(vec![vec![[0.0, 0.0]]], 0.0, 50.0, 30.0 + 5.0, 5.0);
    /// assert!(disc.contains([34.9, 0.0, 54.9]) && !disc.contains([35.1, 0.0, 10.0]));
    /// assert!(!disc.contains([0.0, 0.0, 55.5]));
    /// ```
    pub fn with_growth(
        rings: Vec<Vec<[f64; 2]>>,
        floor_m: f64,
        top_m: f64,
        grow_ne_m: f64,
        grow_up_m: f64,
    ) -> Self {
        let grow_m = grow_ne_m;
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in rings.iter().flatten() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let bbox = Aabb {
            min: [lo[0] - grow_m, lo[1] - grow_m, floor_m - grow_up_m],
            max: [hi[0] + grow_m, hi[1] + grow_m, top_m + grow_up_m],
        };
        Self {
            rings,
            grow_m,
            bbox,
        }
    }

    /// A building's prism grown by `grow_m`.
    pub fn from_footprint(f: &Footprint, grow_m: f64) -> Self {
        Self::new(f.rings.clone(), f.min_height_m, f.height_m, grow_m)
    }

    /// The grown prism's bounding box.
    pub fn bbox(&self) -> Aabb {
        self.bbox
    }

    /// The polygon's rings, not grown.
    pub fn rings(&self) -> &[Vec<[f64; 2]>] {
        &self.rings
    }

    /// How far the prism is grown horizontally, metres.
    pub fn grow_m(&self) -> f64 {
        self.grow_m
    }

    /// Whether the point lies in the grown prism.
    pub fn contains(&self, p: Neu) -> bool {
        self.bbox.contains(p)
            && region_segment_m(&self.rings, [p[0], p[1]], [p[0], p[1]]) <= self.grow_m
    }

    /// Whether the closed box `b` meets the grown prism.
    pub fn meets(&self, b: &Aabb) -> bool {
        self.bbox.meets(b)
            && region_rect_m(&self.rings, [b.min[0], b.min[1]], [b.max[0], b.max[1]]) <= self.grow_m
    }

    /// Whether some point of the segment `a → b` lies in the grown prism: the part of the
    /// segment within the prism's altitude band, tested against the grown polygon exactly.
    pub fn segment_hits(&self, a: Neu, b: Neu) -> bool {
        if !segment_hits_box(a, b, &self.bbox) {
            return false;
        }
        let (lo, hi) = (self.bbox.min[2], self.bbox.max[2]);
        let (t0, t1) = if a[2] == b[2] {
            (0.0, 1.0) // inside the band: the box test passed
        } else {
            let ta = (lo - a[2]) / (b[2] - a[2]);
            let tb = (hi - a[2]) / (b[2] - a[2]);
            (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
        };
        if t0 > t1 {
            return false;
        }
        let (p, q) = (lerp(a, b, t0), lerp(a, b, t1));
        region_segment_m(&self.rings, [p[0], p[1]], [q[0], q[1]]) <= self.grow_m
    }
}
