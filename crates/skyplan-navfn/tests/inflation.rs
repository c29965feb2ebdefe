//! Nav2-style inflation against numbers computed by hand.

use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_navfn::{Costmap, INSCRIBED, Inflation, LETHAL, NavError, distance_transform};

/// A 9 × 9 grid of 0.5 m cells with one obstacle in the middle (row 4, col 4).
fn one_obstacle() -> Grid2 {
    let mut blocked = vec![false; 81];
    blocked[4 * 9 + 4] = true;
    let frame = GridFrame {
        cell_m: 0.5,
        ..GridFrame::default()
    };
    Grid2::new(9, 9, blocked, frame).unwrap()
}

#[test]
fn costs_match_hand_computed_values() {
    // Inscribed radius 0.6 m, inflation radius 2 m, k = 2 /m; cost = ⌊252·e^(−2(d − 0.6))⌋.
    let params = Inflation {
        inscribed_radius_m: 0.6,
        inflation_radius_m: 2.0,
        cost_scaling_factor: 2.0,
    };
    let costmap = Costmap::inflate(&one_obstacle(), params).unwrap();
    let at = |dr: u32, dc: u32| costmap.cost(Cell::new(4 + dr, 4 + dc)).unwrap();
    // (offset in cells, distance in metres, 252·e^(−2(d−0.6)) by hand)
    assert_eq!(at(0, 0), LETHAL); // the obstacle
    assert_eq!(at(0, 1), INSCRIBED); // 0.5 m ≤ 0.6 m
    assert_eq!(at(1, 1), 203); // 0.7071 m: 252·e^(−0.2142) = 203.41
    assert_eq!(at(0, 2), 113); // 1.0 m: 252·e^(−0.8) = 113.23
    assert_eq!(at(1, 2), 89); // 1.1180 m: 252·e^(−1.0361) = 89.42
    assert_eq!(at(2, 2), 49); // 1.4142 m: 252·e^(−1.6284) = 49.45
    assert_eq!(at(0, 3), 41); // 1.5 m: 252·e^(−1.8) = 41.66
    assert_eq!(at(1, 3), 35); // 1.5811 m: 252·e^(−1.9623) = 35.42
    assert_eq!(at(2, 3), 22); // 1.8028 m: 252·e^(−2.4056) = 22.73
    assert_eq!(at(0, 4), 15); // 2.0 m, exactly the inflation radius: 252·e^(−2.8) = 15.32
    assert_eq!(at(1, 4), 0); // 2.0616 m: beyond the inflation radius
    assert_eq!(at(4, 4), 0);
    // Symmetric in all four directions.
    assert_eq!(costmap.cost(Cell::new(2, 4)), Some(113));
    assert_eq!(costmap.cost(Cell::new(4, 1)), Some(41));
    assert_eq!(
        costmap.clearance_m(Cell::new(6, 7)),
        Some(13f64.sqrt() * 0.5)
    );
    assert_eq!(costmap.normalised()[4 * 9 + 4], 255);
}

#[test]
fn nav2_defaults_and_no_obstacles() {
    let grid = Grid2::new(3, 3, vec![false; 9], GridFrame::default()).unwrap();
    let costmap = Costmap::inflate(&grid, Inflation::default()).unwrap();
    assert!(costmap.costs().iter().all(|&c| c == 0));
    assert!(distance_transform(&grid).iter().all(|d| d.is_infinite()));
}

#[test]
fn bad_parameters_are_named() {
    let err = Costmap::inflate(
        &one_obstacle(),
        Inflation {
            inscribed_radius_m: -1.0,
            ..Inflation::default()
        },
    )
    .unwrap_err();
    assert!(matches!(
        err,
        NavError::BadParameter {
            name: "inscribed_radius_m",
            ..
        }
    ));
}
