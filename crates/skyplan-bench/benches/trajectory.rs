//! criterion bench of trajectories on the city (`cargo bench -p skyplan-bench --bench
//! trajectory`): the default route's minimum-jerk trajectory at the default limits (corridor,
//! three solves, re-allocation rounds) and its stop-at-each-waypoint profile. `skyplan bench
//! --trajectory --peers` compares with TOPP-RA and ruckig on far routes.

use criterion::{Criterion, criterion_group, criterion_main};
use skyplan_plan::trajectory::{Options, plan, stop_at_waypoints};
use skyplan_plan::{PlanRequest, Session, TrajectoryLimits, World};
use std::hint::black_box;

fn city_trajectory(c: &mut Criterion) {
    let world = World::fcnd_city();
    let boxes = skyplan_bench::trajectory_bench::city_boxes(&world, 5.0).expect("city boxes");
    let route = Session::new(world)
        .plan(&PlanRequest::default())
        .expect("the default route")
        .points_nea();
    let limits = TrajectoryLimits::default();
    let mut group = c.benchmark_group("city_trajectory");
    group.sample_size(20);
    group.bench_function("minimum_jerk_default_route", |b| {
        b.iter(|| {
            plan(black_box(&route), &boxes, &limits, &Options::default())
                .expect("a trajectory")
                .duration_s()
        })
    });
    group.bench_function("stop_at_waypoints_default_route", |b| {
        b.iter(|| {
            stop_at_waypoints(black_box(&route), &limits)
                .expect("a profile")
                .duration_s()
        })
    });
    group.finish();
}

criterion_group!(benches, city_trajectory);
criterion_main!(benches);
