//! Every planner through the one door, on the city: routes exactly free by an independent check,
//! ends where asked, kinds of failure as documented. (These were CLI tests before the facade.)

use skyplan_plan::{FailureKind, MapKinds, OptionGroup, PlanRequest, PlannerId, Session, World};
use skyplan_world3::{BoxWorld3, CollisionChecker, WorldSpec};

fn city() -> Session {
    Session::new(World::fcnd_city())
}

/// An independent check of a route among the boxes: every segment against every box grown by
/// the margin (minus a hair for routes that run along a margin's edge), by dense sampling.
fn assert_route_clear(world: &World, points: &[[f64; 3]], safety_m: f64) {
    let map = world.colliders().unwrap();
    let spec = WorldSpec {
        safety_m: (safety_m - 0.01).max(0.0),
        min_alt_m: -1.0,
        max_alt_m: 10_000.0,
        margin_bounds_m: 1000.0,
    };
    let boxes = BoxWorld3::new(&map.boxes, &spec).unwrap();
    let brute = boxes.brute_force();
    for w in points.windows(2) {
        let len = skyplan_world3::distance_m(w[0], w[1]);
        let n = (len / 0.05).ceil().max(1.0) as usize;
        for k in 0..=n {
            let p = skyplan_world3::lerp(w[0], w[1], k as f64 / n as f64);
            assert!(
                brute.is_free(p),
                "point {p:?} of segment {:?} → {:?} is inside a grown box",
                w[0],
                w[1]
            );
        }
    }
}

#[test]
fn every_route_producing_planner_flies_a_clear_route_on_the_city() {
    let mut session = city();
    for &planner in PlannerId::ALL {
        let three_d = planner.info().dims == 3;
        let request = PlanRequest {
            planner: Some(planner),
            goal_ne: Some([60.0, 40.0]),
            seed: Some(3),
            time_limit_ms: three_d.then_some(5000),
            ..Default::default()
        };
        if planner.info().maps == MapKinds::SmallGrid {
            // The city is too large for its table: refused at once, saying so.
            let failure = session.plan(&request).unwrap_err();
            assert_eq!(failure.kind, FailureKind::BadRequest, "{planner}");
            assert!(
                failure.message.contains("for small maps"),
                "{}",
                failure.message
            );
            continue;
        }
        let plan = session
            .plan(&request)
            .unwrap_or_else(|e| panic!("{planner}: {e}"));
        assert_eq!(plan.planner, planner);
        let points = plan.points_nea();
        assert_eq!(
            points.first().map(|p| (p[0], p[1])),
            Some((0.0, 0.0)),
            "{planner}"
        );
        assert_eq!(
            points.last().map(|p| (p[0], p[1])),
            Some((60.0, 40.0)),
            "{planner}"
        );
        assert!(plan.cost_m >= plan.straight_line_m - 1e-9, "{planner}");
        assert_route_clear(session.world(), &points, 5.0);
        // The JSON report names the planner by its CLI spelling, and no Rust Debug names leak.
        let json = serde_json::to_string(&plan).unwrap();
        assert!(
            json.contains(&format!("\"planner\":\"{}\"", planner.name())),
            "{json}"
        );
        for debug in ["Some(", "None", "JpsPlus", "Octile\"", "Collinear"] {
            assert!(!json.contains(debug), "{planner}: {debug} in {json}");
        }
    }
}

#[test]
fn optimal_grid_planners_agree_on_the_default_route() {
    let mut session = city();
    let cost = |s: &mut Session, p| {
        s.plan(&PlanRequest {
            planner: Some(p),
            ..Default::default()
        })
        .unwrap()
        .cost_m
    };
    let jps = cost(&mut session, PlannerId::Jps);
    // The published FCND figure (README): 1097.94 m on the 921 × 921 grid.
    assert!((jps - 1097.94).abs() < 0.005, "{jps}");
    assert!(cost(&mut session, PlannerId::Theta) < jps);
    // Every exact planner of the registry finds the same length, on 4 m cells (where the
    // contraction hierarchy's preprocessing takes a second, not minutes).
    let coarse = |s: &mut Session, p| {
        s.plan(&PlanRequest {
            planner: Some(p),
            cell_m: Some(4.0),
            ..Default::default()
        })
        .unwrap()
        .cost_m
    };
    let jps = coarse(&mut session, PlannerId::Jps);
    // (Not the planners for small grids: the city at 4 m is too large for their tables.)
    let exact: Vec<PlannerId> = (PlannerId::ALL.iter().copied())
        .filter(|p| p.is_exact_on_grids() && p.info().maps != MapKinds::SmallGrid)
        .collect();
    assert!(exact.len() >= 6, "{exact:?}");
    for p in exact {
        assert_eq!(coarse(&mut session, p), jps, "{p}");
    }
}

#[test]
fn the_3d_planners_accept_every_point_the_grid_planners_accept() {
    let mut session = city();
    // Free cells on the grid's four edges: a grid planner takes them, so must every 3D planner
    // (the flight volume covers the grid's extent).
    let grid = session.grid(5.0, 5.0, 1.0).unwrap();
    let (rows, cols) = (grid.rows(), grid.cols());
    let edges = [
        (0..cols)
            .map(|c| skyplan_cspace::Cell::new(0, c))
            .collect::<Vec<_>>(),
        (0..cols)
            .map(|c| skyplan_cspace::Cell::new(rows - 1, c))
            .collect(),
        (0..rows).map(|r| skyplan_cspace::Cell::new(r, 0)).collect(),
        (0..rows)
            .map(|r| skyplan_cspace::Cell::new(r, cols - 1))
            .collect(),
    ];
    for edge in edges {
        let cell = edge
            .into_iter()
            .find(|&c| !grid.is_blocked(c))
            .expect("a free cell on every edge");
        let (n, e) = grid.center_ne(cell);
        let goal = [n, e];
        let grid_plan = session.plan(&PlanRequest {
            goal_ne: Some(goal),
            ..Default::default()
        });
        if let Err(e) = &grid_plan {
            assert_ne!(
                e.kind,
                FailureKind::InvalidGoal,
                "grid planner refused {goal:?}: {e}"
            );
        }
        let three_d = PlannerId::ALL.iter().filter(|p| p.info().dims == 3);
        for &planner in three_d {
            let r = session.plan(&PlanRequest {
                planner: Some(planner),
                goal_ne: Some(goal),
                time_limit_ms: Some(1000),
                ..Default::default()
            });
            if let Err(e) = r {
                assert_ne!(
                    e.kind,
                    FailureKind::InvalidGoal,
                    "{planner} refused {goal:?}: {e}"
                );
            }
        }
    }
}

#[test]
fn failures_have_kinds_and_say_what_is_wrong() {
    let mut session = city();
    let fail = |s: &mut Session, r: PlanRequest| s.plan(&r).unwrap_err();
    let e = fail(
        &mut session,
        PlanRequest {
            goal_ne: Some([5000.0, 0.0]),
            ..Default::default()
        },
    );
    assert_eq!(e.kind, FailureKind::InvalidGoal);
    assert!(
        e.message.contains("off the map") && e.message.contains("nearest free cell centre"),
        "{e}"
    );
    let e = fail(
        &mut session,
        PlanRequest {
            start_ne: Some([-310.2, -439.2]),
            ..Default::default()
        },
    );
    assert_eq!(e.kind, FailureKind::InvalidStart, "{e}");
    let e = fail(
        &mut session,
        PlanRequest {
            alt_m: Some(-5.0),
            ..Default::default()
        },
    );
    assert_eq!(e.kind, FailureKind::BadRequest);
    let e = fail(
        &mut session,
        PlanRequest {
            goal_lla: Some([37.79, -110.0]),
            ..Default::default()
        },
    );
    assert_eq!(e.kind, FailureKind::InvalidGoal);
    assert!(e.message.contains("UTM zone 12"), "{e}");
    // A 3D planner on a grid map is a bad request naming the planners that do work there.
    let grid = skyplan_cspace::Grid2::from_ascii("....\n....").unwrap();
    let mut tiny = Session::new(World::from_grid("tiny", grid));
    let e = tiny
        .plan(&PlanRequest {
            planner: Some(PlannerId::Prm),
            start_ne: Some([0.5, 0.5]),
            goal_ne: Some([1.5, 3.5]),
            ..Default::default()
        })
        .unwrap_err();
    assert_eq!(e.kind, FailureKind::BadRequest);
    assert!(
        e.message.contains("colliders") && e.message.contains("wavefront"),
        "{e}"
    );
}

#[test]
fn an_enclosed_goal_is_no_path_with_both_regions() {
    let grid =
        skyplan_cspace::Grid2::from_ascii(".......\n.#####.\n.#...#.\n.#####.\n.......").unwrap();
    let mut s = Session::new(World::from_grid("box", grid));
    // Every planner that takes a grid map.
    for planner in PlannerId::for_maps(false) {
        let e = s
            .plan(&PlanRequest {
                planner: Some(planner),
                start_ne: Some([0.5, 0.5]),
                goal_ne: Some([2.5, 3.5]),
                ..Default::default()
            })
            .unwrap_err();
        assert_eq!(e.kind, FailureKind::NoPath, "{planner}: {e}");
    }
}

#[test]
fn lat_lon_ends_give_the_same_route_as_local_ones() {
    let mut s = city();
    let local = s
        .plan(&PlanRequest {
            start_ne: Some([-100.0, -50.0]),
            goal_ne: Some([199.5, -298.5]),
            ..Default::default()
        })
        .unwrap();
    let global = s
        .plan(&PlanRequest {
            start_lla: Some([local.start.lat_deg.unwrap(), local.start.lon_deg.unwrap()]),
            goal_lla: Some([local.goal.lat_deg.unwrap(), local.goal.lon_deg.unwrap()]),
            ..Default::default()
        })
        .unwrap();
    assert_eq!(local.start.cell, global.start.cell);
    assert_eq!(local.goal.cell, global.goal.cell);
    assert_eq!(local.cost_m, global.cost_m);
    for (a, b) in local.waypoints.iter().zip(&global.waypoints) {
        assert!((a[0] - b[0]).abs() < 1e-3 && (a[1] - b[1]).abs() < 1e-3);
    }
}

#[test]
fn registry_rows_are_consistent() {
    for &p in PlannerId::ALL {
        let info = p.info();
        assert!(!info.summary.is_empty());
        // The 3D planners, and only they, take the 3D options; cell searches take the grid
        // path's options and run on every grid map.
        assert_eq!(info.dims == 3, p.uses(OptionGroup::ThreeD), "{p}");
        if p.is_cell_search() {
            assert!(
                p.is_cell_planner() && info.maps != MapKinds::Obstacles,
                "{p}"
            );
        }
    }
}

/// The human summary states the plan's own numbers: its length, its waypoints, its ends.
#[test]
fn the_summary_tells_the_plans_numbers() {
    for planner in [
        PlannerId::JpsPlus,
        PlannerId::RrtConnect,
        PlannerId::Costmap,
    ] {
        let plan = city()
            .plan(&PlanRequest {
                planner: Some(planner),
                goal_ne: Some([60.0, 40.0]),
                seed: Some(3),
                ..PlanRequest::default()
            })
            .unwrap();
        let text = plan.to_string();
        let path = text.lines().find(|l| l.starts_with("path ")).unwrap();
        assert!(path.contains(&format!("{:.2} m", plan.cost_m)), "{path}");
        let waypoints = text.lines().find(|l| l.starts_with("waypoints ")).unwrap();
        assert!(
            waypoints.contains(&format!("{:.2} m flown", plan.mission_length_m)),
            "{waypoints}"
        );
        assert!(
            text.contains(&format!("goal       {}", plan.goal)),
            "{text}"
        );
        assert!(!text.contains("Some(") && !text.contains("None"), "{text}");
    }
}

#[test]
fn grids_below_the_ground_or_above_the_ceiling_are_bad_requests() {
    let mut session = city();
    for alt_m in [-5.0, 10_001.0] {
        let failure = session.grid(alt_m, 5.0, 1.0).unwrap_err();
        assert_eq!(failure.kind, skyplan_plan::FailureKind::BadRequest);
        assert!(
            failure
                .message
                .contains(&format!("alt_m {alt_m}: expected a number from 0 to 10000")),
            "{}",
            failure.message
        );
    }
    assert!(session.grid(0.0, 5.0, 1.0).is_ok());
}

#[test]
fn ch_preprocessing_stops_at_its_time_limit_and_only_ch_and_3d_planners_take_one() {
    let ch = |world: World, time_limit_ms| {
        Session::new(world).plan(&PlanRequest {
            planner: Some(PlannerId::Ch),
            time_limit_ms: Some(time_limit_ms),
            ..PlanRequest::default()
        })
    };
    // The open city at 1 m takes minutes to contract: 1 ms is far too little.
    let failure = ch(World::fcnd_city(), 1).unwrap_err();
    assert_eq!(failure.kind, FailureKind::Timeout, "{}", failure.message);
    assert!(
        failure.message.starts_with("planner ch: "),
        "{}",
        failure.message
    );
    // The subgoal graph's floods cover the open city for seconds: 1 ms stops them too.
    let failure = Session::new(World::fcnd_city())
        .plan(&PlanRequest {
            planner: Some(PlannerId::Subgoal),
            time_limit_ms: Some(1),
            ..PlanRequest::default()
        })
        .unwrap_err();
    assert_eq!(failure.kind, FailureKind::Timeout, "{}", failure.message);
    assert!(
        failure.message.starts_with("planner subgoal: "),
        "{}",
        failure.message
    );
    // The city's first-move table would take gigabytes: refused at once, saying why.
    let failure = Session::new(World::fcnd_city())
        .plan(&PlanRequest {
            planner: Some(PlannerId::FirstMove),
            time_limit_ms: Some(60_000),
            ..PlanRequest::default()
        })
        .unwrap_err();
    assert_eq!(failure.kind, FailureKind::BadRequest, "{}", failure.message);
    assert!(
        failure.message.starts_with("planner first-move: ")
            && failure.message.contains("small maps"),
        "{}",
        failure.message
    );
    // A small random map contracts well within a generous limit.
    let small = World::random_within(40, 40, 0.2, 3, &Default::default()).unwrap();
    let (start, goal) = small.default_endpoints_ne();
    let plan = Session::new(small)
        .plan(&PlanRequest {
            planner: Some(PlannerId::Ch),
            start_ne: start,
            goal_ne: goal,
            time_limit_ms: Some(600_000),
            ..PlanRequest::default()
        })
        .unwrap();
    assert_eq!(plan.planner, PlannerId::Ch);
    let refused = city()
        .plan(&PlanRequest {
            planner: Some(PlannerId::Jps),
            time_limit_ms: Some(1000),
            ..PlanRequest::default()
        })
        .unwrap_err();
    assert_eq!(refused.kind, FailureKind::BadRequest);
    assert!(
        refused
            .message
            .starts_with("time_limit_ms is not used by planner jps")
            && refused
                .message
                .contains("(ch, subgoal, first-move, auto, prm, "),
        "{}",
        refused.message
    );
}
