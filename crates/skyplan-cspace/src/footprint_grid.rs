//! The 2D grid of a footprint map at a flight altitude: exact rasterisation of polygons with
//! holes grown by a disc of radius margin (the Minkowski sum shapely's `buffer` approximates).

use crate::{Grid2, GridError, GridFrame, GridSpec};
use skyplan_map::footprints::FootprintMap;

impl Grid2 {
    /// The occupancy grid of a footprint map at `spec.alt_m`.
    ///
    /// A footprint counts if its height band grown by the margin holds the altitude
    /// ([`Footprint::meets_altitude`](skyplan_map::footprints::Footprint::meets_altitude)). It then blocks every cell whose closed square lies closer
    /// than the margin to the footprint (the region inside the outer ring and outside the
    /// holes, boundary included): the cell's interior meets the footprint grown by a disc of
    /// radius margin. With a zero margin a cell is blocked when its interior meets the footprint.
    /// The extent is laid out as for colliders maps: origin `floor` of the footprints' smallest
    /// north and east (without margin), size `ceil((max − origin) / cell_m)`.
    ///
    /// Work: each edge scans only the cells of its capsule (the edge grown by the margin), row
    /// by row; the interior is filled by a scanline at each row's centre over the footprint's
    /// rows only.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2, GridSpec};
    /// use skyplan_map::colliders::GeodeticHome;
    /// use skyplan_map::footprints::{Footprint, FootprintMap};
    /// // A 4 m square from (0, 0) to (4, 4), 20 m tall, with a 1 m margin.
    /// let square = Footprint { feature: 0, rings: vec![vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]],
    ///                          min_height_m: 0.0, height_m: 20.0 };
    /// let home = GeodeticHome { lat_deg: 37.79, lon_deg: -122.39 };
    /// let map = FootprintMap { home, footprints: vec![square], default_heights: 0 };
    /// let grid = Grid2::from_footprints(&map, GridSpec { alt_m: 10.0, safety_m: 1.0, cell_m: 1.0 })?;
    /// assert_eq!((grid.rows(), grid.cols()), (4, 4));
    /// assert_eq!(grid.blocked_count(), 16);
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn from_footprints(map: &FootprintMap, spec: GridSpec) -> Result<Self, GridError> {
        let GridSpec {
            alt_m,
            safety_m,
            cell_m,
        } = spec;
        crate::colliders_grid::check_spec(spec)?;
        let (lo, hi) = map.bbox_ne();
        let mut grid = Grid2::empty_over(lo, hi, cell_m)?;
        let mut crossings = Vec::new();
        for f in &map.footprints {
            if f.meets_altitude(alt_m, safety_m) {
                block_near_edges(&mut grid, &f.rings, safety_m);
                fill_inside(&mut grid, &f.rings, f.bbox_ne(), &mut crossings);
            }
        }
        grid.forget_count();
        Ok(grid)
    }
}

/// The cell-row range `[r0, r1]` of `grid` (clamped to it) holding norths `lo..=hi`.
fn row_range(grid: &Grid2, lo: f64, hi: f64) -> (i64, i64) {
    let GridFrame {
        origin_north_m: n0,
        cell_m: c,
        ..
    } = grid.frame;
    let r0 = (((lo - n0) / c).floor() as i64).max(0);
    let r1 = (((hi - n0) / c).floor() as i64).min(grid.rows as i64 - 1);
    (r0, r1)
}

/// Blocks the cells of `grid` closer than `margin_m` to an edge of `rings` (with no margin:
/// the cells whose interior an edge crosses); see [`Grid2::from_footprints`].
pub(crate) fn block_near_edges(grid: &mut Grid2, rings: &[Vec<[f64; 2]>], margin_m: f64) {
    grid.forget_count();
    let GridFrame {
        origin_north_m: n0,
        origin_east_m: e0,
        cell_m: c,
    } = grid.frame;
    let cols = grid.cols as i64;
    for ring in rings {
        let n = ring.len();
        for k in 0..n {
            let a = ring[k];
            let b = ring[(k + 1) % n];
            let (r0, r1) = row_range(grid, a[0].min(b[0]) - margin_m, a[0].max(b[0]) + margin_m);
            let capsule = Capsule::new(a, b, margin_m);
            for r in r0..=r1 {
                let y0 = n0 + r as f64 * c;
                let y1 = y0 + c;
                let start = r as usize * cols as usize;
                if margin_m > 0.0 {
                    // The cells of the row closer than the margin to the edge: those whose east
                    // range meets the east extent of the capsule (the edge grown by the margin)
                    // within the row's band, since a cell spans the whole band.
                    let Some((xl, xr)) = capsule.band_span(y0, y1) else {
                        continue;
                    };
                    let c0 = (((xl - e0) / c).floor() as i64).max(0);
                    let c1 = ((((xr - e0) / c).ceil() as i64) - 1).min(cols - 1);
                    if c0 <= c1 {
                        grid.blocked[start + c0 as usize..=start + c1 as usize].fill(true);
                    }
                    continue;
                }
                // East extent of the edge's points whose north lies within the row ± margin.
                let Some((xa, xb)) = east_span(a, b, y0 - margin_m, y1 + margin_m) else {
                    continue;
                };
                let c0 = (((xa - e0) / c).floor() as i64).max(0);
                let c1 = (((xb - e0) / c).floor() as i64).min(cols - 1);
                for col in c0..=c1 {
                    let i = start + col as usize;
                    if grid.blocked[i] {
                        continue; // already blocked: skip the exact test
                    }
                    let x0 = e0 + col as f64 * c;
                    if segment_meets_open_square(a, b, [[y0, x0], [y1, x0 + c]]) {
                        grid.blocked[i] = true;
                    }
                }
            }
        }
    }
}

/// Blocks the cells of `grid` whose centre lies inside `rings` (even-odd over every ring; `bbox`
/// is theirs, `(min, max)`): with [`block_near_edges`], a cell that no edge reaches lies wholly
/// inside or wholly outside.
pub(crate) fn fill_inside(
    grid: &mut Grid2,
    rings: &[Vec<[f64; 2]>],
    (lo, hi): ([f64; 2], [f64; 2]),
    crossings: &mut Vec<f64>,
) {
    grid.forget_count();
    let GridFrame {
        origin_north_m: n0,
        origin_east_m: e0,
        cell_m: c,
    } = grid.frame;
    let cols = grid.cols as i64;
    let (r0, r1) = row_range(grid, lo[0], hi[0]);
    for r in r0..=r1 {
        let y = n0 + (r as f64 + 0.5) * c;
        crossings.clear();
        for ring in rings {
            let n = ring.len();
            for k in 0..n {
                let a = ring[k];
                let b = ring[(k + 1) % n];
                if (a[0] <= y) != (b[0] <= y) {
                    crossings.push(a[1] + (y - a[0]) / (b[0] - a[0]) * (b[1] - a[1]));
                }
            }
        }
        crossings.sort_by(f64::total_cmp);
        let start = r as usize * cols as usize;
        for pair in crossings.chunks_exact(2) {
            // Columns whose centre east lies in [pair[0], pair[1]].
            let c0 = (((pair[0] - e0) / c - 0.5).ceil() as i64).max(0);
            let c1 = (((pair[1] - e0) / c - 0.5).floor() as i64).min(cols - 1);
            if c0 <= c1 {
                grid.blocked[start + c0 as usize..=start + c1 as usize].fill(true);
            }
        }
    }
}

/// The east range `[min, max]` of the points of segment `ab` whose north lies in `[ylo, yhi]`,
/// or `None` if there are none. Points are `[north, east]`.
fn east_span(a: [f64; 2], b: [f64; 2], ylo: f64, yhi: f64) -> Option<(f64, f64)> {
    let dy = b[0] - a[0];
    let (t0, t1) = if dy == 0.0 {
        if a[0] < ylo || a[0] > yhi {
            return None;
        }
        (0.0, 1.0)
    } else {
        let ta = (ylo - a[0]) / dy;
        let tb = (yhi - a[0]) / dy;
        (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
    };
    if t0 > t1 {
        return None;
    }
    let xa = a[1] + t0 * (b[1] - a[1]);
    let xb = a[1] + t1 * (b[1] - a[1]);
    Some((xa.min(xb), xa.max(xb)))
}

/// The open capsule of radius `m` around a segment `ab` (the points closer than `m` to it), as
/// its two end discs and the rectangle the segment's normal sweeps.
struct Capsule {
    ends: [[f64; 2]; 2],
    m: f64,
    /// The rectangle's corners, in order around it (none for a segment of no length).
    corners: Option<[[f64; 2]; 4]>,
    /// The rectangle's lowest and highest north.
    north_range: (f64, f64),
}

impl Capsule {
    fn new(a: [f64; 2], b: [f64; 2], m: f64) -> Self {
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = d[0].hypot(d[1]);
        let corners = (len > 0.0).then(|| {
            let n = [-d[1] / len * m, d[0] / len * m];
            [
                [a[0] + n[0], a[1] + n[1]],
                [b[0] + n[0], b[1] + n[1]],
                [b[0] - n[0], b[1] - n[1]],
                [a[0] - n[0], a[1] - n[1]],
            ]
        });
        let north_range = corners.map_or((0.0, 0.0), |c| {
            let ys = c.map(|p| p[0]);
            (
                ys.iter().fold(f64::INFINITY, |x, &y| x.min(y)),
                ys.iter().fold(f64::NEG_INFINITY, |x, &y| x.max(y)),
            )
        });
        Capsule {
            ends: [a, b],
            m,
            corners,
            north_range,
        }
    }

    /// The east extent `(inf, sup)` of the capsule within the band of norths `[y0, y1]`, or
    /// `None` if they do not meet. The extent of a convex set within a band is reached on the
    /// band's lines or at the capsule's own east-most and west-most points (an end's disc, `m`
    /// east or west of it).
    fn band_span(&self, y0: f64, y1: f64) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in self.ends {
            if p[0] >= y0 && p[0] <= y1 {
                lo = lo.min(p[1] - self.m);
                hi = hi.max(p[1] + self.m);
            }
        }
        for y in [y0, y1] {
            if let Some((l, r)) = self.chord(y) {
                lo = lo.min(l);
                hi = hi.max(r);
            }
        }
        (lo < hi).then_some((lo, hi))
    }

    /// The east extent of the capsule on the line of north `y`: the union of its end discs'
    /// chords and the rectangle's (each convex, the union an interval as the capsule is).
    fn chord(&self, y: f64) -> Option<(f64, f64)> {
        let m = self.m;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in self.ends {
            let dy = y - p[0];
            if dy.abs() < m {
                let h = (m * m - dy * dy).sqrt();
                lo = lo.min(p[1] - h);
                hi = hi.max(p[1] + h);
            }
        }
        // Only a line through the open rectangle (not along a side or through one corner).
        if let Some(corners) = &self.corners
            && y > self.north_range.0
            && y < self.north_range.1
        {
            for k in 0..4 {
                let (p, q) = (corners[k], corners[(k + 1) % 4]);
                if (p[0] - y) * (q[0] - y) <= 0.0 && p[0] != q[0] {
                    let x = p[1] + (y - p[0]) / (q[0] - p[0]) * (q[1] - p[1]);
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
        }
        (lo < hi).then_some((lo, hi))
    }
}

/// The part `[t0, t1]` of segment `ab` inside the closed box `[lo, hi]` (Liang–Barsky), if any.
fn clip(a: [f64; 2], b: [f64; 2], [lo, hi]: [[f64; 2]; 2]) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..2 {
        let d = b[k] - a[k];
        if d == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return None;
            }
        } else {
            let ta = (lo[k] - a[k]) / d;
            let tb = (hi[k] - a[k]) / d;
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// Whether segment `ab` meets the open square: its part in the closed square has its midpoint
/// strictly inside (a segment in a convex set that reaches the interior anywhere has its whole
/// relative interior there).
fn segment_meets_open_square(a: [f64; 2], b: [f64; 2], square: [[f64; 2]; 2]) -> bool {
    let Some((t0, t1)) = clip(a, b, square) else {
        return false;
    };
    let t = 0.5 * (t0 + t1);
    let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    let [lo, hi] = square;
    p[0] > lo[0] && p[0] < hi[0] && p[1] > lo[1] && p[1] < hi[1]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use skyplan_map::colliders::{CollidersMap, GeodeticHome, ObstacleBox};
    use skyplan_map::footprints::Footprint;

    const HOME: GeodeticHome = GeodeticHome {
        lat_deg: 37.7925,
        lon_deg: -122.3975,
    };

    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A random star-shaped (so simple, usually concave) ring about a centre.
    fn star(rng: &mut Rng, centre: [f64; 2], r_min: f64, r_max: f64, n: usize) -> Vec<[f64; 2]> {
        (0..n)
            .map(|k| {
                let a = (k as f64 + 0.8 * rng.unit()) / n as f64 * std::f64::consts::TAU;
                let r = r_min + (r_max - r_min) * rng.unit();
                [centre[0] + r * a.sin(), centre[1] + r * a.cos()]
            })
            .collect()
    }

    /// Random concave footprints with holes; some out of the altitude band.
    pub(crate) fn random_map(seed: u64, count: usize) -> FootprintMap {
        let mut rng = Rng(seed | 1);
        let footprints = (0..count)
            .map(|i| {
                let centre = [60.0 * rng.unit(), 60.0 * rng.unit()];
                let n = 3 + (rng.unit() * 12.0) as usize;
                let mut rings = vec![star(&mut rng, centre, 6.0, 14.0, n)];
                if rng.unit() < 0.6 {
                    // A hole inside the outer ring's inner radius.
                    let holes = 3 + (rng.unit() * 6.0) as usize;
                    rings.push(star(&mut rng, centre, 1.0, 5.0, holes));
                }
                let min_height_m = if rng.unit() < 0.2 { 30.0 } else { 0.0 };
                Footprint {
                    feature: i,
                    rings,
                    min_height_m,
                    height_m: min_height_m + 5.0 + 40.0 * rng.unit(),
                }
            })
            .collect();
        FootprintMap {
            home: HOME,
            footprints,
            default_heights: 0,
        }
    }

    fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    }
    fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
        orient(a, b, c) * orient(a, b, d) <= 0.0 && orient(c, d, a) * orient(c, d, b) <= 0.0
    }
    fn seg_seg2(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
        if cross(a, b, c, d) {
            return 0.0;
        }
        point_segment_dist2(a, c, d)
            .min(point_segment_dist2(b, c, d))
            .min(point_segment_dist2(c, a, b))
            .min(point_segment_dist2(d, a, b))
    }
    fn winding(p: [f64; 2], ring: &[[f64; 2]]) -> i32 {
        let mut w = 0;
        for k in 0..ring.len() {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            if a[0] <= p[0] && b[0] > p[0] && orient(a, b, p) > 0.0 {
                w += 1;
            } else if a[0] > p[0] && b[0] <= p[0] && orient(a, b, p) < 0.0 {
                w -= 1;
            }
        }
        w
    }

    /// Independent truth for one cell, the closed square `[lo, hi]`, against a polygon's
    /// `rings`: whether its centre lies inside (winding numbers), and whether an edge comes
    /// closer than `margin_m` (segment–segment distances to the square's four sides).
    pub(crate) fn brute_cell(
        rings: &[Vec<[f64; 2]>],
        lo: [f64; 2],
        hi: [f64; 2],
        margin_m: f64,
    ) -> (bool, bool) {
        let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let sides = [
            (lo, [lo[0], hi[1]]),
            ([lo[0], hi[1]], hi),
            (hi, [hi[0], lo[1]]),
            ([hi[0], lo[1]], lo),
        ];
        let inside =
            winding(centre, &rings[0]) != 0 && rings[1..].iter().all(|h| winding(centre, h) == 0);
        let near = rings.iter().any(|ring| {
            (0..ring.len()).any(|k| {
                let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                let inside_square =
                    (lo[0]..=hi[0]).contains(&a[0]) && (lo[1]..=hi[1]).contains(&a[1]);
                let d2 = if inside_square {
                    0.0
                } else {
                    sides
                        .iter()
                        .map(|&(c, d)| seg_seg2(a, b, c, d))
                        .fold(f64::INFINITY, f64::min)
                };
                d2 < margin_m * margin_m
            })
        });
        (inside, near)
    }

    /// Independent truth: every cell against every edge ([`brute_cell`]).
    fn brute_force(
        map: &FootprintMap,
        spec: GridSpec,
        frame: GridFrame,
        rows: u32,
        cols: u32,
    ) -> Vec<bool> {
        let mut out = vec![false; rows as usize * cols as usize];
        for r in 0..rows {
            for col in 0..cols {
                let lo = [
                    frame.origin_north_m + f64::from(r) * frame.cell_m,
                    frame.origin_east_m + f64::from(col) * frame.cell_m,
                ];
                let hi = [lo[0] + frame.cell_m, lo[1] + frame.cell_m];
                out[r as usize * cols as usize + col as usize] = map
                    .footprints
                    .iter()
                    .filter(|f| f.meets_altitude(spec.alt_m, spec.safety_m))
                    .any(|f| {
                        let (inside, near) = brute_cell(&f.rings, lo, hi, spec.safety_m);
                        inside || near
                    });
            }
        }
        out
    }

    #[test]
    fn matches_brute_force_on_random_concave_polygons_with_holes() {
        let mut compared = 0;
        for seed in 1..=6u64 {
            let map = random_map(seed * 7919, 12);
            for (alt_m, safety_m, cell_m) in [(10.0, 2.5, 1.0), (35.0, 0.7, 0.5), (20.0, 4.0, 2.0)]
            {
                let spec = GridSpec {
                    alt_m,
                    safety_m,
                    cell_m,
                };
                let grid = Grid2::from_footprints(&map, spec).unwrap();
                let want = brute_force(&map, spec, grid.frame(), grid.rows(), grid.cols());
                let differ: Vec<Cell> = (0..grid.len())
                    .filter(|&i| grid.blocked_cells()[i] != want[i])
                    .map(|i| grid.cell(i))
                    .collect();
                assert!(
                    differ.is_empty(),
                    "seed {seed}, spec {spec:?}: {} cells differ, first {:?}",
                    differ.len(),
                    differ.first()
                );
                assert!(grid.blocked_count() > 0 && grid.blocked_count() < grid.len());
                compared += grid.len();
            }
        }
        assert!(compared > 50_000);
    }

    use crate::Cell;

    /// Axis-aligned rectangles: with no margin the same cells as the colliders grid of the same
    /// boxes; with a margin, a subset of the colliders grid (a box grown by a square) that
    /// differs only near the corners.
    #[test]
    fn rectangles_agree_with_the_colliders_grid() {
        let mut rng = Rng(99);
        let mut boxes = Vec::new();
        let mut footprints = Vec::new();
        for i in 0..30 {
            let (n, e) = (100.0 * rng.unit(), 100.0 * rng.unit());
            let (hn, he) = (1.0 + 8.0 * rng.unit(), 1.0 + 8.0 * rng.unit());
            boxes.push(ObstacleBox::from_row([n, e, 15.0, hn, he, 15.0]));
            footprints.push(Footprint {
                feature: i,
                rings: vec![vec![
                    [n - hn, e - he],
                    [n - hn, e + he],
                    [n + hn, e + he],
                    [n + hn, e - he],
                ]],
                min_height_m: 0.0,
                height_m: 30.0,
            });
        }
        let fmap = FootprintMap {
            home: HOME,
            footprints,
            default_heights: 0,
        };
        let cmap = CollidersMap { home: HOME, boxes };
        for (safety_m, cell_m) in [(0.0, 1.0), (0.0, 0.7), (3.0, 1.0)] {
            let spec = GridSpec {
                alt_m: 10.0,
                safety_m,
                cell_m,
            };
            let f = Grid2::from_footprints(&fmap, spec).unwrap();
            let c = Grid2::from_colliders(&cmap, spec).unwrap();
            assert_eq!(
                (f.rows(), f.cols(), f.frame()),
                (c.rows(), c.cols(), c.frame())
            );
            if safety_m == 0.0 {
                assert_eq!(f.blocked_cells(), c.blocked_cells(), "cell {cell_m}");
            } else {
                let only_f = (0..f.len())
                    .filter(|&i| f.blocked_cells()[i] && !c.blocked_cells()[i])
                    .count();
                let only_c = (0..f.len())
                    .filter(|&i| !f.blocked_cells()[i] && c.blocked_cells()[i])
                    .count();
                assert_eq!(only_f, 0);
                // Rounded corners free a few cells at each box corner, never more than the corners hold.
                assert!(only_c > 0 && only_c <= 30 * 4 * 9, "{only_c}");
            }
        }
    }

    #[test]
    fn altitude_band_and_hole_are_honoured() {
        // A 20 m square with a 10 m square hole, from 10 m to 30 m.
        let ring = |lo: f64, hi: f64| vec![[lo, lo], [lo, hi], [hi, hi], [hi, lo]];
        let f = Footprint {
            feature: 0,
            rings: vec![ring(0.0, 20.0), ring(5.0, 15.0)],
            min_height_m: 10.0,
            height_m: 30.0,
        };
        let map = FootprintMap {
            home: HOME,
            footprints: vec![f],
            default_heights: 0,
        };
        let at = |alt_m: f64, safety_m: f64| {
            Grid2::from_footprints(
                &map,
                GridSpec {
                    alt_m,
                    safety_m,
                    cell_m: 1.0,
                },
            )
            .unwrap()
            .blocked_count()
        };
        assert_eq!(at(20.0, 0.0), 400 - 100);
        assert_eq!(at(20.0, 1.0), 400 - 64); // the hole shrinks by the margin on each side
        assert_eq!(at(5.0, 1.0), 0);
        assert_eq!(at(9.5, 1.0), 400 - 64);
        assert_eq!(at(31.0, 1.0), 0);
    }

    // The per-cell exact distance the capsule spans replaced, kept as their oracle.
    fn point_square_dist2(p: [f64; 2], [lo, hi]: [[f64; 2]; 2]) -> f64 {
        let dy = (lo[0] - p[0]).max(p[0] - hi[0]).max(0.0);
        let dx = (lo[1] - p[1]).max(p[1] - hi[1]).max(0.0);
        dy * dy + dx * dx
    }

    fn point_segment_dist2(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
        let d = [b[0] - a[0], b[1] - a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        let t = if len2 > 0.0 {
            (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let q = [a[0] + t * d[0] - p[0], a[1] + t * d[1] - p[1]];
        q[0] * q[0] + q[1] * q[1]
    }

    /// Squared distance between segment `ab` and the closed square: 0 if they meet, else the
    /// smallest of the endpoint-to-square and corner-to-segment distances (two disjoint convex
    /// sets are closest at a vertex of one of them).
    fn segment_square_dist2(a: [f64; 2], b: [f64; 2], square: [[f64; 2]; 2]) -> f64 {
        if clip(a, b, square).is_some() {
            return 0.0;
        }
        let [lo, hi] = square;
        let corners = [lo, [lo[0], hi[1]], hi, [hi[0], lo[1]]];
        corners.iter().map(|&q| point_segment_dist2(q, a, b)).fold(
            point_square_dist2(a, square).min(point_square_dist2(b, square)),
            f64::min,
        )
    }

    /// The capsule's span within a row band blocks exactly the cells of that row whose
    /// distance to the segment is under the margin, on random segments, bands and margins.
    #[test]
    fn capsule_spans_equal_the_per_cell_distance_test() {
        let mut rng = Rng(4242);
        let mut checked = 0;
        for _ in 0..3000 {
            let a = [20.0 * rng.unit(), 20.0 * rng.unit()];
            let b = if rng.unit() < 0.15 {
                // Axis-aligned and degenerate edges, on the cell lines too.
                [a[0].round(), (a[1] + 10.0 * rng.unit()).round()]
            } else {
                [20.0 * rng.unit(), 20.0 * rng.unit()]
            };
            let a = if rng.unit() < 0.1 {
                [a[0].round(), a[1].round()]
            } else {
                a
            };
            let m = [0.5, 1.0, 2.5, 4.0][(rng.unit() * 4.0) as usize % 4];
            let y0 = (rng.unit() * 20.0).floor();
            let span = Capsule::new(a, b, m).band_span(y0, y0 + 1.0);
            for col in -8..30 {
                let x0 = col as f64;
                let want = segment_square_dist2(a, b, [[y0, x0], [y0 + 1.0, x0 + 1.0]]) < m * m;
                let got = span.is_some_and(|(l, r)| x0 < r && x0 + 1.0 > l);
                assert_eq!(
                    got, want,
                    "a {a:?} b {b:?} m {m} band {y0} col {col}: span {span:?}"
                );
                checked += 1;
            }
        }
        assert!(checked > 100_000);
    }

    #[test]
    fn segment_square_distance_cases() {
        let sq = [[0.0, 0.0], [1.0, 1.0]];
        assert_eq!(segment_square_dist2([2.0, -5.0], [2.0, 5.0], sq), 1.0);
        assert_eq!(segment_square_dist2([-1.0, 0.5], [2.0, 0.5], sq), 0.0);
        assert!((segment_square_dist2([3.0, 0.0], [0.0, 3.0], sq) - 0.5).abs() < 1e-12);
        assert!(segment_meets_open_square([-1.0, 0.5], [2.0, 0.5], sq));
        assert!(!segment_meets_open_square([-1.0, 1.0], [2.0, 1.0], sq));
        assert!(!segment_meets_open_square([1.0, 1.0], [2.0, 3.0], sq));
    }
}
