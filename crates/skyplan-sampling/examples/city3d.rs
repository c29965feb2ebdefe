//! Timings on the FCND city map: collision checks, PRM build and queries, RRT-Connect and RRT*.
//!
//! `cargo run --release -p skyplan-sampling --example city3d [queries] [start_alt_m] [goal_alt_m] [max_alt_m]`

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skyplan_sampling::prm::{PrmConfig, Roadmap};
use skyplan_sampling::{Budget, PlannerKind, Request, Status, plan};
use skyplan_world3::{
    Aabb, BoxWorld3, CollisionChecker, Neu, WorldSpec, distance_m, first_blocked_segment,
};
use std::time::{Duration, Instant};

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A uniform point in the box.
fn sample(bounds: &Aabb, rng: &mut ChaCha8Rng) -> Neu {
    [0, 1, 2].map(|i| rng.random_range(bounds.min[i]..bounds.max[i]))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let queries: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(25);
    let alt_lo: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5.0);
    let alt_hi: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(5.0);
    let text = include_str!("../../../data/colliders.csv");
    let map = skyplan_map::colliders::parse_colliders(text).expect("bundled map");
    let max_alt_m: f64 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(100.0);
    let spec = WorldSpec {
        safety_m: 5.0,
        min_alt_m: 0.0,
        max_alt_m,
        margin_bounds_m: 0.0,
    };
    let t = Instant::now();
    let world = BoxWorld3::new(&map.boxes, &spec).expect("world");
    println!(
        "world: {} boxes indexed in {:.2} ms, bounds {:?}",
        map.boxes.len(),
        t.elapsed().as_secs_f64() * 1e3,
        world.bounds()
    );
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    time_point_checks(&world, &mut rng);
    for len_m in [10.0, 50.0, 200.0] {
        time_segment_checks(&world, &mut rng, len_m);
    }
    // Queries: random free start/goal at least 300 m apart, at the given altitudes.
    let bounds = world.bounds();
    let mut qs = Vec::new();
    while qs.len() < queries {
        let mut s = sample(&bounds, &mut rng);
        let mut g = sample(&bounds, &mut rng);
        s[2] = alt_lo;
        g[2] = alt_hi;
        if world.is_free(s) && world.is_free(g) && distance_m(s, g) > 300.0 {
            qs.push((s, g));
        }
    }
    time_reused_roadmap(&world, &qs);
    time_planners(&world, &qs);
}

/// Point collision checks on 100,000 uniform points.
fn time_point_checks(world: &BoxWorld3, rng: &mut ChaCha8Rng) {
    let bounds = world.bounds();
    let pts: Vec<Neu> = (0..100_000).map(|_| sample(&bounds, rng)).collect();
    let t = Instant::now();
    let free = pts.iter().filter(|&&p| world.is_free(p)).count();
    println!(
        "point check: {:.3} µs each ({:.1} % free)",
        t.elapsed().as_secs_f64() * 1e6 / pts.len() as f64,
        100.0 * free as f64 / pts.len() as f64
    );
}

/// Segment checks of `len_m` metres, indexed against brute force (which must agree).
fn time_segment_checks(world: &BoxWorld3, rng: &mut ChaCha8Rng, len_m: f64) {
    let bounds = world.bounds();
    let segs: Vec<(Neu, Neu)> = (0..20_000)
        .map(|_| {
            let a = sample(&bounds, rng);
            let dir: Neu = [
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-0.3..0.3),
            ];
            let n = distance_m([0.0; 3], dir).max(1e-9);
            (
                a,
                [0, 1, 2].map(|i| (a[i] + dir[i] / n * len_m).clamp(bounds.min[i], bounds.max[i])),
            )
        })
        .collect();
    let t = Instant::now();
    let nfree = segs
        .iter()
        .filter(|(a, b)| world.segment_is_free(*a, *b))
        .count();
    let idx = t.elapsed().as_secs_f64() * 1e6 / segs.len() as f64;
    let bf = world.brute_force();
    let t = Instant::now();
    let nfree_bf = segs
        .iter()
        .take(2000)
        .filter(|(a, b)| bf.segment_is_free(*a, *b))
        .count();
    let brute = t.elapsed().as_secs_f64() * 1e6 / 2000.0;
    let agree = segs
        .iter()
        .take(2000)
        .filter(|(a, b)| world.segment_is_free(*a, *b))
        .count()
        == nfree_bf;
    println!(
        "segment check {len_m} m: {idx:.3} µs indexed vs {brute:.1} µs brute force ({:.1} % free, agree {agree})",
        100.0 * nfree as f64 / segs.len() as f64
    );
}

/// One PRM built once and queried for every pair (no smoothing).
fn time_reused_roadmap(world: &BoxWorld3, qs: &[(Neu, Neu)]) {
    let t = Instant::now();
    let roadmap = Roadmap::build(
        world,
        &PrmConfig {
            samples: 4000,
            k: 10,
            seed: 1,
            ..PrmConfig::default()
        },
    );
    println!(
        "PRM build: {} vertices, {} edges, {} components, {:.1} ms ({} edge checks)",
        roadmap.vertices().len(),
        roadmap.edges(),
        roadmap.components(),
        t.elapsed().as_secs_f64() * 1e3,
        roadmap.stats.edge_checks
    );
    let mut times = Vec::new();
    let mut ok = 0;
    let mut ratio = Vec::new();
    for &(s, g) in qs {
        let sol = roadmap.query(world, s, g);
        times.push(sol.elapsed_us as f64 / 1e3);
        if sol.status == Status::Exact {
            assert_eq!(first_blocked_segment(&world.brute_force(), &sol.path), None);
            ok += 1;
            ratio.push(sol.cost_m / distance_m(s, g));
        }
    }
    println!(
        "PRM query (reused roadmap, no smoothing): {ok}/{} exact, median {:.2} ms, length/straight median {:.3}",
        qs.len(),
        median(times),
        median(ratio)
    );
}

/// PRM, RRT-Connect and RRT* planning each pair from scratch.
fn time_planners(world: &BoxWorld3, qs: &[(Neu, Neu)]) {
    for (kind, budget) in [
        (PlannerKind::Prm, Budget::time(Duration::from_secs(5))),
        (
            PlannerKind::RrtConnect,
            Budget::time(Duration::from_secs(5)),
        ),
        (PlannerKind::RrtStar, Budget::time(Duration::from_secs(1))),
    ] {
        let mut first = Vec::new();
        let mut total = Vec::new();
        let mut ratio = Vec::new();
        let mut ok = 0;
        for (i, &(s, g)) in qs.iter().enumerate() {
            let sol = plan(
                world,
                kind,
                &Request {
                    start: s,
                    goal: g,
                    seed: i as u64,
                    budget,
                    ..Request::default()
                },
            );
            total.push(sol.elapsed_us as f64 / 1e3);
            if sol.status == Status::Exact {
                assert_eq!(first_blocked_segment(&world.brute_force(), &sol.path), None);
                ok += 1;
                first.push(sol.first_solution_us.unwrap_or(0) as f64 / 1e3);
                ratio.push(sol.cost_m / distance_m(s, g));
            }
        }
        println!(
            "{:12?} {ok}/{} exact (all re-checked free), first solution median {:.2} ms, run median {:.2} ms, smoothed length/straight median {:.3} max {:.3}",
            kind,
            qs.len(),
            median(first),
            median(total),
            median(ratio.clone()),
            ratio.iter().cloned().fold(0.0, f64::max)
        );
    }
}
