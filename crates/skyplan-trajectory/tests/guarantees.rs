//! The guarantees against independent truth: random box worlds built around random routes,
//! every trajectory sampled at ≤ 1 cm of travel and each sample tested against every grown box
//! (brute force, not the corridor), speeds and accelerations at the samples within the limits,
//! rest at both ends at the route's ends; grids checked cell by cell.

use proptest::prelude::*;
use skyplan_cspace::{Grid2, GridFrame};
use skyplan_map::colliders::ObstacleBox;
use skyplan_trajectory::{
    FreeSpace, GridLayer, Limits, Method, Options, Trajectory, plan, stop_at_waypoints, verify,
};
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, segment_hits_box};

mod common;
use common::{dense_check_free_and_within_limits, norm};

/// Samples so close that consecutive points are ≤ 1 cm apart (at the proven speed bound), free
/// and within the limits, at rest at both ends at the route's ends.
fn dense_check(traj: &Trajectory, is_free: &dyn Fn(Neu) -> bool, route: &[Neu]) {
    dense_check_free_and_within_limits(traj, is_free);
    let total = traj.duration_s();
    let (a, b) = (traj.state_at(0.0), traj.state_at(total));
    let (first, last) = (route[0], route[route.len() - 1]);
    assert!(norm([0, 1, 2].map(|k| a.point_neu[k] - first[k])) < 1e-9);
    assert!(norm([0, 1, 2].map(|k| b.point_neu[k] - last[k])) < 1e-9);
    assert!(norm(a.vel_neu_m_s) + norm(b.vel_neu_m_s) < 1e-12);
    assert!(norm(a.accel_neu_m_s2) + norm(b.accel_neu_m_s2) < 1e-12);
}

/// A box world around `route`: random boxes that keep clear of it by the margin, and two low
/// corner boxes so the bounds cover 0..100 m.
fn world_around(route: &[Neu], boxes: Vec<ObstacleBox>, safety_m: f64) -> BoxWorld3 {
    let mut kept: Vec<ObstacleBox> = boxes
        .into_iter()
        .filter(|b| {
            let g = Aabb::from_obstacle(b, safety_m);
            !route.windows(2).any(|w| segment_hits_box(w[0], w[1], &g))
        })
        .collect();
    kept.push(ObstacleBox::from_row([-5.0, -5.0, 0.5, 0.5, 0.5, 0.5]));
    kept.push(ObstacleBox::from_row([105.0, 105.0, 0.5, 0.5, 0.5, 0.5]));
    skyplan_testkit::box_world(&kept, safety_m, 60.0, 10.0)
}

fn arb_route(planar: bool) -> impl Strategy<Value = Vec<Neu>> {
    let alt = if planar { 20.0..20.000_001 } else { 5.0..40.0 };
    prop::collection::vec(skyplan_testkit::arb_point(alt), 2..6).prop_map(move |mut r| {
        if planar {
            for p in &mut r {
                p[2] = 20.0;
            }
        }
        r
    })
}

fn arb_limits() -> impl Strategy<Value = Limits> {
    (
        1.0..15.0f64,
        1.0..8.0f64,
        2.0..30.0f64,
        0.5..4.0f64,
        0.5..3.0f64,
    )
        .prop_map(|(v, a, j, up, down)| Limits {
            max_speed_m_s: v,
            max_accel_m_s2: a,
            max_jerk_m_s3: j,
            max_climb_m_s: up,
            max_descent_m_s: down,
            max_yaw_rate_deg_s: 90.0,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    #[test]
    fn trajectories_in_box_worlds_stay_free_and_within_limits(
        planar in any::<bool>(),
        route in arb_route(false),
        boxes in prop::collection::vec(skyplan_testkit::arb_box(0.0..30.0, 0.5..12.0, 0.5..30.0), 0..30),
        safety_m in 0.0..4.0f64,
        limits in arb_limits(),
    ) {
        let route: Vec<Neu> = if planar { route.iter().map(|p| [p[0], p[1], 20.0]).collect() } else { route };
        prop_assume!(route.windows(2).any(|w| skyplan_world3::distance_m(w[0], w[1]) > 1e-6));
        let world = world_around(&route, boxes, safety_m);
        let bf = world.brute_force();
        let traj = plan(&route, &world, &limits, &Options::default()).expect("a trajectory");
        dense_check(&traj, &|p| bf.is_free(p), &route);
        prop_assert!(verify(&traj, &world).is_ok());
        if planar {
            prop_assert!(traj.pieces.iter().all(|p| p.control_points_neu.iter().all(|c| c[2] == 20.0)));
        }
        let stop = stop_at_waypoints(&route, &limits).expect("a profile");
        prop_assert!(verify(&stop, &world).is_ok());
        dense_check(&stop, &|p| bf.is_free(p), &route);
        // Never slower than stopping at every waypoint; when stopping was chosen for speed the
        // reason says so.
        prop_assert!(traj.duration_s() <= stop.duration_s() * (1.0 + 1e-12),
            "{} s vs {} s", traj.duration_s(), stop.duration_s());
        if traj.method == Method::StopAtWaypoints {
            prop_assert!(traj.fallback_reason.is_some());
        }
    }
}

/// A grid with a wall and a pillar: the trajectory, checked cell by cell at ≤ 1 cm.
#[test]
fn a_grid_trajectory_stays_in_free_cells() {
    let mut text = String::new();
    for r in 0..40 {
        let row: String = (0..40)
            .map(|c| {
                let wall = c == 20 && r < 30;
                let pillar = (20..24).contains(&r) && (30..33).contains(&c);
                if wall || pillar { '#' } else { '.' }
            })
            .collect();
        text.push_str(&row);
        text.push('\n');
    }
    let frame = GridFrame {
        origin_north_m: -10.0,
        origin_east_m: 5.0,
        cell_m: 0.5,
    };
    let g = Grid2::from_ascii(&text).unwrap();
    let grid = Grid2::new(g.rows(), g.cols(), g.blocked_cells().to_vec(), frame).unwrap();
    let layer = GridLayer::new(grid.clone(), 7.0);
    let c = |r: f64, col: f64| [-10.0 + r * 0.5, 5.0 + col * 0.5, 7.0];
    let route = [c(2.5, 2.5), c(35.5, 18.5), c(35.5, 22.5), c(2.5, 37.5)];
    let limits = Limits::default();
    let traj = plan(&route, &layer, &limits, &Options::default()).unwrap();
    assert_eq!(
        traj.method,
        Method::MinimumJerk,
        "{:?}",
        traj.fallback_reason
    );
    let free = |p: Neu| {
        // Free iff at the altitude and every cell whose closed square holds p is free.
        let (fr, fc) = ((p[0] + 10.0) / 0.5, (p[1] - 5.0) / 0.5);
        let rows = [fr.floor(), fr.ceil() - 1.0];
        let cols = [fc.floor(), fc.ceil() - 1.0];
        (p[2] - 7.0).abs() < 1e-9
            && rows.iter().all(|&r| {
                cols.iter().all(|&col| {
                    r >= 0.0
                        && col >= 0.0
                        && grid
                            .checked_cell(r as i64, col as i64)
                            .is_some_and(|cell| !grid.is_blocked(cell))
                })
            })
    };
    dense_check(&traj, &free, &route);
    assert!(layer.point_is_free(route[0]));
}

#[test]
fn a_route_through_an_obstacle_is_refused_with_where() {
    let boxes = [ObstacleBox::from_row([50.0, 50.0, 10.0, 5.0, 5.0, 10.0])];
    let world = skyplan_testkit::box_world(&boxes, 1.0, 60.0, 60.0);
    let route = [[0.0, 50.0, 5.0], [100.0, 50.0, 5.0]];
    let err = plan(&route, &world, &Limits::default(), &Options::default()).unwrap_err();
    let text = err.to_string();
    assert!(
        text.starts_with("no safe corridor near north") && text.contains("not in free space"),
        "{text}"
    );
}

#[test]
fn an_exhausted_budget_falls_back_and_says_why() {
    let boxes = [ObstacleBox::from_row([50.0, 50.0, 10.0, 5.0, 5.0, 10.0])];
    let world = skyplan_testkit::box_world(&boxes, 1.0, 60.0, 60.0);
    let route = [[0.0, 0.0, 5.0], [0.0, 100.0, 5.0], [100.0, 100.0, 30.0]];
    let opts = Options {
        budget: std::time::Duration::ZERO,
        ..Options::default()
    };
    let traj = plan(&route, &world, &Limits::default(), &opts).unwrap();
    assert_eq!(traj.method, Method::StopAtWaypoints);
    assert_eq!(
        traj.fallback_reason.as_deref(),
        Some("the time budget ran out")
    );
    dense_check(&traj, &|p| world.is_free(p), &route);
}

/// One straight leg under a low jerk limit (a case CI's proptest found): smooth pieces were 20 %
/// slower than the jerk-limited stop profile, which is time-optimal there, so that profile is
/// returned, with the reason; its duration is the closed form of a rest-to-rest move that never
/// reaches the acceleration limit (jerk ramps of `2 √(v / j)` and a cruise).
#[test]
fn a_straight_leg_gets_the_time_optimal_profile() {
    let route = [
        [0.0, 85.28664387508309, 20.0],
        [0.0, 37.61295883891635, 20.0],
    ];
    let limits = Limits {
        max_speed_m_s: 3.0526489595338915,
        max_accel_m_s2: 6.2468640032021625,
        max_jerk_m_s3: 2.0,
        max_climb_m_s: 0.5,
        max_descent_m_s: 0.5,
        max_yaw_rate_deg_s: 90.0,
    };
    let world = world_around(&route, Vec::new(), 2.2);
    let traj = plan(&route, &world, &limits, &Options::default()).unwrap();
    let (v, j) = (limits.max_speed_m_s, limits.max_jerk_m_s3);
    assert!(
        v < limits.max_accel_m_s2.powi(2) / j,
        "the closed form below needs it"
    );
    let ramp_s = 2.0 * (v / j).sqrt();
    let length_m = route[0][1] - route[1][1];
    let expected_s = 2.0 * ramp_s + (length_m - v * ramp_s) / v;
    assert_eq!(traj.method, Method::StopAtWaypoints);
    assert!(
        (traj.duration_s() - expected_s).abs() < 1e-6,
        "{} s",
        traj.duration_s()
    );
    let why = traj.fallback_reason.as_deref().unwrap_or_default();
    assert!(
        why.starts_with("stopping at each waypoint (18.09 s) is faster than the optimised curve ("),
        "{why}"
    );
    dense_check(&traj, &|p| world.is_free(p), &route);
}

/// Where the route turns, the optimised curve is kept: it does not stop at the corners.
#[test]
fn a_turning_route_keeps_the_optimised_curve() {
    let route = [
        [0.0, 0.0, 20.0],
        [0.0, 60.0, 20.0],
        [60.0, 60.0, 20.0],
        [60.0, 0.0, 20.0],
    ];
    let world = world_around(&route, Vec::new(), 2.0);
    let traj = plan(&route, &world, &Limits::default(), &Options::default()).unwrap();
    let stop = stop_at_waypoints(&route, &Limits::default()).unwrap();
    assert_eq!(
        traj.method,
        Method::MinimumJerk,
        "{:?}",
        traj.fallback_reason
    );
    assert!(traj.duration_s() < 0.9 * stop.duration_s());
}

#[test]
fn limits_out_of_range_are_refused_naming_the_field() {
    for (field, bad) in [
        ("max_speed_m_s", 0.0),
        ("max_speed_m_s", 150.0),
        ("max_accel_m_s2", f64::NAN),
        ("max_jerk_m_s3", -1.0),
        ("max_climb_m_s", f64::INFINITY),
        ("max_yaw_rate_deg_s", 0.0),
    ] {
        let mut l = Limits::default();
        match field {
            "max_speed_m_s" => l.max_speed_m_s = bad,
            "max_accel_m_s2" => l.max_accel_m_s2 = bad,
            "max_jerk_m_s3" => l.max_jerk_m_s3 = bad,
            "max_climb_m_s" => l.max_climb_m_s = bad,
            _ => l.max_yaw_rate_deg_s = bad,
        }
        let e = stop_at_waypoints(&[[0.0; 3], [1.0, 0.0, 0.0]], &l).unwrap_err();
        assert!(e.to_string().starts_with(&format!("{field} = ")), "{e}");
    }
}
