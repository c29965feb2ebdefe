//! Property tests on random grids: returned routes are exactly free, start and goal as asked,
//! and a route exists exactly when the grid connects the two cells.

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_roadmap::{
    Roadmap, RoadmapError, RoadmapSpec, first_blocked_segment, grid_boundary_sites,
};
use skyplan_search::{GridSearch, MoveModel, Planner};

fn grid_strategy() -> impl Strategy<Value = Grid2> {
    (8u32..40, 8u32..40, 0.0f64..0.35, any::<u64>()).prop_map(|(rows, cols, density, seed)| {
        let mut state = seed | 1;
        let blocked = (0..rows * cols)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state % 10_000) as f64 / 10_000.0 < density
            })
            .collect();
        Grid2::new(rows, cols, blocked, GridFrame::default()).unwrap()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn routes_are_exactly_free(grid in grid_strategy(), a in any::<(u16, u16)>(), b in any::<(u16, u16)>(), fa in (0.05f64..0.95, 0.05f64..0.95), fb in (0.05f64..0.95, 0.05f64..0.95)) {
        let ca = Cell::new(u32::from(a.0) % grid.rows(), u32::from(a.1) % grid.cols());
        let cb = Cell::new(u32::from(b.0) % grid.rows(), u32::from(b.1) % grid.cols());
        let s = [f64::from(ca.row) + fa.0, f64::from(ca.col) + fa.1];
        let g = [f64::from(cb.row) + fb.0, f64::from(cb.col) + fb.1];
        let roadmap = Roadmap::from_sites(&grid, &grid_boundary_sites(&grid), &RoadmapSpec::default());
        for (p, q) in roadmap.edges() {
            prop_assert!(first_blocked_segment(&grid, &[p, q]).is_none());
        }
        let reachable = !grid.is_blocked(ca) && !grid.is_blocked(cb)
            && GridSearch::new().search(&grid, ca, cb, MoveModel::Octile, Planner::AStar).is_ok();
        match roadmap.query(&grid, s, g) {
            Ok(route) => {
                prop_assert_eq!(route.points_ne.first(), Some(&s));
                prop_assert_eq!(route.points_ne.last(), Some(&g));
                prop_assert_eq!(first_blocked_segment(&grid, &route.points_ne), None);
                prop_assert!(route.cost_m <= route.graph_cost_m + 1e-9);
                prop_assert!(route.cost_m + 1e-9 >= ((s[0] - g[0]).hypot(s[1] - g[1])));
            }
            Err(RoadmapError::StartBlocked(..)) => prop_assert!(grid.is_blocked(ca)),
            Err(RoadmapError::GoalBlocked(..)) => prop_assert!(grid.is_blocked(cb)),
            Err(RoadmapError::NoPath) => prop_assert!(!reachable),
        }
    }
}
