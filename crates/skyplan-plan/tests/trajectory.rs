//! Trajectories through the planning API: every planner's route on the city, sampled at ≤ 1 cm
//! of travel and checked against every box grown by the margin (brute force, independent of the
//! corridor); limits respected at the samples; refusals and the corridor failure named.

use skyplan_plan::{
    FailureKind, MapKinds, PlanRequest, PlannerId, Session, TrajectoryReport, World,
};
use skyplan_world3::{BoxWorld3, CollisionChecker, WorldSpec};

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Every box of the city grown by `safety_m` (minus a micrometre: a corridor may touch its
/// margin).
fn brute_city(safety_m: f64) -> BoxWorld3 {
    let world = World::fcnd_city();
    let spec = WorldSpec {
        safety_m: (safety_m - 1e-6).max(0.0),
        min_alt_m: -1.0,
        max_alt_m: 10_000.0,
        margin_bounds_m: 1000.0,
    };
    BoxWorld3::new(&world.colliders().unwrap().boxes, &spec).unwrap()
}

fn dense_check(t: &TrajectoryReport, boxes: &BoxWorld3, what: &str) {
    let traj = &t.trajectory;
    let lim = traj.limits;
    // The indexed test (itself checked against testing every box in skyplan-world3), not the
    // corridor's boxes.
    let total = traj.duration_s();
    let n = (total * traj.bounds.speed_m_s / 0.01).ceil() as usize;
    for i in 0..=n {
        let s = traj.state_at(total * i as f64 / n as f64);
        assert!(
            boxes.is_free(s.point_neu),
            "{what}: {:?} at {} s is in a grown box",
            s.point_neu,
            s.t_s
        );
        assert!(
            norm(s.vel_neu_m_s) <= lim.max_speed_m_s * (1.0 + 1e-9),
            "{what}"
        );
        assert!(
            norm(s.accel_neu_m_s2) <= lim.max_accel_m_s2 * (1.0 + 1e-9),
            "{what}"
        );
        assert!(
            s.vel_neu_m_s[2] <= lim.max_climb_m_s * (1.0 + 1e-9),
            "{what}"
        );
        assert!(
            -s.vel_neu_m_s[2] <= lim.max_descent_m_s * (1.0 + 1e-9),
            "{what}"
        );
    }
}

#[test]
fn the_default_route_gets_a_minimum_jerk_trajectory_faster_than_stopping_at_each_waypoint() {
    let mut session = Session::new(World::fcnd_city());
    let plan = session
        .plan(&PlanRequest {
            trajectory: Some(true),
            ..Default::default()
        })
        .unwrap();
    let t = plan.trajectory.as_ref().expect("a trajectory");
    assert_eq!(
        t.trajectory.method.name(),
        "minimum_jerk",
        "{:?}",
        t.trajectory.fallback_reason
    );
    dense_check(t, &brute_city(plan.spec.safety_m), "default route");
    // Never faster than the route at the speed limit; faster than stopping at each waypoint.
    assert!(t.duration_s >= t.length_over_max_speed_s);
    assert!(
        t.duration_s < t.stop_at_waypoints_s,
        "{} s vs {} s",
        t.duration_s,
        t.stop_at_waypoints_s
    );
    // Samples: 10 Hz from 0 to the end, at rest at both ends, ending on the goal.
    let (first, last) = (t.samples[0], *t.samples.last().unwrap());
    assert_eq!(first[0], 0.0);
    assert!((last[0] - t.duration_s).abs() < 1e-9);
    assert!((t.samples[1][0] - 0.1).abs() < 1e-12);
    let goal = plan.points_nea().last().copied().unwrap();
    assert!((last[1] - goal[0]).abs() < 1e-9 && (last[2] - goal[1]).abs() < 1e-9);
    assert!(
        first[4..10]
            .iter()
            .chain(&last[4..10])
            .all(|v| v.abs() < 1e-9)
    );
    // The JSON carries it.
    let json = serde_json::to_value(&plan).unwrap();
    assert_eq!(json["trajectory"]["columns"][10], "yaw_deg");
    assert_eq!(json["trajectory"]["method"], "minimum_jerk");
}

#[test]
fn every_planners_route_on_the_city_gets_a_trajectory_inside_free_space() {
    let mut session = Session::new(World::fcnd_city());
    let boxes = brute_city(5.0);
    // Not the planners for small grids: the city is too large for their tables (tested in
    // every_planner.rs).
    let planners = (PlannerId::ALL.iter()).filter(|p| p.info().maps != MapKinds::SmallGrid);
    for &planner in planners {
        let three_d = planner.info().dims == 3;
        let request = PlanRequest {
            planner: Some(planner),
            goal_ne: Some([60.0, 40.0]),
            goal_alt_m: three_d.then_some(20.0),
            seed: Some(3),
            time_limit_ms: three_d.then_some(1000),
            // Coarse cells: ch's preprocessing of the whole city at 1 m takes a minute in
            // test builds.
            cell_m: Some(4.0),
            trajectory: Some(true),
            ..Default::default()
        };
        let plan = session
            .plan(&request)
            .unwrap_or_else(|e| panic!("{planner}: {e}"));
        let t = plan.trajectory.as_ref().expect("a trajectory");
        dense_check(t, &boxes, planner.name());
        let end = t.trajectory.state_at(t.duration_s);
        let goal = plan.points_nea().last().copied().unwrap();
        assert!(
            norm([0, 1, 2].map(|k| end.point_neu[k] - goal[k])) < 1e-9,
            "{planner}"
        );
    }
}

#[test]
fn limits_without_trajectory_and_out_of_range_are_refused_by_name() {
    let mut session = Session::new(World::fcnd_city());
    let e = session
        .plan(&PlanRequest {
            max_speed_m_s: Some(5.0),
            ..Default::default()
        })
        .unwrap_err();
    assert_eq!(e.kind, FailureKind::BadRequest);
    assert!(
        e.message
            .starts_with("max_speed_m_s is used only with a trajectory"),
        "{}",
        e.message
    );
    let e = session
        .plan(&PlanRequest {
            trajectory: Some(true),
            max_speed_m_s: Some(150.0),
            ..Default::default()
        })
        .unwrap_err();
    assert_eq!(e.kind, FailureKind::BadRequest);
    assert_eq!(
        e.message,
        "max_speed_m_s = 150: expected a number above 0 and at most 100"
    );
}

#[test]
fn a_trajectory_from_the_goal_to_itself_is_a_bad_request_not_an_internal_error() {
    let mut session = Session::new(World::fcnd_city());
    let e = session
        .plan(&PlanRequest {
            goal_ne: Some([0.0, 0.0]),
            trajectory: Some(true),
            ..Default::default()
        })
        .unwrap_err();
    assert_eq!(e.kind, FailureKind::BadRequest, "{}", e.message);
    assert_eq!(
        e.message,
        "trajectory: the route has fewer than two distinct points: nothing to fly"
    );
}

#[test]
fn a_route_squeezing_between_diagonal_cells_has_no_corridor_and_says_where() {
    // Corner cutting lets the route pass between two diagonal blocked cells, through a point
    // that no free box can hold.
    let text = "type octile\nheight 3\nwidth 3\nmap\n...\n.@.\n..@\n";
    let mut session = Session::new(World::from_movingai("squeeze.map", text).unwrap());
    let plain = session.plan(&PlanRequest {
        planner: Some(PlannerId::Astar),
        start_ne: Some([0.5, 1.5]),
        goal_ne: Some([1.5, 2.5]),
        corner_cutting: Some(true),
        ..Default::default()
    });
    let route = plain
        .expect("corner cutting finds the diagonal")
        .points_nea();
    let e = session
        .plan(&PlanRequest {
            planner: Some(PlannerId::Astar),
            start_ne: Some([0.5, 1.5]),
            goal_ne: Some([1.5, 2.5]),
            corner_cutting: Some(true),
            trajectory: Some(true),
            ..Default::default()
        })
        .unwrap_err();
    assert_eq!(
        e.kind,
        FailureKind::NoCorridor,
        "{} (route {route:?})",
        e.message
    );
    assert!(
        e.message
            .starts_with("trajectory: no safe corridor near north"),
        "{}",
        e.message
    );
}
