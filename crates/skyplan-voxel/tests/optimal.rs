//! The voxel A* against an independent Dijkstra over the same graph, built explicitly with the
//! brute-force checker, on small random box worlds; and every returned segment re-checked.

use proptest::prelude::*;
use skyplan_map::colliders::ObstacleBox;
use skyplan_voxel::{End, Query, VoxelError, VoxelGrid, VoxelSpec, edge_cost, path_cost};
use skyplan_world3::{BoxWorld3, BruteForce, CollisionChecker, Neu, first_blocked_segment};

/// O(V²) Dijkstra over the explicit graph: lattice points free by brute force, 26-neighbour edges
/// free by brute force, start/goal joined to every free lattice point within one step per axis,
/// and the direct segment.
fn oracle(grid: &VoxelGrid, bf: &BruteForce, start: Neu, goal: Neu, w: f64) -> Option<f64> {
    let n = grid.len();
    let step = grid.step();
    let mut pts: Vec<Neu> = (0..n).map(|v| grid.point(v)).collect();
    pts.push(start);
    pts.push(goal);
    let (s, t) = (n, n + 1);
    let usable: Vec<bool> = (0..n + 2).map(|v| v >= n || bf.is_free(pts[v])).collect();
    let close = |a: Neu, b: Neu| (0..3).all(|k| (a[k] - b[k]).abs() <= step[k]);
    let lattice_nb = |u: usize, v: usize| {
        let (a, b) = (grid.ijk(u), grid.ijk(v));
        u != v && (0..3).all(|k| a[k].abs_diff(b[k]) <= 1)
    };
    let mut dist = vec![f64::INFINITY; n + 2];
    let mut done = vec![false; n + 2];
    dist[s] = 0.0;
    loop {
        let u = (0..n + 2)
            .filter(|&v| !done[v] && dist[v].is_finite())
            .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))?;
        if u == t {
            return Some(dist[t]);
        }
        done[u] = true;
        for v in 0..n + 2 {
            if done[v] || !usable[v] {
                continue;
            }
            let edge = match (u >= n, v >= n) {
                (false, false) => lattice_nb(u, v),
                (true, true) => u == s && v == t,
                (true, false) => u == s && close(pts[u], pts[v]),
                (false, true) => v == t && close(pts[u], pts[v]),
            };
            if edge && bf.segment_is_free(pts[u], pts[v]) {
                let d = dist[u] + edge_cost(pts[u], pts[v], w);
                if d < dist[v] {
                    dist[v] = d;
                }
            }
        }
    }
}

fn boxes_strategy() -> impl Strategy<Value = Vec<ObstacleBox>> {
    prop::collection::vec(
        (
            5.0..55.0f64,
            5.0..55.0f64,
            1.0..12.0f64,
            1.0..8.0f64,
            1.0..20.0f64,
        ),
        1..7,
    )
    .prop_map(|v| {
        v.into_iter()
            .map(|(n, e, hn, he, hu)| ObstacleBox::from_row([n, e, hu, hn, he, hu]))
            .collect()
    })
}

fn world_of(boxes: &[ObstacleBox], safety_m: f64) -> BoxWorld3 {
    let spec = skyplan_testkit::spec(safety_m, 40.0, 0.0);
    let bounds = skyplan_world3::Aabb {
        min: [0.0, 0.0, 0.0],
        max: [60.0, 60.0, 40.0],
    };
    BoxWorld3::with_bounds(boxes, &spec, bounds).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn astar_matches_independent_dijkstra(
        boxes in boxes_strategy(),
        safety_m in 0.0..3.0f64,
        s in (0.0..60.0f64, 0.0..60.0f64, 0.0..40.0f64),
        t in (0.0..60.0f64, 0.0..60.0f64, 0.0..40.0f64),
        cell_m in prop::sample::select(vec![5.0, 7.5, 10.0]),
        layer_m in prop::sample::select(vec![4.0, 5.0, 10.0]),
        w in prop::sample::select(vec![0.0, 0.5, 3.0]),
    ) {
        let world = world_of(&boxes, safety_m);
        let bf = world.brute_force();
        let (start, goal) = ([s.0, s.1, s.2], [t.0, t.1, t.2]);
        let grid = VoxelGrid::build(&world, &VoxelSpec { cell_m, layer_m }).unwrap();
        // The grid's classification agrees with brute force on every lattice point.
        for v in 0..grid.len() {
            prop_assert_eq!(grid.is_blocked(v), !bf.is_free(grid.point(v)));
        }
        let query = Query { start, goal, climb_weight: w, shortcut: true };
        let got = grid.plan(&query);
        if !bf.is_free(start) {
            prop_assert_eq!(got, Err(VoxelError::Invalid(End::Start)));
            return Ok(());
        }
        if !bf.is_free(goal) {
            prop_assert_eq!(got, Err(VoxelError::Invalid(End::Goal)));
            return Ok(());
        }
        let want = oracle(&grid, &bf, start, goal, w);
        match (got, want) {
            (Ok(route), Some(best)) => {
                prop_assert!((route.raw_cost - best).abs() <= 1e-9 * best.max(1.0),
                    "A* {} vs Dijkstra {}", route.raw_cost, best);
                prop_assert_eq!(route.path[0], start);
                prop_assert_eq!(*route.path.last().unwrap(), goal);
                prop_assert_eq!(first_blocked_segment(&bf, &route.raw), None);
                prop_assert_eq!(first_blocked_segment(&bf, &route.path), None);
                prop_assert!(route.cost <= route.raw_cost + 1e-9);
                prop_assert!((route.cost - path_cost(&route.path, w)).abs() < 1e-9);
            }
            (Err(VoxelError::NoPath { .. } | VoxelError::NoConnector(_)), None) => {}
            (got, want) => prop_assert!(false, "A* {got:?} vs Dijkstra {want:?}"),
        }
    }
}

#[test]
fn enclosed_goal_is_no_path() {
    // A hollow cage around the goal: four walls, a floor-to-ceiling column each side, and a lid.
    let wall = |n: f64, e: f64, hn: f64, he: f64| ObstacleBox::from_row([n, e, 20.0, hn, he, 20.0]);
    let mut boxes = vec![
        wall(20.0, 30.0, 1.0, 11.0),
        wall(40.0, 30.0, 1.0, 11.0),
        wall(30.0, 20.0, 11.0, 1.0),
        wall(30.0, 40.0, 11.0, 1.0),
    ];
    boxes.push(ObstacleBox::from_row([30.0, 30.0, 39.0, 11.0, 11.0, 1.0]));
    boxes.push(ObstacleBox::from_row([2.0, 2.0, 1.0, 1.0, 1.0, 1.0]));
    let world = world_of(&boxes, 0.5);
    let grid = VoxelGrid::build(&world, &VoxelSpec::default()).unwrap();
    let q = Query {
        start: [50.0, 50.0, 5.0],
        goal: [30.0, 30.0, 10.0],
        climb_weight: 1.0,
        shortcut: true,
    };
    assert!(matches!(grid.plan(&q), Err(VoxelError::NoPath { .. })));
}

#[test]
fn climbing_weight_trades_detour_for_climb() {
    // A low, wide block: w = 0 goes over it, a heavy climb weight goes around.
    let block = ObstacleBox::from_row([30.0, 30.0, 4.0, 4.0, 22.0, 4.0]);
    let world = world_of(&[block], 1.0);
    let grid = VoxelGrid::build(&world, &VoxelSpec::default()).unwrap();
    let q = |w| Query {
        start: [5.0, 30.0, 5.0],
        goal: [55.0, 30.0, 5.0],
        climb_weight: w,
        shortcut: true,
    };
    let over = grid.plan(&q(0.0)).unwrap();
    let around = grid.plan(&q(20.0)).unwrap();
    assert!(over.climb_m > 4.0, "{over:?}");
    assert!(around.climb_m < 1e-9, "{around:?}");
    assert!(over.length_m < around.length_m);
}

#[test]
fn goal_on_a_rooftop() {
    // Goal 1 m above the margin over a 20 m roof.
    let tower = ObstacleBox::from_row([40.0, 40.0, 10.0, 8.0, 8.0, 10.0]);
    let world = world_of(&[tower], 2.0);
    let grid = VoxelGrid::build(&world, &VoxelSpec::default()).unwrap();
    let goal = [40.0, 40.0, 23.0];
    let route = grid
        .plan(&Query {
            start: [5.0, 5.0, 5.0],
            goal,
            climb_weight: 1.0,
            shortcut: true,
        })
        .unwrap();
    assert_eq!(*route.path.last().unwrap(), goal);
    assert_eq!(
        first_blocked_segment(&world.brute_force(), &route.path),
        None
    );
    let top = grid.height_map().top_m(8, 8);
    assert_eq!(top, 22.0);
}
