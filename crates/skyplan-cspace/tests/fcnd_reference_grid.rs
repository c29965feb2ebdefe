//! The bundled FCND city map at 5 m altitude with a 5 m margin is the reference grid of the
//! FCND project: 921 × 921 cells, 519,210 of them blocked (FCND's `create_grid`, reproduced
//! with numpy on the same file).

use skyplan_cspace::{Grid2, GridSpec};
use skyplan_map::colliders::parse_colliders;

fn city() -> skyplan_map::colliders::CollidersMap {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/colliders.csv");
    parse_colliders(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn city_grid_at_5m_with_5m_margin_is_the_fcnd_reference() {
    let grid = Grid2::from_colliders(
        &city(),
        GridSpec {
            alt_m: 5.0,
            safety_m: 5.0,
            cell_m: 1.0,
        },
    )
    .unwrap();
    assert_eq!((grid.rows(), grid.cols()), (921, 921));
    assert_eq!(grid.blocked_count(), 519_210);
    let f = grid.frame();
    assert_eq!((f.origin_north_m, f.origin_east_m), (-316.0, -445.0));
}

#[test]
fn higher_altitudes_block_fewer_cells_and_coarser_cells_cover_the_same_area() {
    let map = city();
    let counts: Vec<usize> = [5.0, 20.0, 50.0, 100.0, 250.0]
        .iter()
        .map(|&alt_m| {
            Grid2::from_colliders(
                &map,
                GridSpec {
                    alt_m,
                    safety_m: 5.0,
                    cell_m: 1.0,
                },
            )
            .unwrap()
            .blocked_count()
        })
        .collect();
    assert!(counts.windows(2).all(|w| w[0] >= w[1]), "{counts:?}");
    assert_eq!(
        *counts.last().unwrap(),
        0,
        "nothing in the city is 245 m tall"
    );
    let coarse = Grid2::from_colliders(
        &map,
        GridSpec {
            alt_m: 5.0,
            safety_m: 5.0,
            cell_m: 5.0,
        },
    )
    .unwrap();
    assert_eq!((coarse.rows(), coarse.cols()), (185, 185));
}
