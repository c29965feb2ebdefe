//! Switching trajectories in flight (`plan_from`): the new trajectory starts exactly in the
//! state of the one being flown and keeps every guarantee — checked against independent truth:
//! dense samples (≤ 1 cm of travel) against every grown box by brute force, speeds and
//! accelerations at the samples within the limits, the start's velocity and acceleration, rest
//! at the goal.

use skyplan_map::colliders::ObstacleBox;
use skyplan_testkit::XorShift;
use skyplan_trajectory::{
    FreeSpace, GridLayer, Limits, Method, Options, State, Trajectory, plan, plan_from,
};
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, segment_hits_box};

mod common;
use common::{dense_check_free_and_within_limits, norm};

fn gap(a: Neu, b: Neu) -> f64 {
    norm([0, 1, 2].map(|k| a[k] - b[k]))
}

/// The new trajectory from `start` to `goal`: free at ≤ 1 cm of travel, within the limits at
/// every sample, starting in `start`'s state and ending at rest at `goal`.
fn check_switch(traj: &Trajectory, start: &State, goal: Neu, is_free: &dyn Fn(Neu) -> bool) {
    dense_check_free_and_within_limits(traj, is_free);
    let total = traj.duration_s();
    let (a, b) = (traj.state_at(0.0), traj.state_at(total));
    assert!(gap(a.point_neu, start.point_neu) < 1e-6);
    assert!(
        gap(a.vel_neu_m_s, start.vel_neu_m_s) < 1e-6,
        "{a:?} vs {start:?}"
    );
    assert!(gap(a.accel_neu_m_s2, start.accel_neu_m_s2) < 1e-6);
    assert!(gap(b.point_neu, goal) < 1e-9);
    assert!(norm(b.vel_neu_m_s) + norm(b.accel_neu_m_s2) < 1e-12);
}

/// Random planar box worlds: a trajectory through a random route, interrupted at a random
/// instant by a "replan" that flies the rest of the route from there. Every switch that is
/// made keeps the guarantees, and nearly all are made.
#[test]
fn switching_mid_flight_in_random_worlds_keeps_every_guarantee() {
    let (mut made, mut tried) = (0, 0);
    for seed in 1..=40u64 {
        let mut rng = XorShift::new(seed);
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.unit();
        let route: Vec<Neu> = (0..4).map(|_| [u(5.0, 95.0), u(5.0, 95.0), 20.0]).collect();
        let safety_m = u(0.0, 3.0);
        let boxes: Vec<ObstacleBox> = (0..25)
            .map(|_| {
                ObstacleBox::from_row([
                    u(0.0, 100.0),
                    u(0.0, 100.0),
                    u(5.0, 30.0),
                    u(0.5, 8.0),
                    u(0.5, 8.0),
                    u(1.0, 30.0),
                ])
            })
            .filter(|b| {
                let g = Aabb::from_obstacle(b, safety_m);
                !route.windows(2).any(|w| segment_hits_box(w[0], w[1], &g))
            })
            .chain([
                ObstacleBox::from_row([-5.0, -5.0, 0.5, 0.5, 0.5, 0.5]),
                ObstacleBox::from_row([105.0, 105.0, 0.5, 0.5, 0.5, 0.5]),
            ])
            .collect();
        let world: BoxWorld3 = skyplan_testkit::box_world(&boxes, safety_m, 60.0, 10.0);
        let bf = world.brute_force();
        let limits = Limits::default();
        let first = plan(&route, &world, &limits, &Options::default()).expect("a trajectory");
        if first.method != Method::MinimumJerk {
            continue;
        }
        let t = first.duration_s() * u(0.1, 0.8);
        let now = first.state_at(t);
        // The rest of the route: the points the trajectory passes after `t`.
        let passes = first.passes(&route);
        let rest: Vec<Neu> = std::iter::once(now.point_neu)
            .chain(
                route
                    .iter()
                    .zip(&passes)
                    .filter(|(_, p)| p.t_s > t)
                    .map(|(q, _)| *q),
            )
            .collect();
        tried += 1;
        let Ok(next) = plan_from(&now, &rest, &world, &limits, &Options::default()) else {
            continue;
        };
        made += 1;
        eprintln!(
            "compute {} us, {} pieces",
            next.compute_us,
            next.pieces.len()
        );
        check_switch(&next, &now, route[3], &|p| bf.is_free(p));
        assert!(
            skyplan_trajectory::verify_from(&next, &world, now.vel_neu_m_s, now.accel_neu_m_s2)
                .is_ok()
        );
    }
    eprintln!("{made} of {tried} switches made");
    assert!(tried >= 30, "only {tried} switches tried");
    assert!(made * 10 >= tried * 8, "{made} of {tried} switches made");
}

/// An empty square: flying east at full speed, the replan turns north, then back west (a
/// U-turn, so the curve must brake first): both from the moving state, within the limits.
#[test]
fn a_turn_and_a_u_turn_from_full_speed() {
    let free = GridLayer::new(
        skyplan_cspace::Grid2::from_ascii(&(".".repeat(120) + "\n").repeat(120)).unwrap(),
        10.0,
    );
    let limits = Limits::default();
    let first = plan(
        &[[60.0, 2.0, 10.0], [60.0, 118.0, 10.0]],
        &free,
        &limits,
        &Options::default(),
    )
    .unwrap();
    let mut now = first.state_at(first.duration_s() / 2.0);
    assert!(norm(now.vel_neu_m_s) > 9.9, "{now:?}");
    // As evaluated on a level curve, the altitude may be an ulp off the route's: still level.
    now.point_neu[2] = f64::from_bits(10f64.to_bits() + 1);
    let free_at = |p: Neu| free.point_is_free(p);
    for goal in [[110.0, now.point_neu[1], 10.0], [60.0, 5.0, 10.0]] {
        let next = plan_from(
            &now,
            &[now.point_neu, goal],
            &free,
            &limits,
            &Options::default(),
        )
        .unwrap();
        check_switch(&next, &now, goal, &free_at);
    }
    // From rest it is `plan` itself.
    let rest = State {
        vel_neu_m_s: [0.0; 3],
        accel_neu_m_s2: [0.0; 3],
        ..now
    };
    let level = [now.point_neu[0], now.point_neu[1], 10.0];
    let route = [level, [110.0, 60.0, 10.0]];
    assert_eq!(
        plan_from(&rest, &route, &free, &limits, &Options::default())
            .unwrap()
            .pieces,
        plan(&route, &free, &limits, &Options::default())
            .unwrap()
            .pieces
    );
}

/// A start heading straight into a wall too close to stop before it: refused with a reason,
/// never a trajectory through the wall.
#[test]
fn a_start_too_close_to_a_wall_is_refused() {
    let mut text = String::new();
    for _ in 0..60 {
        text.push_str(&(".".repeat(40) + "#" + &".".repeat(19) + "\n"));
    }
    let free = GridLayer::new(skyplan_cspace::Grid2::from_ascii(&text).unwrap(), 10.0);
    let now = State {
        t_s: 0.0,
        point_neu: [30.0, 37.0, 10.0],
        vel_neu_m_s: [0.0, 10.0, 0.0],
        accel_neu_m_s2: [0.0; 3],
        yaw_rad: std::f64::consts::FRAC_PI_2,
    };
    let err = plan_from(
        &now,
        &[now.point_neu, [55.0, 37.0, 10.0]],
        &free,
        &Limits::default(),
        &Options::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("moving start"), "{err}");
}
