//! Times a trajectory through a route given as JSON `[[north_m, east_m, alt_m], …]` on the
//! bundled city (margin 5 m): `cargo run --release -p skyplan-trajectory --example route_timing -- route.json`.
use skyplan_trajectory::{Limits, Options, plan, stop_at_waypoints};
use std::time::Instant;

fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: route_timing ROUTE.json");
    let text = std::fs::read_to_string(&path).expect("readable route file");
    let route: Vec<[f64; 3]> = parse(&text);
    let world = skyplan_testkit::city_world(5.0, 120.0);
    let limits = Limits::default();
    corridor_ms(&route, &world);
    let rounds0 = Options {
        refine_rounds: 0,
        ..Options::default()
    };
    let t0 = Instant::now();
    let t = plan(&route, &world, &limits, &rounds0).expect("a trajectory");
    eprintln!(
        "no refinement: {:.1} s in {:.1} ms",
        t.duration_s(),
        t0.elapsed().as_secs_f64() * 1e3
    );
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..20 {
        let t0 = Instant::now();
        let t = plan(&route, &world, &limits, &Options::default()).expect("a trajectory");
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        last = Some(t);
    }
    times.sort_by(f64::total_cmp);
    let t = last.expect("ran");
    let stop = stop_at_waypoints(&route, &limits).expect("a profile");
    let len: f64 = route
        .windows(2)
        .map(|w| skyplan_world3::distance_m(w[0], w[1]))
        .sum();
    println!(
        "{}: {} pieces, duration {:.1} s, stop {:.1} s (ratio {:.3}), length/vmax {:.1} s (ratio {:.3}), p50 {:.2} ms, reason {:?}, bounds {:?}",
        t.method.name(),
        t.pieces.len(),
        t.duration_s(),
        stop.duration_s(),
        t.duration_s() / stop.duration_s(),
        len / limits.max_speed_m_s,
        t.duration_s() / (len / limits.max_speed_m_s),
        times[times.len() / 2],
        t.fallback_reason,
        t.bounds
    );
}

fn parse(text: &str) -> Vec<[f64; 3]> {
    let nums: Vec<f64> = text
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().expect("a number"))
        .collect();
    nums.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

#[allow(dead_code)]
fn corridor_ms(route: &[[f64; 3]], world: &skyplan_world3::BoxWorld3) -> f64 {
    let t0 = Instant::now();
    let opts = skyplan_trajectory::CorridorOptions {
        piece_m: 25.0,
        grow_m: 20.0,
    };
    let c = skyplan_trajectory::build_corridor(route, world, true, &opts).expect("corridor");
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    eprintln!("corridor {} cells in {ms:.2} ms", c.len());
    ms
}
