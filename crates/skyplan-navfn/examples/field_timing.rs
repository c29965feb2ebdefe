//! Times the distance fields, the distance transform, inflation and the cost-to-go field on a
//! 1000 × 1000 city-like grid (rectangular blocks; deterministic). Run in release mode:
//! `cargo run --release -p skyplan-navfn --example field_timing`.

use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_navfn::{
    Costmap, FieldMetric, Inflation, MoveModel, cost_to_go, distance_field, distance_transform,
};
use std::time::Instant;

fn city(n: u32) -> Grid2 {
    let mut blocked = vec![false; (n * n) as usize];
    let mut state = 12345u64;
    let mut next = |m: u32| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) % u64::from(m)) as u32
    };
    for _ in 0..900 {
        let (r, c, h, w) = (next(n), next(n), 5 + next(30), 5 + next(30));
        for row in r..(r + h).min(n) {
            for col in c..(c + w).min(n) {
                blocked[(row * n + col) as usize] = true;
            }
        }
    }
    blocked[0] = false;
    Grid2::new(n, n, blocked, GridFrame::default()).expect("a valid grid")
}

fn time<T>(label: &str, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let out = f();
    println!("{label:<44} {:>8.1} ms", t.elapsed().as_secs_f64() * 1e3);
    out
}

fn main() {
    let grid = city(1000);
    println!(
        "grid 1000 × 1000, {:.1} % blocked",
        100.0 * grid.blocked_count() as f64 / grid.len() as f64
    );
    let goal = Cell::new(0, 0);
    for (label, model, metric) in [
        (
            "wavefront BFS, 4-connected",
            MoveModel::FourConnected,
            FieldMetric::Steps,
        ),
        (
            "wavefront BFS, 8-connected",
            MoveModel::Octile,
            FieldMetric::Steps,
        ),
        (
            "distance field Dijkstra, octile",
            MoveModel::Octile,
            FieldMetric::Length,
        ),
    ] {
        time(label, || {
            distance_field(&grid, goal, model, metric).map(|f| f.values().len())
        })
        .expect("field");
    }
    time("Euclidean distance transform (FH)", || {
        distance_transform(&grid).len()
    });
    let params = Inflation {
        inscribed_radius_m: 1.0,
        inflation_radius_m: 10.0,
        cost_scaling_factor: 0.3,
    };
    let costmap = time("inflation (EDT + costs)", || {
        Costmap::inflate(&grid, params)
    })
    .expect("costmap");
    time("cost-to-go field (weight 2), octile", || {
        cost_to_go(&costmap, goal, MoveModel::Octile, 2.0).map(|f| f.values().len())
    })
    .expect("cost to go");
}
