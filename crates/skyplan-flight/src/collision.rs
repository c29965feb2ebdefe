//! Checking a flown track against the obstacles of the true world (the real boxes and building
//! footprint prisms, no margin): collisions, and the closest approach ([`Closest`]) that a
//! flight's verdict judges against the route's safety margin. Obstacles are numbered footprints
//! first, then boxes.
//!
//! ```
//! use skyplan_flight::collision::{BoxWorld, TrackCheck};
//! use skyplan_map::colliders::ObstacleBox;
//! let tower = ObstacleBox { north_m: 10.0, east_m: 0.0, up_m: 15.0, half_north_m: 2.0, half_east_m: 2.0, half_up_m: 15.0 };
//! let world = BoxWorld::new(&[tower]);
//! assert!(world.hit([10.0, 1.0, -5.0]).is_some());      // NED: 5 m up, inside
//! assert!(world.hit([10.0, 1.0, -31.0]).is_none());     // above the roof
//! let mut check = TrackCheck::default();
//! check.add(&world, 0.0, [0.0, 0.0, -5.0]);
//! check.add(&world, 1.0, [10.0, 0.0, -5.0]);
//! assert_eq!(check.collision().map(|c| c.box_index), Some(0));
//! ```

use skyplan_map::colliders::ObstacleBox;
use skyplan_map::footprints::Footprint;
use skyplan_map::planar::region_segment_m;
use std::collections::HashMap;

/// Size of the buckets of the spatial index, metres.
const BUCKET_M: f64 = 20.0;
/// How far below a roof a point may be and still stand on it ([`BoxWorld::roof_under`]),
/// metres: a vehicle stopped on a roof is a few centimetres above it, never this far inside.
pub const ROOF_REACH_M: f64 = 0.5;

/// The obstacles — building footprints (prisms) and boxes — with a coarse horizontal bucket
/// index.
#[derive(Debug, Clone)]
pub struct BoxWorld {
    footprints: Vec<Footprint>,
    boxes: Vec<ObstacleBox>,
    buckets: HashMap<(i64, i64), Vec<u32>>,
}

/// The horizontal distance from `p` to a footprint's polygon (0 inside), metres.
fn footprint_distance_m(f: &Footprint, p: [f64; 2]) -> f64 {
    region_segment_m(&f.rings, p, p)
}

/// How far the altitude `up` is from the band `[lo, hi]`, metres (0 inside).
fn band_gap_m(up: f64, lo: f64, hi: f64) -> f64 {
    (lo - up).max(up - hi).max(0.0)
}

fn bucket(x_m: f64) -> i64 {
    (x_m / BUCKET_M).floor() as i64
}

impl BoxWorld {
    /// Indexes the boxes.
    pub fn new(boxes: &[ObstacleBox]) -> Self {
        Self::with_footprints(&[], boxes)
    }

    /// Indexes building footprints (numbered first) and boxes.
    ///
    /// ```
    /// use skyplan_flight::collision::BoxWorld;
    /// use skyplan_map::footprints::Footprint;
    /// // A triangular building 20 m tall.
    /// let rings = vec![vec![[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]]];
    /// let f = Footprint { feature: 0, rings, min_height_m: 0.0, height_m: 20.0 };
    /// let world = BoxWorld::with_footprints(&[f], &[]);
    /// assert_eq!(world.hit([2.0, 2.0, -5.0]), Some(0));
    /// assert_eq!(world.hit([6.0, 6.0, -5.0]), None); // beyond the hypotenuse
    /// let (k, d) = world.nearest([6.0, 6.0, -5.0], 10.0).unwrap();
    /// assert!(k == 0 && (d - 2f64.sqrt()).abs() < 1e-12);
    /// ```
    pub fn with_footprints(footprints: &[Footprint], boxes: &[ObstacleBox]) -> Self {
        let mut buckets: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
        let extents = (footprints.iter().map(Footprint::bbox_ne)).chain(boxes.iter().map(|b| {
            (
                [b.north_m - b.half_north_m, b.east_m - b.half_east_m],
                [b.north_m + b.half_north_m, b.east_m + b.half_east_m],
            )
        }));
        for (i, (lo, hi)) in extents.enumerate() {
            for n in bucket(lo[0])..=bucket(hi[0]) {
                for e in bucket(lo[1])..=bucket(hi[1]) {
                    buckets.entry((n, e)).or_default().push(i as u32);
                }
            }
        }
        Self {
            footprints: footprints.to_vec(),
            boxes: boxes.to_vec(),
            buckets,
        }
    }

    /// The boxes (numbered after the footprints).
    pub fn boxes(&self) -> &[ObstacleBox] {
        &self.boxes
    }

    /// The building footprints (numbered first).
    pub fn footprints(&self) -> &[Footprint] {
        &self.footprints
    }

    /// How many obstacles: footprints and boxes.
    pub fn len(&self) -> usize {
        self.footprints.len() + self.boxes.len()
    }

    /// Whether the world has no obstacle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Obstacle `i` (footprints first, then boxes).
    pub fn obstacle(&self, i: usize) -> Obstacle<'_> {
        match i.checked_sub(self.footprints.len()) {
            None => Obstacle::Footprint(&self.footprints[i]),
            Some(k) => Obstacle::Box(&self.boxes[k]),
        }
    }

    /// The distance from a NED point to obstacle `i`, metres (0 touching or inside).
    pub fn distance_m(&self, i: usize, point_ned_m: [f64; 3]) -> f64 {
        let [n, e, d] = point_ned_m;
        let up = -d;
        match self.obstacle(i) {
            Obstacle::Footprint(f) => {
                footprint_distance_m(f, [n, e]).hypot(band_gap_m(up, f.min_height_m, f.height_m))
            }
            Obstacle::Box(b) => {
                let dn = ((n - b.north_m).abs() - b.half_north_m).max(0.0);
                let de = ((e - b.east_m).abs() - b.half_east_m).max(0.0);
                let du = ((up - b.up_m).abs() - b.half_up_m).max(0.0);
                (dn * dn + de * de + du * du).sqrt()
            }
        }
    }

    /// Indices of the obstacles whose footprint may come within `range_m` of a north/east point
    /// (a superset from the bucket index, each once, ascending).
    pub fn boxes_within(&self, north_m: f64, east_m: f64, range_m: f64) -> Vec<usize> {
        let r = range_m.max(0.0);
        let mut out = Vec::new();
        for bn in bucket(north_m - r)..=bucket(north_m + r) {
            for be in bucket(east_m - r)..=bucket(east_m + r) {
                if let Some(list) = self.buckets.get(&(bn, be)) {
                    out.extend(list.iter().map(|&i| i as usize));
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The roof the vehicle would stand on at a NED point: the highest top, at most
    /// [`ROOF_REACH_M`] above the point, among the obstacles whose footprint holds it
    /// (`None`: nothing under it but the ground). Returns the obstacle and its top, metres up.
    ///
    /// ```
    /// use skyplan_flight::collision::BoxWorld;
    /// use skyplan_map::colliders::ObstacleBox;
    /// let tower = ObstacleBox::from_row([10.0, 0.0, 30.0, 5.0, 5.0, 30.0]); // 60 m tall
    /// let world = BoxWorld::new(&[tower]);
    /// assert_eq!(world.roof_under([10.0, 1.0, -66.0]), Some((0, 60.0)));
    /// assert_eq!(world.roof_under([10.0, 1.0, -50.0]), None); // beside its wall, not over it
    /// assert_eq!(world.roof_under([30.0, 1.0, -66.0]), None);
    /// ```
    pub fn roof_under(&self, point_ned_m: [f64; 3]) -> Option<(usize, f64)> {
        let [n, e, d] = point_ned_m;
        let up = -d;
        let mut best: Option<(usize, f64)> = None;
        for &i in self.buckets.get(&(bucket(n), bucket(e)))? {
            let i = i as usize;
            let (holds, top_m) = match self.obstacle(i) {
                Obstacle::Footprint(f) => {
                    (skyplan_map::planar::inside(&f.rings, [n, e]), f.height_m)
                }
                Obstacle::Box(b) => (
                    (n - b.north_m).abs() <= b.half_north_m
                        && (e - b.east_m).abs() <= b.half_east_m,
                    b.up_m + b.half_up_m,
                ),
            };
            if holds && top_m <= up + ROOF_REACH_M && best.is_none_or(|(_, t)| top_m > t) {
                best = Some((i, top_m));
            }
        }
        best
    }

    /// The first obstacle containing a NED point (faces included), if any.
    pub fn hit(&self, point_ned_m: [f64; 3]) -> Option<usize> {
        let [n, e, _] = point_ned_m;
        self.buckets
            .get(&(bucket(n), bucket(e)))?
            .iter()
            .map(|&i| i as usize)
            .find(|&i| self.distance_m(i, point_ned_m) == 0.0)
    }

    /// Distance from a NED point to the nearest box, metres, if one is within `max_m`
    /// (`max_m` ≤ 20 m; farther boxes may be missed).
    pub fn clearance_m(&self, point_ned_m: [f64; 3], max_m: f64) -> Option<f64> {
        self.nearest(point_ned_m, max_m).map(|(_, d)| d)
    }

    /// The nearest obstacle to a NED point and its distance, metres, if one is within `max_m`
    /// (`max_m` ≤ 20 m; farther obstacles may be missed); the lower index on a tie.
    pub fn nearest(&self, point_ned_m: [f64; 3], max_m: f64) -> Option<(usize, f64)> {
        self.nearest_except(point_ned_m, max_m, None)
    }

    /// [`BoxWorld::nearest`] leaving out obstacle `except` (the roof a vehicle stands on).
    pub fn nearest_except(
        &self,
        point_ned_m: [f64; 3],
        max_m: f64,
        except: Option<usize>,
    ) -> Option<(usize, f64)> {
        let [n, e, _] = point_ned_m;
        let mut best: Option<(usize, f64)> = None;
        for i in self.boxes_within(n, e, max_m) {
            if Some(i) == except {
                continue;
            }
            let dist = self.distance_m(i, point_ned_m);
            if dist <= max_m && best.is_none_or(|(_, x)| dist < x) {
                best = Some((i, dist));
            }
        }
        best
    }
}

/// One obstacle of a [`BoxWorld`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Obstacle<'a> {
    /// A building footprint: a prism between its floor and its top.
    Footprint(&'a Footprint),
    /// A box.
    Box(&'a ObstacleBox),
}

/// The true world of a flight: the map's obstacles followed by the hidden boxes the planner
/// does not know (so an obstacle's index tells which it is); `None` without either. The one
/// world that the flown track is checked against and the simulated sensor sees.
pub fn true_world(map: Option<&BoxWorld>, hidden: &[ObstacleBox]) -> Option<BoxWorld> {
    match (map, hidden.is_empty()) {
        (Some(w), true) => Some(w.clone()),
        (Some(w), false) => Some(BoxWorld::with_footprints(
            w.footprints(),
            &[w.boxes(), hidden].concat(),
        )),
        (None, false) => Some(BoxWorld::new(hidden)),
        (None, true) => None,
    }
}

/// A collision of the track with a box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collision {
    /// When, seconds (the time given with the point).
    pub time_s: f64,
    /// Where, NED metres.
    pub point_ned_m: [f64; 3],
    /// Index of the box in the map.
    pub box_index: usize,
}

/// The track's closest approach to a box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// Distance to the box, metres (0: touching or inside).
    pub clearance_m: f64,
    /// When, seconds (the time given with the point).
    pub time_s: f64,
    /// Index of the box in the world.
    pub box_index: usize,
}

/// Accumulates a track's collisions and its closest approach to the boxes.
#[derive(Debug, Clone, Default)]
pub struct TrackCheck {
    last: Option<[f64; 3]>,
    first_collision: Option<Collision>,
    collisions: usize,
    closest: Option<Closest>,
    samples: usize,
}

/// The track is checked every this many metres along it.
const SAMPLE_M: f64 = 0.25;
/// Clearance is measured up to this distance.
const CLEARANCE_MAX_M: f64 = 20.0;

impl TrackCheck {
    /// Adds the next point of the track; the segment from the previous point is sampled every
    /// 0.25 m.
    pub fn add(&mut self, world: &BoxWorld, time_s: f64, point_ned_m: [f64; 3]) {
        self.add_on(world, time_s, point_ned_m, None);
    }

    /// [`TrackCheck::add`] for a vehicle landing on, or standing on, the roof of obstacle
    /// `roof`: that roof counts for collisions but not for the closest approach (a vehicle
    /// on a roof touches it).
    pub fn add_on(
        &mut self,
        world: &BoxWorld,
        time_s: f64,
        point_ned_m: [f64; 3],
        roof: Option<usize>,
    ) {
        if point_ned_m.iter().any(|x| !x.is_finite()) {
            return;
        }
        let from = self.last.unwrap_or(point_ned_m);
        let len = ((0..3)
            .map(|i| (point_ned_m[i] - from[i]).powi(2))
            .sum::<f64>())
        .sqrt();
        let steps = ((len / SAMPLE_M).ceil() as usize).clamp(1, 100_000);
        for k in 1..=steps {
            let f = k as f64 / steps as f64;
            let p = [
                from[0] + f * (point_ned_m[0] - from[0]),
                from[1] + f * (point_ned_m[1] - from[1]),
                from[2] + f * (point_ned_m[2] - from[2]),
            ];
            self.samples += 1;
            // On the ground (the take-off and landing spot) the floor is not an obstacle.
            if -p[2] < 0.05 {
                continue;
            }
            if let Some(box_index) = world.hit(p) {
                self.collisions += 1;
                if self.first_collision.is_none() {
                    self.first_collision = Some(Collision {
                        time_s,
                        point_ned_m: p,
                        box_index,
                    });
                }
            }
        }
        if -point_ned_m[2] >= 0.05
            && let Some((box_index, clearance_m)) =
                world.nearest_except(point_ned_m, CLEARANCE_MAX_M, roof)
            && self.closest.is_none_or(|c| clearance_m < c.clearance_m)
        {
            self.closest = Some(Closest {
                clearance_m,
                time_s,
                box_index,
            });
        }
        self.last = Some(point_ned_m);
    }

    /// The first collision, if any.
    pub fn collision(&self) -> Option<Collision> {
        self.first_collision
    }

    /// How many sampled points were inside a box.
    pub fn colliding_samples(&self) -> usize {
        self.collisions
    }

    /// Smallest distance of an airborne track point to a box, metres (`None`: never within 20 m).
    pub fn min_clearance_m(&self) -> Option<f64> {
        self.closest.map(|c| c.clearance_m)
    }

    /// The closest approach of an airborne track point to a box (`None`: never within 20 m).
    pub fn closest(&self) -> Option<Closest> {
        self.closest
    }
}
