//! Exact plane geometry shared by the footprint and zone code: distances between points,
//! segments, rectangles and polygons with holes (`[north, east]` metres; a polygon is its rings,
//! outer first, without closing positions, inside by the even-odd rule).
//!
//! A polygon grown by a margin `r` (its Minkowski sum with a disc, shapely's `buffer(r)`) meets
//! a segment iff [`region_segment_m`] ≤ `r`, and a rectangle iff [`region_rect_m`] ≤ `r`.
//!
//! ```
//! use skyplan_map::planar::{region_rect_m, region_segment_m};
//! // A 10 m square with a 4 m hole in the middle.
//! let rings = vec![
//!     vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]],
//!     vec![[3.0, 3.0], [7.0, 3.0], [7.0, 7.0], [3.0, 7.0]],
//! ];
//! assert_eq!(region_segment_m(&rings, [-2.0, 5.0], [-2.0, 8.0]), 2.0); // beside it
//! assert_eq!(region_segment_m(&rings, [1.0, 1.0], [1.0, 2.0]), 0.0); // inside
//! assert_eq!(region_segment_m(&rings, [5.0, 4.0], [5.0, 6.0]), 1.0); // in the hole
//! assert_eq!(region_rect_m(&rings, [4.0, 4.0], [6.0, 5.0]), 1.0); // in the hole
//! assert_eq!(region_rect_m(&rings, [12.0, 12.0], [20.0, 20.0]), 8f64.sqrt());
//! ```

/// The distance from the point `p` to the closed segment `a`–`b`, metres.
///
/// ```
/// assert_eq!(skyplan_map::planar::point_segment_m([3.0, 4.0], [0.0, 0.0], [0.0, 0.0]), 5.0);
/// assert_eq!(skyplan_map::planar::point_segment_m([1.0, 2.0], [0.0, 0.0], [0.0, 10.0]), 1.0);
/// ```
pub fn point_segment_m(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let [x, y] = nearest_offset(p, a, b);
    x.hypot(y)
}

/// The squared distance from the point `p` to the closed segment `a`–`b`, square metres: for
/// comparisons in inner loops (no square root).
///
/// ```
/// assert_eq!(skyplan_map::planar::point_segment2_m2([3.0, 4.0], [0.0, 0.0], [0.0, 0.0]), 25.0);
/// ```
#[inline]
pub fn point_segment2_m2(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let [x, y] = nearest_offset(p, a, b);
    x * x + y * y
}

/// The segment's point nearest to `p`, less `p`.
#[inline]
fn nearest_offset(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    [a[0] + t * dx - p[0], a[1] + t * dy - p[1]]
}

/// Whether the closed segments `a`–`b` and `c`–`d` share a point.
///
/// ```
/// use skyplan_map::planar::segments_meet;
/// assert!(segments_meet([0.0, 0.0], [2.0, 2.0], [0.0, 2.0], [2.0, 0.0]));
/// assert!(segments_meet([0.0, 0.0], [1.0, 1.0], [1.0, 1.0], [2.0, 0.0])); // touching
/// assert!(!segments_meet([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]));
/// ```
pub fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let cross = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let (d1, d2) = (cross(a, b, c), cross(a, b, d));
    let (d3, d4) = (cross(c, d, a), cross(c, d, b));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    // Touching or collinear: an end on the other segment.
    point_segment_m(c, a, b) == 0.0
        || point_segment_m(d, a, b) == 0.0
        || point_segment_m(a, c, d) == 0.0
        || point_segment_m(b, c, d) == 0.0
}

/// The distance between the closed segments `a`–`b` and `c`–`d`, metres (0 where they meet).
///
/// ```
/// use skyplan_map::planar::segment_segment_m;
/// assert_eq!(segment_segment_m([0.0, 0.0], [0.0, 4.0], [3.0, 2.0], [5.0, 2.0]), 3.0);
/// assert_eq!(segment_segment_m([0.0, 0.0], [2.0, 2.0], [0.0, 2.0], [2.0, 0.0]), 0.0);
/// ```
pub fn segment_segment_m(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    if segments_meet(a, b, c, d) {
        return 0.0;
    }
    point_segment_m(a, c, d)
        .min(point_segment_m(b, c, d))
        .min(point_segment_m(c, a, b))
        .min(point_segment_m(d, a, b))
}

/// The rings' edges, each as its two ends.
fn edges(rings: &[Vec<[f64; 2]>]) -> impl Iterator<Item = ([f64; 2], [f64; 2])> + '_ {
    rings
        .iter()
        .flat_map(|ring| (0..ring.len()).map(move |k| (ring[k], ring[(k + 1) % ring.len()])))
}

/// Whether `p` lies inside the polygon by the even-odd rule over every ring (inside the outer
/// ring and in no hole); a point on an edge may fall either way (every caller also measures the
/// distance to the edges).
///
/// ```
/// let square = vec![vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]];
/// assert!(skyplan_map::planar::inside(&square, [1.0, 3.0]));
/// assert!(!skyplan_map::planar::inside(&square, [5.0, 3.0]));
/// ```
pub fn inside(rings: &[Vec<[f64; 2]>], p: [f64; 2]) -> bool {
    let crossings = edges(rings)
        .filter(|(c, d)| {
            (c[1] > p[1]) != (d[1] > p[1])
                && p[0] < c[0] + (p[1] - c[1]) / (d[1] - c[1]) * (d[0] - c[0])
        })
        .count();
    crossings % 2 == 1
}

/// The distance from the segment `a`–`b` to the rings (the polygon's boundary), metres: 0 where
/// it crosses or touches an edge.
pub fn boundary_segment_m(rings: &[Vec<[f64; 2]>], a: [f64; 2], b: [f64; 2]) -> f64 {
    let mut best = f64::INFINITY;
    for (c, d) in edges(rings) {
        best = best.min(segment_segment_m(a, b, c, d));
        if best == 0.0 {
            break;
        }
    }
    best
}

/// The distance from the segment `a`–`b` to the polygon (its closed region), metres: 0 where
/// the segment has a point inside or on an edge.
pub fn region_segment_m(rings: &[Vec<[f64; 2]>], a: [f64; 2], b: [f64; 2]) -> f64 {
    if inside(rings, a) {
        0.0
    } else {
        // Outside at `a`: a segment reaching the region crosses the boundary.
        boundary_segment_m(rings, a, b)
    }
}

/// The distance from the point `p` to the closed rectangle `lo`–`hi`, metres.
fn point_rect_m(p: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let dx = (lo[0] - p[0]).max(p[0] - hi[0]).max(0.0);
    let dy = (lo[1] - p[1]).max(p[1] - hi[1]).max(0.0);
    dx.hypot(dy)
}

/// The distance from the closed rectangle `lo`–`hi` (`lo ≤ hi` on both axes) to the polygon
/// (its closed region), metres: 0 where they share a point.
pub fn region_rect_m(rings: &[Vec<[f64; 2]>], lo: [f64; 2], hi: [f64; 2]) -> f64 {
    if inside(rings, lo) {
        return 0.0;
    }
    let corners = [lo, [lo[0], hi[1]], hi, [hi[0], lo[1]]];
    let mut best = f64::INFINITY;
    for (c, d) in edges(rings) {
        // A segment and a convex rectangle: apart, their distance is an end of the segment to
        // the rectangle or a corner of the rectangle to the segment; an edge crossing a side
        // touches it; one inside the rectangle has its ends in it (distance 0).
        let mut m = point_rect_m(c, lo, hi).min(point_rect_m(d, lo, hi));
        for k in 0..4 {
            if segments_meet(c, d, corners[k], corners[(k + 1) % 4]) {
                return 0.0;
            }
            m = m.min(point_segment_m(corners[k], c, d));
        }
        best = best.min(m);
        if best == 0.0 {
            break;
        }
    }
    // Outside at a corner and no edge meets the rectangle: the rectangle is entirely outside
    // the region (or in a hole).
    best
}
