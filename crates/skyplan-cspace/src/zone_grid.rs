//! No-fly zones on a grid at a flight altitude: exclusion zones grown by the margin block the
//! cells they meet, an inclusion boundary shrunk by the margin blocks every cell that leaves it.

use crate::footprint_grid::{block_near_edges, fill_inside};
use crate::{Grid2, GridError, GridFrame, GridSpec};
use skyplan_map::nofly::{Zone, ZoneShape};

impl Grid2 {
    /// Blocks the cells that `zones` forbid at `spec.alt_m` with the margin `spec.safety_m`
    /// (`spec.cell_m` is not used: the grid keeps its frame); the number of cells newly blocked.
    ///
    /// - An exclusion zone counts when its band grown by the margin holds the altitude
    ///   ([`Zone::meets_altitude`]); it then blocks every cell whose interior meets the zone
    ///   grown by the margin, exactly as a building's footprint ([`Grid2::from_footprints`]):
    ///   a polygon's Minkowski sum with a disc, a circle of radius `radius + margin`.
    /// - An inclusion zone blocks every cell whose interior leaves the zone shrunk by the margin
    ///   (comes closer than the margin to its boundary or lies outside it): a circle of radius
    ///   `radius − margin`, a polygon less the outside grown by the margin. If its band shrunk by
    ///   the margin does not hold the altitude ([`Zone::holds_altitude`]), every cell is blocked.
    ///
    /// ```
    /// use skyplan_cspace::{Grid2, GridFrame, GridSpec};
    /// use skyplan_map::nofly::{Zone, ZoneShape};
    /// let mut grid = Grid2::new(10, 10, vec![false; 100], GridFrame::default())?;
    /// let circle = Zone { feature: 0, shape: ZoneShape::Circle { centre: [5.0, 5.0], radius_m: 1.0 },
    ///                     floor_m: 0.0, ceiling_m: 50.0, inclusion: false, start_unix_s: None, end_unix_s: None };
    /// // Grown to 2 m: the 4 × 4 cells around the centre (the corner cells' nearest point is
    /// // √2 m away; the next cells' nearest points are 2 m away, not closer).
    /// let spec = GridSpec { alt_m: 10.0, safety_m: 1.0, cell_m: 1.0 };
    /// assert_eq!(grid.block_zones(&[circle.clone()], spec)?, 16);
    /// // Above the band (50 m + 1 m margin) it does not count.
    /// let mut free = Grid2::new(10, 10, vec![false; 100], GridFrame::default())?;
    /// assert_eq!(free.block_zones(&[circle], GridSpec { alt_m: 51.0, ..spec })?, 0);
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn block_zones(&mut self, zones: &[Zone], spec: GridSpec) -> Result<usize, GridError> {
        crate::colliders_grid::check_spec(spec)?;
        let GridSpec {
            alt_m,
            safety_m: margin_m,
            ..
        } = spec;
        let before = self.blocked_count();
        let mut crossings = Vec::new();
        for z in zones {
            if z.inclusion {
                if !z.holds_altitude(alt_m, margin_m) {
                    self.blocked.fill(true);
                    self.forget_count();
                    continue;
                }
                match &z.shape {
                    ZoneShape::Circle { centre, radius_m } => {
                        let inner = radius_m - margin_m;
                        self.mark_cells(|lo, hi| {
                            // The farthest point of the closed square from the centre.
                            let dn = (centre[0] - lo[0]).abs().max((hi[0] - centre[0]).abs());
                            let de = (centre[1] - lo[1]).abs().max((hi[1] - centre[1]).abs());
                            inner < 0.0 || dn * dn + de * de > inner * inner
                        });
                    }
                    ZoneShape::Polygon(rings) => {
                        let mut near = self.clone();
                        near.blocked.fill(false);
                        block_near_edges(&mut near, rings, margin_m);
                        let mut inside = near.clone();
                        inside.blocked.fill(false);
                        fill_inside(&mut inside, rings, z.bbox_ne(), &mut crossings);
                        for ((b, n), i) in self
                            .blocked
                            .iter_mut()
                            .zip(&near.blocked)
                            .zip(&inside.blocked)
                        {
                            *b |= *n || !*i;
                        }
                    }
                }
            } else if z.meets_altitude(alt_m, margin_m) {
                match &z.shape {
                    ZoneShape::Circle { centre, radius_m } => {
                        let grown = radius_m + margin_m;
                        self.mark_cells_near(*centre, grown, |lo, hi| {
                            let dn = (lo[0] - centre[0]).max(centre[0] - hi[0]).max(0.0);
                            let de = (lo[1] - centre[1]).max(centre[1] - hi[1]).max(0.0);
                            dn * dn + de * de < grown * grown
                        });
                    }
                    ZoneShape::Polygon(rings) => {
                        block_near_edges(self, rings, margin_m);
                        fill_inside(self, rings, z.bbox_ne(), &mut crossings);
                    }
                }
            }
        }
        self.forget_count();
        Ok(self.blocked_count() - before)
    }

    /// Blocks every cell whose closed square `[lo, hi]` (`[north, east]`) `hit` holds.
    fn mark_cells(&mut self, hit: impl Fn([f64; 2], [f64; 2]) -> bool) {
        let GridFrame {
            origin_north_m: n0,
            origin_east_m: e0,
            cell_m: c,
        } = self.frame;
        self.forget_count();
        let cols = self.cols as usize;
        for (i, b) in self.blocked.iter_mut().enumerate() {
            if !*b {
                let lo = [n0 + (i / cols) as f64 * c, e0 + (i % cols) as f64 * c];
                *b = hit(lo, [lo[0] + c, lo[1] + c]);
            }
        }
    }

    /// [`Grid2::mark_cells`] over the cells within `radius_m` (north and east) of `centre` only.
    fn mark_cells_near(
        &mut self,
        centre: [f64; 2],
        radius_m: f64,
        hit: impl Fn([f64; 2], [f64; 2]) -> bool,
    ) {
        self.forget_count();
        let GridFrame {
            origin_north_m: n0,
            origin_east_m: e0,
            cell_m: c,
        } = self.frame;
        let span = |x: f64, o: f64, n: u32| {
            let a = (((x - radius_m - o) / c).floor() as i64).max(0);
            let b = (((x + radius_m - o) / c).floor() as i64).min(i64::from(n) - 1);
            a..=b
        };
        let cols = self.cols as usize;
        for r in span(centre[0], n0, self.rows) {
            for k in span(centre[1], e0, self.cols) {
                let i = r as usize * cols + k as usize;
                if !self.blocked[i] {
                    let lo = [n0 + r as f64 * c, e0 + k as f64 * c];
                    self.blocked[i] = hit(lo, [lo[0] + c, lo[1] + c]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::footprint_grid::tests::{brute_cell, random_map};

    fn zone(feature: usize, shape: ZoneShape, band: [f64; 2], inclusion: bool) -> Zone {
        Zone {
            feature,
            shape,
            floor_m: band[0],
            ceiling_m: band[1],
            inclusion,
            start_unix_s: None,
            end_unix_s: None,
        }
    }

    /// Exclusion polygons and circles (some out of the band) and one inclusion polygon or
    /// circle, from the footprint tests' random concave polygons with holes.
    fn random_zones(seed: u64) -> Vec<Zone> {
        let map = random_map(seed, 10);
        let mut zones: Vec<Zone> = map
            .footprints
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let band = [f.min_height_m, f.height_m];
                if i % 3 == 0 {
                    let c = f.rings[0][0];
                    let shape = ZoneShape::Circle {
                        centre: c,
                        radius_m: 1.0 + (f.height_m % 7.0),
                    };
                    zone(i, shape, band, false)
                } else {
                    zone(i, ZoneShape::Polygon(f.rings.clone()), band, false)
                }
            })
            .collect();
        // An inclusion boundary around most of the map: the first footprint's outer ring
        // scaled up about its bounding box's centre, moved to (35, 30).
        let ring = &map.footprints[0].rings[0];
        let (lo, hi) = map.footprints[0].bbox_ne();
        let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let big: Vec<[f64; 2]> = ring
            .iter()
            .map(|p| [35.0 + 3.0 * (p[0] - mid[0]), 30.0 + 3.0 * (p[1] - mid[1])])
            .collect();
        let shape = if seed.is_multiple_of(2) {
            ZoneShape::Polygon(vec![big])
        } else {
            ZoneShape::Circle {
                centre: [35.0, 30.0],
                radius_m: 33.0,
            }
        };
        zones.push(zone(99, shape, [0.0, f64::INFINITY], true));
        zones
    }

    /// Independent truth: each cell against each zone (distances from the square's sides and
    /// corners, winding numbers).
    fn brute_force(grid: &Grid2, zones: &[Zone], spec: GridSpec) -> Vec<bool> {
        let f = grid.frame();
        let (alt, m) = (spec.alt_m, spec.safety_m);
        (0..grid.len())
            .map(|i| {
                let cell = grid.cell(i);
                let lo = [
                    f.origin_north_m + f64::from(cell.row) * f.cell_m,
                    f.origin_east_m + f64::from(cell.col) * f.cell_m,
                ];
                let hi = [lo[0] + f.cell_m, lo[1] + f.cell_m];
                let corners = [lo, [lo[0], hi[1]], hi, [hi[0], lo[1]]];
                zones.iter().any(|z| {
                    let grown = z.floor_m - m < alt && alt < z.ceiling_m + m;
                    let shrunk = z.floor_m + m <= alt && alt <= z.ceiling_m - m;
                    match (&z.shape, z.inclusion) {
                        (ZoneShape::Polygon(rings), false) => {
                            let (inside, near) = brute_cell(rings, lo, hi, m);
                            grown && (inside || near)
                        }
                        (ZoneShape::Polygon(rings), true) => {
                            let (inside, near) = brute_cell(rings, lo, hi, m);
                            !shrunk || !inside || near
                        }
                        (&ZoneShape::Circle { centre, radius_m }, false) => {
                            // The centre inside the square, or a side within reach.
                            let inside = (lo[0]..=hi[0]).contains(&centre[0])
                                && (lo[1]..=hi[1]).contains(&centre[1]);
                            let side = (0..4)
                                .map(|k| {
                                    let (a, b) = (corners[k], corners[(k + 1) % 4]);
                                    let t = ((centre[0] - a[0]) * (b[0] - a[0])
                                        + (centre[1] - a[1]) * (b[1] - a[1]))
                                        / (f.cell_m * f.cell_m);
                                    let t = t.clamp(0.0, 1.0);
                                    let q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                                    (q[0] - centre[0]).hypot(q[1] - centre[1])
                                })
                                .fold(f64::INFINITY, f64::min);
                            grown && (inside || side < radius_m + m)
                        }
                        (&ZoneShape::Circle { centre, radius_m }, true) => {
                            let far = corners
                                .iter()
                                .map(|q| (q[0] - centre[0]).hypot(q[1] - centre[1]))
                                .fold(0.0, f64::max);
                            !shrunk || far > radius_m - m
                        }
                    }
                })
            })
            .collect()
    }

    #[test]
    fn matches_brute_force_on_random_zones() {
        let mut compared = 0;
        let mut blocked = 0;
        for seed in 1..=6u64 {
            let zones = random_zones(seed * 6113);
            for (alt_m, safety_m, cell_m) in [(10.0, 2.5, 1.0), (35.0, 0.7, 0.5), (20.0, 4.0, 2.0)]
            {
                let spec = GridSpec {
                    alt_m,
                    safety_m,
                    cell_m,
                };
                let frame = GridFrame {
                    origin_north_m: -20.0,
                    origin_east_m: -15.0,
                    cell_m,
                };
                let n = (110.0 / cell_m) as u32;
                let mut grid = Grid2::new(n, n, vec![false; (n * n) as usize], frame).unwrap();
                let count = grid.block_zones(&zones, spec).unwrap();
                assert_eq!(count, grid.blocked_count());
                let want = brute_force(&grid, &zones, spec);
                let differ: Vec<usize> = (0..grid.len())
                    .filter(|&i| grid.blocked_cells()[i] != want[i])
                    .collect();
                assert!(
                    differ.is_empty(),
                    "seed {seed}, spec {spec:?}: {} cells differ, first {:?}",
                    differ.len(),
                    differ.first().map(|&i| grid.cell(i))
                );
                // Neither all nor nothing: the inclusion boundary leaves room inside.
                assert!(
                    count > grid.len() / 10 && grid.len() - count > grid.len() / 50,
                    "seed {seed}: {count} of {} blocked",
                    grid.len()
                );
                compared += grid.len();
                blocked += count;
            }
        }
        assert!(compared > 50_000 && blocked > 10_000);
    }

    #[test]
    fn bands_decide_which_zones_count() {
        let square = ZoneShape::Polygon(vec![vec![[2.0, 2.0], [2.0, 6.0], [6.0, 6.0], [6.0, 2.0]]]);
        let at = |z: &Zone, alt_m: f64| {
            let mut g = Grid2::new(10, 10, vec![false; 100], GridFrame::default()).unwrap();
            let spec = GridSpec {
                alt_m,
                safety_m: 1.0,
                cell_m: 1.0,
            };
            g.block_zones(std::slice::from_ref(z), spec).unwrap()
        };
        // Exclusion 20–40 m grown by 1 m: counts strictly between 19 and 41 m; the 4 × 4
        // square grown by 1 m blocks 6 × 6 cells (the corner cells touch the square's corners).
        let ex = zone(0, square.clone(), [20.0, 40.0], false);
        assert_eq!(at(&ex, 30.0), 36);
        assert_eq!(at(&ex, 19.5), 36);
        assert_eq!(at(&ex, 19.0), 0);
        assert_eq!(at(&ex, 41.0), 0);
        assert_eq!(at(&ex, 10.0), 0);
        // Inclusion 0–50 m shrunk by 1 m: 1 ≤ alt ≤ 49 flies inside a 2 × 2 core; elsewhere
        // nothing is free.
        let inc = zone(1, square, [0.0, 50.0], true);
        assert_eq!(at(&inc, 25.0), 100 - 4);
        assert_eq!(at(&inc, 49.0), 100 - 4);
        assert_eq!(at(&inc, 49.5), 100);
        assert_eq!(at(&inc, 0.5), 100);
    }
}
