//! Times the voxel grid and a few queries on the bundled FCND city map.
//!
//! ```text
//! cargo run --release -p skyplan-voxel --example city_voxel
//! ```
use skyplan_map::colliders::parse_colliders;
use skyplan_voxel::{Query, VoxelGrid, VoxelSpec};
use skyplan_world3::{BoxWorld3, WorldSpec};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/colliders.csv");
    let map = parse_colliders(&std::fs::read_to_string(path)?)?;
    let world = BoxWorld3::new(&map.boxes, &WorldSpec::default())?;
    for spec in [
        VoxelSpec::default(),
        VoxelSpec {
            cell_m: 2.0,
            layer_m: 2.0,
        },
    ] {
        let t = Instant::now();
        let grid = VoxelGrid::build(&world, &spec)?;
        let [a, b, c] = grid.dims();
        println!(
            "grid {} m / {} m: {a} × {b} × {c} = {} voxels, {} blocked, {} clear, built in {:.1} ms",
            spec.cell_m,
            spec.layer_m,
            grid.len(),
            grid.blocked_count(),
            grid.clear_count(),
            t.elapsed().as_secs_f64() * 1e3
        );
        for (goal, w) in [
            ([420.0, 390.0, 5.0], 1.0),
            ([420.0, 390.0, 5.0], 0.0),
            ([420.0, 390.0, 40.0], 1.0),
            ([-300.0, 300.0, 5.0], 1.0),
        ] {
            let q = Query {
                start: [0.0, 0.0, 5.0],
                goal,
                climb_weight: w,
                shortcut: true,
            };
            let r = grid.plan(&q)?;
            println!(
                "  to {goal:?} w {w}: cost {:.1} (lattice {:.1}), {:.1} m, climb {:.1} m, {} expansions, {} edge checks, {:.1} ms",
                r.cost,
                r.raw_cost,
                r.length_m,
                r.climb_m,
                r.expansions,
                r.edge_checks,
                r.search_us as f64 / 1e3
            );
        }
    }
    Ok(())
}
