//! Plane geometry for the conflict test: a local metric plane, convex hulls, the separating
//! axis test between convex polygons and its brute-force oracle.
//!
//! Latitude and longitude are mapped to metres by an equirectangular plane about a reference
//! point ([`LocalPlane`]): `x = Δlng · cos(lat₀) · m`, `y = Δlat · m`. The map is affine in
//! (lat, lng), so whether two polygons intersect does not depend on the reference (an affine
//! map keeps convexity and intersection); the reference only keeps the numbers small. Polygons
//! across the ±180° meridian are not supported (their longitudes are not unwrapped).

use crate::model::{LatLng, Polygon};

/// Metres per degree of latitude (and of longitude at the equator) on the plane: the WGS84
/// equatorial circumference over 360.
pub const M_PER_DEG: f64 = 111_319.490_793_273_57;

/// An equirectangular plane about a reference point, in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalPlane {
    lat0: f64,
    lng0: f64,
    x_per_deg: f64,
}

impl LocalPlane {
    /// The plane about `origin`.
    pub fn about(origin: LatLng) -> Self {
        Self {
            lat0: origin.lat,
            lng0: origin.lng,
            x_per_deg: origin.lat.to_radians().cos() * M_PER_DEG,
        }
    }

    /// `p` on the plane: `[x east, y north]`, metres.
    pub fn xy(&self, p: LatLng) -> [f64; 2] {
        [
            (p.lng - self.lng0) * self.x_per_deg,
            (p.lat - self.lat0) * M_PER_DEG,
        ]
    }

    /// The point at `xy` on the plane (the inverse of [`LocalPlane::xy`]).
    pub fn lat_lng(&self, xy: [f64; 2]) -> LatLng {
        LatLng {
            lat: self.lat0 + xy[1] / M_PER_DEG,
            lng: self.lng0 + xy[0] / self.x_per_deg,
        }
    }
}

/// `(b − a) × (c − a)`: positive when `a, b, c` turn left.
pub fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The convex hull of `points`, counter-clockwise from the lowest-leftmost point, without
/// collinear or repeated points (Andrew's monotone chain).
pub fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p: Vec<[f64; 2]> = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Twice the signed area of a polygon (positive counter-clockwise).
pub fn area2(poly: &[[f64; 2]]) -> f64 {
    (0..poly.len())
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

/// Smallest area, square metres, of a polygon the conflict test takes.
pub const MIN_AREA_M2: f64 = 1e-4;

/// A polygon's convex hull on a plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Hull {
    /// Counter-clockwise vertices, metres.
    pub points: Vec<[f64; 2]>,
}

impl Hull {
    /// The hull of `polygon` on `plane`.
    pub fn on(plane: &LocalPlane, polygon: &Polygon) -> Self {
        let pts: Vec<[f64; 2]> = polygon.vertices.iter().map(|&v| plane.xy(v)).collect();
        Self {
            points: convex_hull(&pts),
        }
    }

    /// The hull of `polygon` on the plane about its first vertex, if it has 3 vertices and an
    /// area of at least [`MIN_AREA_M2`].
    pub fn of_polygon(polygon: &Polygon) -> Option<Self> {
        let first = *polygon.vertices.first()?;
        let hull = Self::on(&LocalPlane::about(first), polygon);
        (hull.points.len() >= 3 && area2(&hull.points) >= 2.0 * MIN_AREA_M2).then_some(hull)
    }
}

/// The range of `poly` projected on `axis`.
fn project(poly: &[[f64; 2]], axis: [f64; 2]) -> (f64, f64) {
    poly.iter()
        .map(|p| p[0] * axis[0] + p[1] * axis[1])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        })
}

/// Whether an edge normal of `a` separates `a` and `b` (strictly: touching is not separated).
fn separated_by_edges_of(a: &[[f64; 2]], b: &[[f64; 2]]) -> bool {
    (0..a.len()).any(|i| {
        let (p, q) = (a[i], a[(i + 1) % a.len()]);
        let axis = [q[1] - p[1], p[0] - q[0]];
        let (a_lo, a_hi) = project(a, axis);
        let (b_lo, b_hi) = project(b, axis);
        a_hi < b_lo || b_hi < a_lo
    })
}

/// Whether two convex polygons (counter-clockwise hulls of 3 or more points) share a point,
/// by separating axes: two convex polygons are disjoint exactly when the normal of one of
/// their edges separates them.
pub fn convex_intersect(a: &[[f64; 2]], b: &[[f64; 2]]) -> bool {
    !separated_by_edges_of(a, b) && !separated_by_edges_of(b, a)
}

/// Whether `p` lies in the convex counter-clockwise polygon `poly`, its boundary included.
pub fn contains(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    (0..poly.len()).all(|i| cross(poly[i], poly[(i + 1) % poly.len()], p) >= 0.0)
}

/// Whether the closed segments `ab` and `cd` share a point (orientation tests).
pub fn segments_intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on(c, d, a))
        || (d2 == 0.0 && on(c, d, b))
        || (d3 == 0.0 && on(a, b, c))
        || (d4 == 0.0 && on(a, b, d))
}

/// The brute-force oracle of [`convex_intersect`]: some pair of edges crosses, or a vertex
/// of one polygon lies inside the other.
pub fn convex_intersect_brute(a: &[[f64; 2]], b: &[[f64; 2]]) -> bool {
    let edges = |p: &[[f64; 2]]| {
        (0..p.len())
            .map(|i| (p[i], p[(i + 1) % p.len()]))
            .collect::<Vec<_>>()
    };
    let (ea, eb) = (edges(a), edges(b));
    ea.iter()
        .any(|&(p, q)| eb.iter().any(|&(r, s)| segments_intersect(p, q, r, s)))
        || a.iter().any(|&p| contains(b, p))
        || b.iter().any(|&p| contains(a, p))
}

/// The convex hull of `points` grown by `radius`: each point replaced by a regular `sides`-gon
/// circumscribed about the disc of `radius` around it, so the result holds every point within
/// `radius` of the hull.
pub fn buffered_hull(points: &[[f64; 2]], radius: f64, sides: usize) -> Vec<[f64; 2]> {
    let sides = sides.max(3);
    let r = radius / (std::f64::consts::PI / sides as f64).cos();
    let mut grown = Vec::with_capacity(points.len() * sides);
    for &p in &convex_hull(points) {
        for k in 0..sides {
            let angle = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / sides as f64;
            grown.push([p[0] + r * angle.cos(), p[1] + r * angle.sin()]);
        }
    }
    convex_hull(&grown)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn point() -> impl Strategy<Value = [f64; 2]> {
        prop_oneof![
            (0i32..12, 0i32..12).prop_map(|(x, y)| [f64::from(x), f64::from(y)]),
            (-50.0..50.0f64, -50.0..50.0f64).prop_map(|(x, y)| [x, y]),
        ]
    }

    fn polygon() -> impl Strategy<Value = Vec<[f64; 2]>> {
        proptest::collection::vec(point(), 3..9)
            .prop_map(|p| convex_hull(&p))
            .prop_filter("a polygon with area", |h| h.len() >= 3 && area2(h) > 0.0)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        #[test]
        fn separating_axes_agree_with_brute_force(a in polygon(), b in polygon()) {
            prop_assert_eq!(convex_intersect(&a, &b), convex_intersect_brute(&a, &b), "{:?} {:?}", a, b);
        }

        #[test]
        fn a_hull_holds_its_points_and_turns_left(pts in proptest::collection::vec(point(), 3..30)) {
            let h = convex_hull(&pts);
            prop_assume!(h.len() >= 3);
            for i in 0..h.len() {
                prop_assert!(cross(h[i], h[(i + 1) % h.len()], h[(i + 2) % h.len()]) > 0.0);
            }
            // Exact on the integer points; within rounding on the others.
            for p in &pts {
                let inside = (0..h.len()).all(|i| cross(h[i], h[(i + 1) % h.len()], *p) >= -1e-9);
                prop_assert!(inside, "{:?} outside {:?}", p, h);
            }
        }

        #[test]
        fn a_buffered_hull_holds_the_disc(pts in proptest::collection::vec(point(), 1..10), r in 0.1..30.0f64, angle in 0.0..6.3f64) {
            let h = buffered_hull(&pts, r, 8);
            for p in &pts {
                let q = [p[0] + r * angle.cos(), p[1] + r * angle.sin()];
                prop_assert!(contains(&h, q));
            }
        }
    }

    #[test]
    fn touching_polygons_intersect() {
        let a = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let corner = [[1.0, 1.0], [2.0, 1.0], [2.0, 2.0]];
        let edge = [[1.0, 0.5], [2.0, 0.0], [2.0, 1.0]];
        let apart = [[1.0 + 1e-9, 0.0], [2.0, 0.0], [2.0, 1.0]];
        assert!(convex_intersect(&a, &corner) && convex_intersect_brute(&a, &corner));
        assert!(convex_intersect(&a, &edge) && convex_intersect_brute(&a, &edge));
        assert!(!convex_intersect(&a, &apart) && !convex_intersect_brute(&a, &apart));
    }
}
