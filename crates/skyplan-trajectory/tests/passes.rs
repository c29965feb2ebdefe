//! Where a trajectory passes its route's points, against independent truth: the
//! stop-at-each-waypoint profile comes to rest exactly at every point, so its passes are the
//! instants it stands still (found here by a dense scan of the speed, not by the programme), and
//! each leg's peak ground speed is the densest sample maximum between two of them.

use skyplan_cspace::Grid2;
use skyplan_trajectory::{GridLayer, Limits, Options, plan, stop_at_waypoints};
use skyplan_world3::Neu;

fn ground_speed(v: Neu) -> f64 {
    v[0].hypot(v[1])
}

#[test]
fn the_stop_at_each_waypoint_profile_passes_where_it_stands_still() {
    // Out along a street and back past the same points (the passes must keep the route's order),
    // then a climb.
    let route = [
        [0.0, 0.0, 10.0],
        [60.0, 0.0, 10.0],
        [60.0, 30.0, 10.0],
        [0.5, 30.0, 10.0],
        [0.5, 0.5, 10.0],
        [0.5, 0.5, 25.0],
    ];
    let limits = Limits::default();
    let traj = stop_at_waypoints(&route, &limits).unwrap();
    let passes = traj.passes(&route);
    assert_eq!(passes.len(), route.len());
    // Independent: the instants of rest, by a 1 ms scan (rest at a waypoint lasts an instant).
    let total = traj.duration_s();
    let n = (total / 0.001).ceil() as usize;
    let samples: Vec<_> = (0..=n)
        .map(|i| traj.state_at(total * i as f64 / n as f64))
        .collect();
    let speed = |i: usize| {
        let v = samples[i].vel_neu_m_s;
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    };
    let mut rests = vec![0usize];
    for i in 1..n {
        if speed(i) < speed(i - 1) && speed(i) <= speed(i + 1) && speed(i) < 0.05 {
            rests.push(i);
        }
    }
    rests.push(n);
    assert_eq!(rests.len(), route.len(), "one rest per waypoint");
    for (k, (p, &i)) in passes.iter().zip(&rests).enumerate() {
        assert!(
            (p.t_s - samples[i].t_s).abs() < 0.03,
            "waypoint {k}: {} s vs {} s",
            p.t_s,
            samples[i].t_s
        );
        assert!(p.miss_m < 0.01, "waypoint {k} missed by {} m", p.miss_m);
        if k > 0 {
            let peak = (rests[k - 1]..=i)
                .map(|j| ground_speed(samples[j].vel_neu_m_s))
                .fold(0.0, f64::max);
            // The passes' 0.02 s samples see the same plateau (cruise at the limit or the peak of
            // a short leg's profile) to within what 0.02 s of the jerk-limited ramp changes.
            assert!(
                (p.peak_ground_speed_m_s - peak).abs() < 0.02,
                "leg {k}: {} vs {peak}",
                p.peak_ground_speed_m_s
            );
            assert!(p.peak_ground_speed_m_s <= limits.max_speed_m_s + 1e-9);
        }
    }
    // The climb is vertical: no ground speed on it (but the last 0.02 s of the stop before it).
    assert!(passes[5].peak_ground_speed_m_s < 0.01);
    // The long legs reach the speed limit.
    assert!((passes[1].peak_ground_speed_m_s - limits.max_speed_m_s).abs() < 1e-6);
}

#[test]
fn a_minimum_jerk_trajectory_rounds_its_corners_in_order() {
    let free = GridLayer::new(
        Grid2::from_ascii(&(".".repeat(80) + "\n").repeat(80)).unwrap(),
        10.0,
    );
    let route = [
        [1.0, 1.0, 10.0],
        [60.0, 1.0, 10.0],
        [60.0, 60.0, 10.0],
        [1.0, 60.0, 10.0],
    ];
    let traj = plan(&route, &free, &Limits::default(), &Options::default()).unwrap();
    let passes = traj.passes(&route);
    assert!(passes.windows(2).all(|w| w[0].t_s < w[1].t_s));
    assert_eq!(passes[0].t_s, 0.0);
    assert_eq!(passes[3].t_s, traj.duration_s());
    assert!(passes[0].miss_m < 1e-9 && passes[3].miss_m < 1e-9);
    // Each corner: the pass is the closest the trajectory comes to it (brute force, 1 ms, over
    // the whole flight: the route does not come back near its corners).
    let total = traj.duration_s();
    for k in 1..3 {
        let closest = (0..=(total / 0.001) as usize)
            .map(|i| {
                let p = traj.state_at(i as f64 * 0.001).point_neu;
                ((p[0] - route[k][0]).powi(2)
                    + (p[1] - route[k][1]).powi(2)
                    + (p[2] - route[k][2]).powi(2))
                .sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(passes[k].miss_m >= closest - 1e-9);
        assert!(
            passes[k].miss_m - closest < 0.25,
            "corner {k}: {} m vs {closest} m",
            passes[k].miss_m
        );
        assert!(passes[k].peak_ground_speed_m_s > 2.0);
    }
}
