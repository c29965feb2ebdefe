//! Renders the FCND city map with a made-up path to `/tmp/city.png` and `/tmp/city.svg`.
//!
//! ```text
//! cargo run --release -p skyplan-plot --example city [-- WIDTH HEIGHT]
//! ```
use std::time::Instant;

use skyplan_cspace::{Grid2, GridSpec};
use skyplan_map::colliders::parse_colliders;
use skyplan_plot::{Scene, render_png, render_svg};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<u32> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let (width, height) = match args[..] {
        [w, h] => (w, h),
        [] => (1200, 1000),
        _ => return Err("usage: city [WIDTH HEIGHT]".into()),
    };
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/colliders.csv");
    let map = parse_colliders(&std::fs::read_to_string(path)?)?;
    let spec = GridSpec::default();
    let grid = Grid2::from_colliders(&map, spec)?;
    let obstacles: Vec<_> = map
        .boxes
        .iter()
        .copied()
        .filter(|b| b.top_m() + spec.safety_m > spec.alt_m && b.bottom_m() - spec.safety_m < spec.alt_m)
        .collect();

    // A made-up path: a staircase of grid steps along the straight line from start to goal.
    let start = grid.center_ne(grid.nearest_free_ne(0.0, 0.0).ok_or("no free cell")?);
    let goal = grid.center_ne(grid.nearest_free_ne(250.0, 300.0).ok_or("no free cell")?);
    let steps = ((goal.0 - start.0).abs().max((goal.1 - start.1).abs()) / spec.cell_m).ceil() as usize;
    let cell = spec.cell_m;
    let raw: Vec<(f64, f64)> = (0..=steps)
        .map(|i| {
            let t = i as f64 / steps as f64;
            let n = start.0 + t * (goal.0 - start.0);
            let e = start.1 + t * (goal.1 - start.1);
            (((n - start.0) / cell).round() * cell + start.0, ((e - start.1) / cell).round() * cell + start.1)
        })
        .collect();
    let pruned = vec![start, raw[raw.len() / 3], raw[2 * raw.len() / 3], goal];
    let scene = Scene {
        title: format!("colliders.csv at {} m, margin {} m", spec.alt_m, spec.safety_m),
        grid: &grid,
        obstacles: &obstacles,
        raw_path_ne: &raw,
        pruned_path_ne: &pruned,
        start_ne: Some(start),
        goal_ne: Some(goal),
    };

    let t = Instant::now();
    let png = render_png(&scene, width, height)?;
    let png_time = t.elapsed();
    let t = Instant::now();
    let svg = render_svg(&scene, width, height)?;
    let svg_time = t.elapsed();
    std::fs::write("/tmp/city.png", &png)?;
    std::fs::write("/tmp/city.svg", &svg)?;
    println!(
        "grid {}x{} ({} blocked, {} rectangles), {} obstacles",
        grid.rows(),
        grid.cols(),
        grid.blocked_count(),
        skyplan_plot::blocked_rects(&grid).len(),
        obstacles.len()
    );
    println!("PNG {width}x{height}: {:.1} ms, {} bytes -> /tmp/city.png", png_time.as_secs_f64() * 1e3, png.len());
    println!("SVG {width}x{height}: {:.1} ms, {} bytes -> /tmp/city.svg", svg_time.as_secs_f64() * 1e3, svg.len());
    Ok(())
}
