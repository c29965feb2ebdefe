//! The any-angle planner on the bundled city at the bench's grid (921 × 921): three of the bench's
//! far-apart queries (seed 1) are never longer than Theta\* or the octile optimum, never shorter
//! than the straight line, and every segment passes both the exact rule and the grid crate's own
//! (weaker, corner-cutting) traversal.

use skyplan_anyangle::{AnyAngle, GridPoint, segment_is_free_any_angle};
use skyplan_bench::random_far_queries;
use skyplan_cspace::{Grid2, GridSpec, Touch};
use skyplan_search::{GridSearch, MoveModel, Planner};

const CITY: &str = include_str!("../../../data/colliders.csv");

#[test]
fn city_queries_beat_theta_star_and_stay_in_free_space() {
    let map = skyplan_map::colliders::parse_colliders(CITY).expect("bundled map parses");
    // The bench's grid: 5 m altitude, 5 m margin, 1 m cells.
    let grid = Grid2::from_colliders(&map, GridSpec::default()).expect("city grid");
    assert_eq!((grid.rows(), grid.cols()), (921, 921));
    let diagonal = f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let queries = random_far_queries(&grid, MoveModel::Octile, 26, 1, 0.5 * diagonal);
    let planner = AnyAngle::new(&grid);
    let mut search = GridSearch::new();
    for &(s, g) in queries.iter().take(3) {
        let (ps, pg) = (GridPoint::center(s), GridPoint::center(g));
        let path = planner
            .plan(ps, pg)
            .expect("the bench queries are connected");
        let theta = search
            .search(&grid, s, g, MoveModel::Octile, Planner::ThetaStar)
            .expect("Theta* path")
            .cost_cells();
        let octile = search
            .search(&grid, s, g, MoveModel::Octile, Planner::Jps)
            .expect("JPS path")
            .cost_cells();
        let straight = (ps.row - pg.row).hypot(ps.col - pg.col);
        assert!(
            path.length_cells <= theta,
            "{} > Theta* {theta}",
            path.length_cells
        );
        assert!(path.length_cells < octile);
        assert!(path.length_cells >= straight);
        assert!((path.length_m - path.length_cells * GridSpec::default().cell_m).abs() < 1e-9);
        for (w, ne) in path.points.windows(2).zip(path.points_ne.windows(2)) {
            assert!(segment_is_free_any_angle(&grid, w[0], w[1]));
            assert!(grid.segment_is_free_ne(ne[0], ne[1], Touch::Open));
        }
    }
}
