//! Times `Grid2::from_footprints` on a synthetic city: 100,000 buildings (rotated rectangles and
//! concave L shapes, 10 % with a courtyard) over 10 km² (3,163 m square), rasterised at 1 m with a
//! 5 m margin at 20 m altitude.
//!
//! ```text
//! cargo run --release -p skyplan-cspace --example rasterise_footprints
//! ```

use skyplan_cspace::{Grid2, GridSpec};
use skyplan_map::colliders::GeodeticHome;
use skyplan_map::footprints::{Footprint, FootprintMap};
use std::time::Instant;

fn main() {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut unit = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let side_m = 3163.0;
    let mut footprints = Vec::with_capacity(100_000);
    let mut vertices = 0;
    for i in 0..100_000 {
        let c = [side_m * unit(), side_m * unit()];
        let a = std::f64::consts::PI * unit();
        let (ca, sa) = (a.cos(), a.sin());
        let (hn, he) = (2.0 + 6.0 * unit(), 2.0 + 6.0 * unit());
        let shape: Vec<[f64; 2]> = if i % 2 == 0 {
            vec![[-hn, -he], [-hn, he], [hn, he], [hn, -he]]
        } else {
            vec![
                [-hn, -he],
                [-hn, he],
                [0.0, he],
                [0.0, 0.0],
                [hn, 0.0],
                [hn, -he],
            ]
        };
        let place = |p: &[f64; 2]| [c[0] + p[0] * ca - p[1] * sa, c[1] + p[0] * sa + p[1] * ca];
        let mut rings = vec![shape.iter().map(place).collect::<Vec<_>>()];
        if i % 10 == 0 && i % 2 == 0 {
            let (qn, qe) = (hn / 3.0, he / 3.0);
            rings.push(
                [[-qn, -qe], [-qn, qe], [qn, qe], [qn, -qe]]
                    .iter()
                    .map(place)
                    .collect(),
            );
        }
        vertices += rings.iter().map(Vec::len).sum::<usize>();
        footprints.push(Footprint {
            feature: i,
            rings,
            min_height_m: 0.0,
            height_m: 10.0 + 60.0 * unit(),
        });
    }
    let map = FootprintMap {
        home: GeodeticHome {
            lat_deg: 37.7925,
            lon_deg: -122.3975,
        },
        footprints,
        default_heights: 0,
    };
    let spec = GridSpec {
        alt_m: 20.0,
        safety_m: 5.0,
        cell_m: 1.0,
    };
    let t0 = Instant::now();
    let grid = Grid2::from_footprints(&map, spec).expect("grid");
    let elapsed = t0.elapsed();
    println!(
        "{} footprints ({vertices} vertices) -> {} x {} grid, {} blocked, in {:.3} s",
        map.footprints.len(),
        grid.rows(),
        grid.cols(),
        grid.blocked_count(),
        elapsed.as_secs_f64()
    );
}
