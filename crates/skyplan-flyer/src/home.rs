//! The way home in flight: a route planned from where the vehicle stopped to its launch point,
//! on the flight's own map, planner and margin ([`PlannedHome`], the ground station's
//! [`HomeRouter`] for the interrupt and failsafe action `return`).

use skyplan_flight::executor::Target;
use skyplan_flight::sensing::{HomeRouter, WayHome};
use skyplan_plan::{Limits, Plan, PlanRequest, Session, World};

/// Plans the way home with the flight's request: the same map, planner, margin and altitude,
/// from the vehicle's position to the plan's start (where the vehicle took off).
pub struct PlannedHome {
    session: Session,
    request: PlanRequest,
    launch_ne: [f64; 2],
}

impl PlannedHome {
    /// A router for the flight that flies `plan`, planned for `request` on `world`.
    ///
    /// The request is used as it is apart from its ends (and what only the first plan uses: a
    /// trajectory, the replanner's climbing limit of the 2D grid planners).
    pub fn new(world: World, limits: Limits, request: &PlanRequest, plan: &Plan) -> Self {
        let mut request = request.clone();
        request.trajectory = None;
        request.max_speed_m_s = None;
        request.max_accel_m_s2 = None;
        request.max_jerk_m_s3 = None;
        request.max_climb_m_s = None;
        request.max_descent_m_s = None;
        request.max_yaw_rate_deg_s = None;
        request.sample_hz = None;
        request.start_heading_deg = None;
        if crate::runner::replannable(&request) {
            request.max_alt_m = None;
        }
        Self {
            session: Session::new(world).with_limits(limits),
            request,
            launch_ne: [plan.start.north_m, plan.start.east_m],
        }
    }

    /// The launch point the way home ends above, metres north and east of home.
    pub fn launch_ne(&self) -> [f64; 2] {
        self.launch_ne
    }
}

impl HomeRouter for PlannedHome {
    fn route_home(&mut self, from_ned: [f64; 3]) -> Result<WayHome, String> {
        let mut r = self.request.clone();
        r.start_ne = Some([from_ned[0], from_ned[1]]);
        r.start_lla = None;
        r.goal_ne = Some(self.launch_ne);
        r.goal_lla = None;
        let plan = self.session.plan(&r).map_err(|e| e.to_string())?;
        let mission = plan
            .mission
            .as_ref()
            .ok_or_else(|| "the route home has no waypoints".to_string())?;
        Ok(WayHome {
            targets: mission.waypoints.iter().map(Target::from).collect(),
            length_m: mission.length_3d_m(),
            planner: plan.planner.to_string(),
        })
    }
}

/// The highest obstacle under the autopilot's own way home (RTL: a straight line from wherever
/// the vehicle is to the launch point, at the RTL altitude).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RtlClearance {
    /// Altitude above home that clears every obstacle under a straight way home from any point
    /// of the route, the margin included: the obstacle's top plus the margin, metres.
    pub alt_m: f64,
    /// Index of that obstacle in the map.
    pub obstacle: usize,
}

/// What an RTL from anywhere on the route flies over: the straight lines from the points of
/// each leg (`route_ne[i]` → `route_ne[i + 1]`) to the launch point sweep the triangle
/// (launch, both ends of the leg). An obstacle matters when its footprint grown by `margin_m`
/// meets one of those triangles (an exact separating-axis test); the answer is the highest such
/// top plus the margin, or `None` when nothing is under any way home.
///
/// ```
/// use skyplan_flyer::home::rtl_clearance;
/// use skyplan_map::colliders::ObstacleBox;
///
/// // A 40 m tower between the route (north 100 m) and the launch point, one off to the side.
/// let tower = ObstacleBox::from_row([50.0, 0.0, 20.0, 5.0, 5.0, 20.0]);
/// let aside = ObstacleBox::from_row([50.0, 300.0, 50.0, 5.0, 5.0, 50.0]);
/// let route = [[100.0, -20.0], [100.0, 20.0]];
/// let world = skyplan_flight::collision::BoxWorld::new(&[tower, aside]);
/// let c = rtl_clearance(&world, &route, [0.0, 0.0], 5.0).unwrap();
/// assert_eq!((c.alt_m, c.obstacle), (45.0, 0));
/// ```
pub fn rtl_clearance(
    world: &skyplan_flight::collision::BoxWorld,
    route_ne: &[[f64; 2]],
    launch_ne: [f64; 2],
    margin_m: f64,
) -> Option<RtlClearance> {
    let triangles: Vec<[[f64; 2]; 3]> = match route_ne {
        [] => return None,
        [only] => vec![[launch_ne, *only, *only]],
        _ => route_ne
            .windows(2)
            .map(|w| [launch_ne, w[0], w[1]])
            .collect(),
    };
    let mut best: Option<RtlClearance> = None;
    for (i, f) in world.footprints().iter().enumerate() {
        let top_m = f.height_m + margin_m;
        if best.is_some_and(|c| c.alt_m >= top_m) {
            continue;
        }
        if triangles
            .iter()
            .any(|t| triangle_meets_grown(t, &f.rings, margin_m))
        {
            best = Some(RtlClearance {
                alt_m: top_m,
                obstacle: i,
            });
        }
    }
    let first_box = world.footprints().len();
    for (i, b) in world.boxes().iter().enumerate() {
        let top_m = b.up_m + b.half_up_m + margin_m;
        if best.is_some_and(|c| c.alt_m >= top_m) {
            continue;
        }
        let rect = [
            [
                b.north_m - b.half_north_m - margin_m,
                b.east_m - b.half_east_m - margin_m,
            ],
            [
                b.north_m + b.half_north_m + margin_m,
                b.east_m + b.half_east_m + margin_m,
            ],
        ];
        if triangles.iter().any(|t| triangle_meets_rect(t, &rect)) {
            best = Some(RtlClearance {
                alt_m: top_m,
                obstacle: first_box + i,
            });
        }
    }
    best
}

/// Spacing of the points of the route whose straight way home [`rtl_ground_clearance`] bounds,
/// metres; the bounds are grown by half of it.
pub const RTL_ROUTE_STEP_M: f64 = 10.0;
/// Longest piece of a straight way home one ground bound covers, metres.
pub const RTL_PIECE_M: f64 = 20.0;

/// Over terrain: an altitude above the map's home that keeps `margin_m` above the ground under
/// the autopilot's straight way home (RTL, to the route's first point) from anywhere on
/// `route_ne`. The ground is bounded exactly over rectangles along each way home from a point
/// every [`RTL_ROUTE_STEP_M`] of the route, each piece's rectangle grown by the margin and half
/// that step, so the answer is never below the truth (at most a little above it on slopes).
/// Errors where the DEM does not reach.
///
/// ```
/// use skyplan_flyer::home::rtl_ground_clearance;
/// use skyplan_map::terrain::{Dem, Terrain};
/// use skyplan_frames::{Lla, LocalFrame};
/// // Ground 100 m above sea level with a ridge 30 m higher from 200 to 300 m north of home, on
/// // a grid of about 10 m (row 0 northernmost; home at row 60, column 40).
/// let step = 10.0 / 111_000.0;
/// let (rows, cols) = (100, 80);
/// let heights: Vec<f32> = (0..rows * cols)
///     .map(|k| if (30..=40).contains(&(k / cols)) { 130.0 } else { 100.0 })
///     .collect();
/// let dem = Dem::geographic(rows, cols, heights, [-84.0 - 40.0 * step, 36.0 + 60.0 * step], [step, step])?;
/// let home = Lla { lat_deg: 36.0, lon_deg: -84.0, alt_m: 0.0 };
/// let t = Terrain::new(dem, LocalFrame::new(home)?)?;
/// // A route that stays south of the ridge clears it by the margin only.
/// let south = rtl_ground_clearance(&t, &[[0.0, 0.0], [50.0, 100.0]], 5.0)?;
/// assert!((south - 5.0).abs() < 0.05, "{south}");
/// // Beyond it, the way home crosses the ridge.
/// let beyond = rtl_ground_clearance(&t, &[[0.0, 0.0], [400.0, 0.0]], 5.0)?;
/// assert!((beyond - 35.0).abs() < 0.05, "{beyond}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn rtl_ground_clearance(
    terrain: &skyplan_map::terrain::Terrain,
    route_ne: &[[f64; 2]],
    margin_m: f64,
) -> Result<f64, skyplan_map::terrain::TerrainError> {
    let Some(&launch) = route_ne.first() else {
        return Ok(margin_m);
    };
    let grow_m = margin_m + RTL_ROUTE_STEP_M / 2.0;
    let mut points = vec![launch];
    for w in route_ne.windows(2) {
        let len_m = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        let n = (len_m / RTL_ROUTE_STEP_M).ceil().max(1.0) as usize;
        points.extend((1..=n).map(|k| {
            let f = k as f64 / n as f64;
            [
                w[0][0] + f * (w[1][0] - w[0][0]),
                w[0][1] + f * (w[1][1] - w[0][1]),
            ]
        }));
    }
    let mut top_m = f64::NEG_INFINITY;
    for p in points {
        let len_m = (p[0] - launch[0]).hypot(p[1] - launch[1]);
        let n = (len_m / RTL_PIECE_M).ceil().max(1.0) as usize;
        let at = |k: usize| {
            let f = k as f64 / n as f64;
            [
                launch[0] + f * (p[0] - launch[0]),
                launch[1] + f * (p[1] - launch[1]),
            ]
        };
        for k in 0..n {
            let (a, b) = (at(k), at(k + 1));
            let north = [a[0].min(b[0]) - grow_m, a[0].max(b[0]) + grow_m];
            let east = [a[1].min(b[1]) - grow_m, a[1].max(b[1]) + grow_m];
            let [_, hi] = terrain.ground_extremes_m_in(north, east)?;
            top_m = top_m.max(hi);
        }
    }
    Ok(top_m + margin_m)
}

/// Whether the (closed) triangle `t` meets the polygon `rings` grown by `margin_m`: an edge of
/// the triangle comes within the margin of the polygon, or the polygon lies inside the
/// triangle (then its first vertex does).
fn triangle_meets_grown(t: &[[f64; 2]; 3], rings: &[Vec<[f64; 2]>], margin_m: f64) -> bool {
    use skyplan_map::planar::region_segment_m;
    if (0..3).any(|k| region_segment_m(rings, t[k], t[(k + 1) % 3]) <= margin_m) {
        return true;
    }
    let Some(&p) = rings.first().and_then(|r| r.first()) else {
        return false;
    };
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let d = [
        cross(t[0], t[1], p),
        cross(t[1], t[2], p),
        cross(t[2], t[0], p),
    ];
    d.iter().all(|&x| x >= 0.0) || d.iter().all(|&x| x <= 0.0)
}

/// Whether the (closed) triangle `t` and the axis-aligned rectangle `[min, max]` share a point:
/// no separating axis among the rectangle's two and the triangle's edge normals.
fn triangle_meets_rect(t: &[[f64; 2]; 3], rect: &[[f64; 2]; 2]) -> bool {
    for axis in 0..2 {
        let lo = t.iter().map(|p| p[axis]).fold(f64::INFINITY, f64::min);
        let hi = t.iter().map(|p| p[axis]).fold(f64::NEG_INFINITY, f64::max);
        if hi < rect[0][axis] || lo > rect[1][axis] {
            return false;
        }
    }
    let corners = [
        rect[0],
        [rect[0][0], rect[1][1]],
        rect[1],
        [rect[1][0], rect[0][1]],
    ];
    for k in 0..3 {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        let normal = [b[1] - a[1], a[0] - b[0]];
        if normal == [0.0, 0.0] {
            continue;
        }
        let dot = |p: [f64; 2]| normal[0] * p[0] + normal[1] * p[1];
        let (tl, th) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &p| {
                (l.min(dot(p)), h.max(dot(p)))
            });
        let (rl, rh) = corners
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &p| {
                (l.min(dot(p)), h.max(dot(p)))
            });
        if th < rl || tl > rh {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent truth: a closed triangle and a rectangle meet iff a vertex of one is inside
    /// the other or two of their edges cross.
    fn meets_by_edges(t: &[[f64; 2]; 3], r: &[[f64; 2]; 2]) -> bool {
        let corners = [r[0], [r[0][0], r[1][1]], r[1], [r[1][0], r[0][1]]];
        let in_rect = |p: [f64; 2]| {
            (r[0][0]..=r[1][0]).contains(&p[0]) && (r[0][1]..=r[1][1]).contains(&p[1])
        };
        let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
            (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
        };
        let flat = cross(t[0], t[1], t[2]) == 0.0;
        let in_tri = |p: [f64; 2]| {
            let d = [
                cross(t[0], t[1], p),
                cross(t[1], t[2], p),
                cross(t[2], t[0], p),
            ];
            d.iter().all(|&x| x >= 0.0) || d.iter().all(|&x| x <= 0.0)
        };
        let on_segment = |a: [f64; 2], b: [f64; 2], p: [f64; 2]| {
            cross(a, b, p) == 0.0
                && p[0] >= a[0].min(b[0])
                && p[0] <= a[0].max(b[0])
                && p[1] >= a[1].min(b[1])
                && p[1] <= a[1].max(b[1])
        };
        let segments_meet = |a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]| {
            let (d1, d2, d3, d4) = (
                cross(c, d, a),
                cross(c, d, b),
                cross(a, b, c),
                cross(a, b, d),
            );
            ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
                && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
                || on_segment(c, d, a)
                || on_segment(c, d, b)
                || on_segment(a, b, c)
                || on_segment(a, b, d)
        };
        t.iter().any(|&p| in_rect(p))
            || (!flat && corners.iter().any(|&c| in_tri(c)))
            || (0..3).any(|i| {
                (0..4)
                    .any(|j| segments_meet(t[i], t[(i + 1) % 3], corners[j], corners[(j + 1) % 4]))
            })
    }

    #[test]
    fn the_separating_axis_test_agrees_with_the_edge_test_on_random_shapes() {
        // A small LCG: the shapes on a coarse lattice, so that touching and collinear cases
        // (shared edges, vertices on edges, degenerate triangles) come up often.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) % n) as f64
        };
        let (mut met, mut apart) = (0, 0);
        for _ in 0..200_000 {
            let t = [[next(9), next(9)], [next(9), next(9)], [next(9), next(9)]];
            let (x, y) = (next(9), next(9));
            let r = [[x, y], [x + next(4), y + next(4)]];
            let want = meets_by_edges(&t, &r);
            assert_eq!(triangle_meets_rect(&t, &r), want, "{t:?} {r:?}");
            if want { met += 1 } else { apart += 1 }
        }
        assert!(met > 10_000 && apart > 10_000, "{met} met, {apart} apart");
    }
}
