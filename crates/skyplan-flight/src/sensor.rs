//! The simulated horizontal range sensor: one ray per sector, cast at the vehicle's altitude
//! against the true world's obstacles (exact 2D ray–rectangle and ray–polygon intersection, no
//! sampling).
//!
//! An obstacle takes part when its vertical extent covers the altitude (faces included); the
//! ray from the vehicle's north/east position along a bearing (radians clockwise from north)
//! hits a box's footprint at the entry distance of the slab test, a building's polygon where it
//! first crosses an edge, or at 0 when the vehicle is inside it.
//!
//! ```
//! use skyplan_flight::collision::BoxWorld;
//! use skyplan_flight::sensing::SectorRange;
//! use skyplan_flight::sensor::{RangeSensor, ray_distance_m};
//! use skyplan_map::colliders::ObstacleBox;
//! // A 4 m wide, 20 m tall tower whose near face is 10 m east of home.
//! let tower = ObstacleBox { north_m: 0.0, east_m: 12.0, up_m: 10.0, half_north_m: 2.0, half_east_m: 2.0, half_up_m: 10.0 };
//! let world = BoxWorld::new(&[tower]);
//! let d = ray_distance_m(&world, [0.0, 0.0, -5.0], 90f64.to_radians(), 30.0);
//! assert!((d.unwrap() - 10.0).abs() < 1e-9);
//! let sweep = RangeSensor::default().scan(&world, [0.0, 0.0, -5.0], 0.0);
//! assert_eq!(sweep.len(), 72);
//! assert!(matches!(sweep[18], SectorRange::Obstacle(d) if (d - 10.0).abs() < 1e-9)); // 90° east
//! assert_eq!(sweep[54], SectorRange::Clear);                                         // 270° west
//! assert_eq!(RangeSensor::default().scan(&world, [0.0, 0.0, -25.0], 0.0)[18], SectorRange::Clear); // above it
//! ```

use crate::collision::{BoxWorld, Obstacle};
use crate::sensing::SectorRange;
use skyplan_map::colliders::ObstacleBox;
use skyplan_map::planar::region_segment_m;

/// Sectors of a sweep, as MAVLink `OBSTACLE_DISTANCE` carries them.
pub const SECTORS: usize = 72;

/// A horizontal range sensor: `SECTORS` sectors of `360° / SECTORS`, sector 0 centred on north.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeSensor {
    /// Closest range it measures, metres.
    pub min_range_m: f64,
    /// Farthest range it measures, metres.
    pub max_range_m: f64,
}

impl Default for RangeSensor {
    /// 0.2 m to 30 m.
    fn default() -> Self {
        Self {
            min_range_m: 0.2,
            max_range_m: 30.0,
        }
    }
}

impl RangeSensor {
    /// Angular width of a sector, radians.
    pub fn increment_rad(&self) -> f64 {
        std::f64::consts::TAU / SECTORS as f64
    }

    /// One sweep from `position_ned` (metres about home in the world's frame): for each sector
    /// the distance to the nearest box (clamped up to `min_range_m`), or `Clear` beyond
    /// `max_range_m`. `first_bearing_rad` is the bearing of sector 0's centre in the world's
    /// frame (0 when the world's north is the sensor's north).
    pub fn scan(
        &self,
        world: &BoxWorld,
        position_ned: [f64; 3],
        first_bearing_rad: f64,
    ) -> Vec<SectorRange> {
        let near = boxes_near(world, position_ned, self.max_range_m);
        (0..SECTORS)
            .map(|i| {
                let bearing = first_bearing_rad + self.increment_rad() * i as f64;
                match nearest_hit(&near, position_ned, bearing, self.max_range_m) {
                    Some(d) => SectorRange::Obstacle(d.max(self.min_range_m)),
                    None => SectorRange::Clear,
                }
            })
            .collect()
    }
}

/// The obstacles that may be hit within `range_m` of the position, at its altitude.
fn boxes_near(world: &BoxWorld, position_ned: [f64; 3], range_m: f64) -> Vec<Obstacle<'_>> {
    let up = -position_ned[2];
    world
        .boxes_within(position_ned[0], position_ned[1], range_m)
        .into_iter()
        .map(|i| world.obstacle(i))
        .filter(|o| match o {
            Obstacle::Box(b) => (up - b.up_m).abs() <= b.half_up_m,
            Obstacle::Footprint(f) => f.min_height_m <= up && up <= f.height_m,
        })
        .collect()
}

fn nearest_hit(near: &[Obstacle], p: [f64; 3], bearing_rad: f64, max_m: f64) -> Option<f64> {
    let dir = [bearing_rad.cos(), bearing_rad.sin()];
    near.iter()
        .filter_map(|o| match o {
            Obstacle::Box(b) => ray_box_entry_m([p[0], p[1]], dir, b),
            Obstacle::Footprint(f) => ray_polygon_entry_m([p[0], p[1]], dir, &f.rings),
        })
        .filter(|d| *d <= max_m)
        .min_by(f64::total_cmp)
}

/// Where a ray from `origin_ne` along the unit vector `dir_ne` enters a polygon with holes
/// (`[north, east]` rings, even-odd, closed), metres along it: where it first crosses an edge,
/// 0 when the origin is inside or on an edge.
///
/// ```
/// use skyplan_flight::sensor::ray_polygon_entry_m;
/// let triangle = vec![vec![[10.0, -5.0], [10.0, 5.0], [20.0, 0.0]]];
/// assert_eq!(ray_polygon_entry_m([0.0, 0.0], [1.0, 0.0], &triangle), Some(10.0));
/// assert_eq!(ray_polygon_entry_m([0.0, 0.0], [-1.0, 0.0], &triangle), None);
/// assert_eq!(ray_polygon_entry_m([12.0, 0.0], [0.0, 1.0], &triangle), Some(0.0));
/// ```
pub fn ray_polygon_entry_m(
    origin_ne: [f64; 2],
    dir_ne: [f64; 2],
    rings: &[Vec<[f64; 2]>],
) -> Option<f64> {
    if region_segment_m(rings, origin_ne, origin_ne) == 0.0 {
        return Some(0.0);
    }
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    let mut best: Option<f64> = None;
    for ring in rings {
        for k in 0..ring.len() {
            let (c, e) = (ring[k], ring[(k + 1) % ring.len()]);
            let edge = [e[0] - c[0], e[1] - c[1]];
            let to_c = [c[0] - origin_ne[0], c[1] - origin_ne[1]];
            let denom = cross(dir_ne, edge);
            let t = if denom == 0.0 {
                if cross(to_c, dir_ne) != 0.0 {
                    continue; // parallel, off the ray's line
                }
                // Along the ray's line: its nearer end ahead of the origin (the origin is not
                // on the edge).
                let along = |p: [f64; 2]| {
                    (p[0] - origin_ne[0]) * dir_ne[0] + (p[1] - origin_ne[1]) * dir_ne[1]
                };
                let (s, u) = (along(c), along(e));
                if s.max(u) < 0.0 {
                    continue;
                }
                s.min(u).max(0.0)
            } else {
                let s = cross(to_c, dir_ne) / denom;
                let t = cross(to_c, edge) / denom;
                if !(0.0..=1.0).contains(&s) || t < 0.0 {
                    continue;
                }
                t
            };
            best = Some(best.map_or(t, |b: f64| b.min(t)));
        }
    }
    best
}

/// Distance from `position_ned` along `bearing_rad` (horizontal, at the position's altitude) to
/// the nearest box of `world` within `max_m`, metres (0 inside a box).
pub fn ray_distance_m(
    world: &BoxWorld,
    position_ned: [f64; 3],
    bearing_rad: f64,
    max_m: f64,
) -> Option<f64> {
    let near = boxes_near(world, position_ned, max_m);
    nearest_hit(&near, position_ned, bearing_rad, max_m)
}

/// Where a ray from `origin_ne` along the unit vector `dir_ne` enters a box's footprint
/// (closed), metres along it; 0 when the origin is inside. Slab test on both axes.
pub fn ray_box_entry_m(origin_ne: [f64; 2], dir_ne: [f64; 2], b: &ObstacleBox) -> Option<f64> {
    let lo = [b.north_m - b.half_north_m, b.east_m - b.half_east_m];
    let hi = [b.north_m + b.half_north_m, b.east_m + b.half_east_m];
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..2 {
        if dir_ne[k] == 0.0 {
            if origin_ne[k] < lo[k] || origin_ne[k] > hi[k] {
                return None;
            }
        } else {
            let a = (lo[k] - origin_ne[k]) / dir_ne[k];
            let c = (hi[k] - origin_ne[k]) / dir_ne[k];
            t0 = t0.max(a.min(c));
            t1 = t1.min(a.max(c));
        }
    }
    (t0 <= t1).then_some(t0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tiny deterministic generator (no dependency): xorshift.
    struct Rng(u64);
    impl Rng {
        fn unit(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
    }

    /// Brute force: march along the ray in 1 mm steps and ask the world's point test.
    fn sampled(world: &BoxWorld, p: [f64; 3], bearing: f64, max_m: f64) -> Option<f64> {
        let step = 0.001;
        let n = (max_m / step) as usize;
        (0..=n).map(|k| k as f64 * step).find(|d| {
            world
                .hit([p[0] + d * bearing.cos(), p[1] + d * bearing.sin(), p[2]])
                .is_some()
        })
    }

    #[test]
    fn rays_agree_with_a_brute_force_sampler_on_random_worlds() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut hits = 0;
        for _ in 0..40 {
            let boxes: Vec<ObstacleBox> = (0..12)
                .map(|_| {
                    let h = rng.range(2.0, 30.0);
                    ObstacleBox {
                        north_m: rng.range(-40.0, 40.0),
                        east_m: rng.range(-40.0, 40.0),
                        up_m: h / 2.0,
                        half_north_m: rng.range(0.5, 8.0),
                        half_east_m: rng.range(0.5, 8.0),
                        half_up_m: h / 2.0,
                    }
                })
                .collect();
            // Buildings: star-shaped polygons (concave), some with a floor above the ground.
            let footprints: Vec<skyplan_map::footprints::Footprint> = (0..6)
                .map(|feature| {
                    let centre = [rng.range(-40.0, 40.0), rng.range(-40.0, 40.0)];
                    let n = 3 + (rng.unit() * 7.0) as usize;
                    let ring = (0..n)
                        .map(|k| {
                            let a =
                                (k as f64 + 0.5 * rng.unit()) / n as f64 * std::f64::consts::TAU;
                            let r = rng.range(2.0, 9.0);
                            [centre[0] + r * a.cos(), centre[1] + r * a.sin()]
                        })
                        .collect();
                    let floor = if rng.unit() < 0.3 {
                        rng.range(0.0, 10.0)
                    } else {
                        0.0
                    };
                    skyplan_map::footprints::Footprint {
                        feature,
                        rings: vec![ring],
                        min_height_m: floor,
                        height_m: floor + rng.range(2.0, 25.0),
                    }
                })
                .collect();
            let world = BoxWorld::with_footprints(&footprints, &boxes);
            for _ in 0..6 {
                let p = [
                    rng.range(-30.0, 30.0),
                    rng.range(-30.0, 30.0),
                    -rng.range(1.0, 25.0),
                ];
                let bearing = rng.range(0.0, std::f64::consts::TAU);
                let exact = ray_distance_m(&world, p, bearing, 30.0);
                let brute = sampled(&world, p, bearing, 30.0);
                match (exact, brute) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        // The sampler finds the first sample inside: at most one step late.
                        assert!(
                            b >= a - 1e-9 && b - a <= 0.001 + 1e-9,
                            "{a} vs {b} at {p:?}"
                        );
                    }
                    (None, None) => {}
                    // A ray that only grazes a corner may pass between two samples: sample
                    // finely around the exact entry instead.
                    (Some(a), None) => {
                        let fine = (0..=2000).map(|k| a - 1e-3 + k as f64 * 1e-6).any(|d| {
                            world
                                .hit([p[0] + d * bearing.cos(), p[1] + d * bearing.sin(), p[2]])
                                .is_some()
                        });
                        assert!(fine, "exact {a}, no sample inside near it at {p:?}");
                    }
                    (None, Some(b)) => panic!("sampler hit at {b}, exact none, at {p:?}"),
                }
            }
        }
        assert!(
            hits > 40,
            "only {hits} rays hit something: the test is too easy"
        );
    }

    #[test]
    fn a_sweep_sees_a_known_box_in_the_right_sectors() {
        // Near face 15 m north, 10 m wide: visible within atan(5/15) = 18.4° of north.
        let b = ObstacleBox {
            north_m: 17.0,
            east_m: 0.0,
            up_m: 10.0,
            half_north_m: 2.0,
            half_east_m: 5.0,
            half_up_m: 10.0,
        };
        let world = BoxWorld::new(&[b]);
        let sweep = RangeSensor::default().scan(&world, [0.0, 0.0, -5.0], 0.0);
        for (i, r) in sweep.iter().enumerate() {
            let bearing = (i as f64 * 5.0).to_radians();
            let expect = (bearing.cos() > 0.0 && 15.0 * bearing.tan().abs() <= 5.0)
                .then(|| 15.0 / bearing.cos());
            match (r, expect) {
                (SectorRange::Obstacle(d), Some(e)) => assert!((d - e).abs() < 1e-9, "{i}"),
                (SectorRange::Clear, None) => {}
                other => panic!("sector {i}: {other:?}"),
            }
        }
        // Inside the box: the minimum range everywhere.
        let inside = RangeSensor::default().scan(&world, [17.0, 0.0, -5.0], 0.0);
        assert!(inside.iter().all(|r| *r == SectorRange::Obstacle(0.2)));
    }
}
