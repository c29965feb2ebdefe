//! The wavefront workshop's three situations: around a U-shaped wall, through a narrow corridor,
//! and an enclosed destination ("path could not be found").

use skyplan_cspace::{Cell, Grid2};
use skyplan_navfn::FieldMetric::{Length, Steps};
use skyplan_navfn::MoveModel::{FourConnected, Octile, OctileCornerCutting};
use skyplan_navfn::{FieldMetric, MoveModel, NavError, distance_field, show};
use skyplan_search::oracle::dijkstra_exact;
use skyplan_search::{GridSearch, Planner, check_path};

/// Text with the NORTHERNMOST row first (as `--show` prints), to a grid (row 0 = south).
fn north_up(text: &str) -> Grid2 {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let flipped: Vec<&str> = lines.into_iter().rev().collect();
    // `S` and `D` only mark the endpoints for the reader; they are free cells.
    Grid2::from_ascii(&flipped.join("\n").replace(['S', 'D'], ".")).unwrap()
}

const MODELS: [MoveModel; 3] = [
    MoveModel::FourConnected,
    MoveModel::Octile,
    MoveModel::OctileCornerCutting,
];

fn assert_matches_astar(grid: &Grid2, source: Cell, destination: Cell) {
    for model in MODELS {
        let field = distance_field(grid, destination, model, FieldMetric::Length).unwrap();
        let descent = field.descend(source).unwrap();
        check_path(grid, &descent.cells, model).unwrap();
        let truth = dijkstra_exact(grid, source, destination, model).unwrap();
        assert_eq!(
            (descent.straight_moves, descent.diagonal_moves),
            (truth.straight, truth.diagonal),
            "{model:?}"
        );
        let astar = GridSearch::new()
            .search(grid, source, destination, model, Planner::AStar)
            .unwrap();
        assert_eq!(descent.length_cells(), astar.cost_cells(), "{model:?}");
    }
}

#[test]
fn around_a_u_shaped_wall() {
    // The destination sits inside a U open to the north; the source is south of its bottom.
    let grid = north_up(
        "
        .........
        .#.....#.
        .#..D..#.
        .#.....#.
        .#######.
        .........
        ....S....",
    );
    let (source, destination) = (Cell::new(0, 4), Cell::new(4, 4));
    assert_matches_astar(&grid, source, destination);
    let field = distance_field(&grid, destination, FourConnected, Steps).unwrap();
    let path = field.descend(source).unwrap();
    // By hand: 1 up, 4 sideways, 5 up past the wall, 2 + 2 sideways back in, 2 down = 16 moves.
    assert_eq!(path.straight_moves, 16);
    assert_eq!(field.value(source), Some(16.0));
    let text = show::workspace(
        &grid,
        Some(source),
        Some(destination),
        &path.cells,
        Some(&field),
    );
    assert_eq!(text.lines().count(), 8);
    assert!(text.contains('S') && text.contains('D') && text.contains('*'));
}

#[test]
fn through_a_narrow_corridor() {
    let grid = north_up(
        "
        ....#....
        ....#....
        S.......D
        ....#....
        ....#....",
    );
    let (source, destination) = (Cell::new(2, 0), Cell::new(2, 8));
    assert_matches_astar(&grid, source, destination);
    for model in MODELS {
        let field = distance_field(&grid, destination, model, FieldMetric::Length).unwrap();
        let path = field.descend(source).unwrap();
        assert!(
            path.cells.contains(&Cell::new(2, 4)),
            "{model:?} must use the gap"
        );
        assert_eq!(path.length_cells(), 8.0);
    }
}

#[test]
fn enclosed_destination_has_no_path_and_unreachable_cells_are_marked() {
    let grid = north_up(
        "
        .......
        .#####.
        .#.D.#.
        .#####.
        S......",
    );
    let (source, destination) = (Cell::new(0, 0), Cell::new(2, 3));
    for model in MODELS {
        let field = distance_field(&grid, destination, model, FieldMetric::Length).unwrap();
        let err = field.descend(source).unwrap_err();
        assert_eq!(
            err,
            NavError::Unreachable {
                source_cell: source,
                destination_cell: destination
            }
        );
        assert!(err.to_string().starts_with("path could not be found"));
        // Everything outside the box is unreachable: 35 cells − 15 in the box (12 wall, 3 inside).
        assert_eq!(field.unreachable_count(), 20);
        let text = show::workspace(&grid, Some(source), Some(destination), &[], Some(&field));
        assert_eq!(
            text,
            "   0123456\n 4 xxxxxxx\n 3 x#####x\n 2 x#.D.#x\n 1 x#####x\n 0 Sxxxxxx\n"
        );
        let matrix = show::distance_matrix(&field, Some(source));
        assert!(matrix.contains('∞') && matrix.contains('#'));
    }
}

#[test]
fn endpoint_at_an_obstacle_or_off_the_grid_is_named() {
    let grid = north_up("..#\n...");
    let err = distance_field(&grid, Cell::new(1, 2), Octile, Length).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the destination (row 1, col 2) is at an obstacle"
    );
    let field = distance_field(&grid, Cell::new(0, 0), Octile, Length).unwrap();
    assert_eq!(
        field.descend(Cell::new(5, 0)).unwrap_err().to_string(),
        "the source cell (row 5, col 0) is outside the 2 × 3 grid"
    );
}

#[test]
fn corner_rule_decides_a_diagonal_gap() {
    // The only way from S to D passes diagonally between two blocked cells.
    let grid = north_up(
        "
        ##D
        #.#
        S##",
    );
    let (source, destination) = (Cell::new(0, 0), Cell::new(2, 2));
    for model in [MoveModel::FourConnected, MoveModel::Octile] {
        let field = distance_field(&grid, destination, model, FieldMetric::Length).unwrap();
        assert!(field.descend(source).is_err(), "{model:?}");
    }
    let field = distance_field(&grid, destination, OctileCornerCutting, Length).unwrap();
    let path = field.descend(source).unwrap();
    assert_eq!(path.diagonal_moves, 2);
}
