//! The Voronoi roadmap on the FCND city at 5 m / 5 m: 26 far-apart queries all succeed, every
//! segment re-checks free on the grid and against the 3D boxes at the flight altitude.

use skyplan_cspace::{Grid2, GridSpec};
use skyplan_roadmap::{Roadmap, RoadmapSpec, first_blocked_segment};
use skyplan_search::MoveModel;
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, WorldSpec};

const CITY: &str = include_str!("../../../data/colliders.csv");

#[test]
fn city_far_queries_all_succeed_and_recheck_free() {
    let map = skyplan_map::colliders::parse_colliders(CITY).unwrap();
    let (alt_m, safety_m) = (5.0, 5.0);
    let grid = Grid2::from_colliders(
        &map,
        GridSpec {
            alt_m,
            safety_m,
            cell_m: 1.0,
        },
    )
    .unwrap();
    let roadmap = Roadmap::build(&map, &grid, alt_m, safety_m, &RoadmapSpec::default());
    let f = grid.frame();
    let bounds = Aabb {
        min: [f.origin_north_m, f.origin_east_m, 0.0],
        max: [
            f.origin_north_m + f64::from(grid.rows()) * f.cell_m,
            f.origin_east_m + f64::from(grid.cols()) * f.cell_m,
            120.0,
        ],
    };
    let spec = WorldSpec {
        safety_m,
        min_alt_m: 0.0,
        max_alt_m: 120.0,
        margin_bounds_m: 0.0,
    };
    let world = BoxWorld3::with_bounds(&map.boxes, &spec, bounds).unwrap();
    let exact = world.brute_force();
    let diagonal = f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let queries =
        skyplan_bench::random_far_queries(&grid, MoveModel::Octile, 26, 42, 0.5 * diagonal);
    assert_eq!(queries.len(), 26);
    let mut fallbacks = 0;
    for (k, &(a, b)) in queries.iter().enumerate() {
        let (s, g) = (grid.center_ne(a), grid.center_ne(b));
        let route = roadmap
            .query(&grid, [s.0, s.1], [g.0, g.1])
            .unwrap_or_else(|e| panic!("query {k}: {e}"));
        assert_eq!(route.points_ne.first(), Some(&[s.0, s.1]));
        assert_eq!(route.points_ne.last(), Some(&[g.0, g.1]));
        assert_eq!(
            first_blocked_segment(&grid, &route.points_ne),
            None,
            "query {k}"
        );
        for w in route.points_ne.windows(2) {
            let (p, q) = ([w[0][0], w[0][1], alt_m], [w[1][0], w[1][1], alt_m]);
            assert!(exact.segment_is_free(p, q), "query {k}: {p:?} → {q:?}");
        }
        fallbacks += usize::from(route.fallback.is_some());
    }
    eprintln!(
        "city: {} nodes, {} edges, {} components (largest {}), {} sites, built in {} µs; {fallbacks} of 26 fell back",
        roadmap.nodes().len(),
        roadmap.edge_count(),
        roadmap.component_count(),
        roadmap.largest_component(),
        roadmap.stats().sites,
        roadmap.stats().build_us
    );
    assert_eq!(fallbacks, 0, "every far query should run on the graph");
    // Every graph edge is exactly free.
    for (p, q) in roadmap.edges() {
        assert!(exact.segment_is_free([p[0], p[1], alt_m], [q[0], q[1], alt_m]));
    }
}
