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
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
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
        .filter(|b| b.meets_altitude(spec.alt_m, spec.safety_m))
        .collect();

    // A made-up path: grid steps (8-connected) through a few corners, and a pruned version that
    // keeps every other corner.
    let corners = [
        (0.0, 0.0),
        (120.0, -40.0),
        (170.0, 60.0),
        (160.0, 180.0),
        (250.0, 300.0),
    ];
    let corners: Vec<(f64, f64)> = corners
        .iter()
        .map(|&(n, e)| {
            grid.nearest_free_ne(n, e)
                .map(|c| grid.center_ne(c))
                .ok_or("no free cell")
        })
        .collect::<Result<_, _>>()?;
    let mut raw = vec![corners[0]];
    for pair in corners.windows(2) {
        let (mut n, mut e) = pair[0];
        let (gn, ge) = pair[1];
        while (n, e) != (gn, ge) {
            n += (gn - n).clamp(-spec.cell_m, spec.cell_m);
            e += (ge - e).clamp(-spec.cell_m, spec.cell_m);
            raw.push((n, e));
        }
    }
    let pruned: Vec<(f64, f64)> = corners.iter().copied().step_by(2).collect();
    let (start, goal) = (corners[0], corners[corners.len() - 1]);
    let scene = Scene {
        title: format!(
            "colliders.csv at {} m, margin {} m",
            spec.alt_m, spec.safety_m
        ),
        grid: &grid,
        obstacles: &obstacles,
        footprints: &[],
        raw_path_ne: &raw,
        pruned_path_ne: &pruned,
        start_ne: Some(start),
        goal_ne: Some(goal),
        graph_ne: &[],
        connectors_ne: &[],
        flight: None,
        zones: &[],
        fleet: &[],
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
    println!(
        "PNG {width}x{height}: {:.1} ms, {} bytes -> /tmp/city.png",
        png_time.as_secs_f64() * 1e3,
        png.len()
    );
    println!(
        "SVG {width}x{height}: {:.1} ms, {} bytes -> /tmp/city.svg",
        svg_time.as_secs_f64() * 1e3,
        svg.len()
    );
    Ok(())
}
