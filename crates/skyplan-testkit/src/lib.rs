//! Test helpers shared by the tests and examples of skyplan's crates (a dev-dependency only):
//! proptest strategies for random box worlds, box worlds from a few numbers, the bundled city,
//! the distance from a point to a route segment, and fixed far-apart grid queries.

use proptest::prelude::*;
use skyplan_cspace::{Cell, Grid2, GridFrame};
use skyplan_map::colliders::ObstacleBox;
use skyplan_world3::{BoxWorld3, Neu, WorldSpec};
use std::ops::Range;

/// The bundled FCND city map's text (`data/colliders.csv`).
pub const CITY_CSV: &str = include_str!("../../../data/colliders.csv");

/// A MovingAI map and its scenarios read from the files `map` and `scen` (for examples and
/// benchmarks: a file that cannot be read or parsed panics, naming it).
pub fn movingai(map: &str, scen: &str) -> (Grid2, Vec<skyplan_map::movingai::Scenario>) {
    let read = |path: &str| {
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("cannot read {path}: {e}"))
    };
    let parsed =
        skyplan_map::movingai::parse_map(&read(map)).unwrap_or_else(|e| panic!("{map}: {e}"));
    let scenarios =
        skyplan_map::movingai::parse_scen(&read(scen)).unwrap_or_else(|e| panic!("{scen}: {e}"));
    let grid = Grid2::from_passable(parsed.height as u32, parsed.width as u32, &parsed.passable)
        .unwrap_or_else(|e| panic!("{map}: {e}"));
    (grid, scenarios)
}

/// Far-apart cell pairs from a fixed 64-bit LCG (the same pairs on every machine): pairs drawn
/// over the whole grid, kept when they are at least half the grid's diagonal apart and `accept`
/// takes them (say, both free and connected), until there are `count`.
///
/// ```
/// use skyplan_cspace::{Grid2, GridSpec};
///
/// let map = skyplan_map::colliders::parse_colliders(skyplan_testkit::CITY_CSV).unwrap();
/// let grid = Grid2::from_colliders(&map, GridSpec::default()).unwrap();
/// let free = |a, b| !grid.is_blocked(a) && !grid.is_blocked(b);
/// let pairs = skyplan_testkit::lcg_far_pairs(&grid, 3, free);
/// assert_eq!(pairs, skyplan_testkit::lcg_far_pairs(&grid, 3, free));
/// assert_eq!(pairs.len(), 3);
/// ```
pub fn lcg_far_pairs(
    grid: &Grid2,
    count: usize,
    mut accept: impl FnMut(Cell, Cell) -> bool,
) -> Vec<(Cell, Cell)> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = |n: usize| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 33) as usize) % n
    };
    let min_d = 0.5 * f64::from(grid.rows()).hypot(f64::from(grid.cols()));
    let mut out = Vec::new();
    while out.len() < count {
        let a = grid.cell(next(grid.len()));
        let b = grid.cell(next(grid.len()));
        let d = (f64::from(a.row) - f64::from(b.row)).hypot(f64::from(a.col) - f64::from(b.col));
        if d >= min_d && accept(a, b) {
            out.push((a, b));
        }
    }
    out
}

/// Random boxes with their centre north and east in 0..100 m, centre up in `up`, half sizes north
/// and east in `half`, half height in `half_up`.
pub fn arb_box(
    up: Range<f64>,
    half: Range<f64>,
    half_up: Range<f64>,
) -> impl Strategy<Value = ObstacleBox> {
    (0.0..100.0, 0.0..100.0, up, half.clone(), half, half_up)
        .prop_map(|(n, e, u, hn, he, hu)| ObstacleBox::from_row([n, e, u, hn, he, hu]))
}

/// Random points with north and east in 0..100 m and altitude in `alt`.
pub fn arb_point(alt: Range<f64>) -> impl Strategy<Value = Neu> {
    (0.0..100.0f64, 0.0..100.0f64, alt).prop_map(|(n, e, a)| [n, e, a])
}

/// A world spec from the ground (0 m) to `max_alt_m`.
pub fn spec(safety_m: f64, max_alt_m: f64, margin_bounds_m: f64) -> WorldSpec {
    WorldSpec {
        safety_m,
        min_alt_m: 0.0,
        max_alt_m,
        margin_bounds_m,
    }
}

/// The world of `boxes` under [`spec`].
pub fn box_world(
    boxes: &[ObstacleBox],
    safety_m: f64,
    max_alt_m: f64,
    margin_bounds_m: f64,
) -> BoxWorld3 {
    BoxWorld3::new(boxes, &spec(safety_m, max_alt_m, margin_bounds_m)).expect("valid spec")
}

/// The bundled city's boxes grown by `safety_m`, from the ground to `max_alt_m`, no margin
/// added around the bounds.
pub fn city_world(safety_m: f64, max_alt_m: f64) -> BoxWorld3 {
    let map = skyplan_map::colliders::parse_colliders(CITY_CSV).unwrap();
    box_world(&map.boxes, safety_m, max_alt_m, 0.0)
}

/// `boxes` that stand clear of a cage around `c` (more than 12 m off it in north or east), plus
/// the cage: a closed hollow cube of six 1 m thick slabs, 18 m across, centred on `c`.
pub fn caged(boxes: Vec<ObstacleBox>, c: Neu) -> Vec<ObstacleBox> {
    let slab = |d: [f64; 3], h: [f64; 3]| {
        ObstacleBox::from_row([c[0] + d[0], c[1] + d[1], c[2] + d[2], h[0], h[1], h[2]])
    };
    let mut all: Vec<ObstacleBox> = boxes
        .into_iter()
        .filter(|b| {
            (b.north_m - c[0]).abs() > b.half_north_m + 12.0
                || (b.east_m - c[1]).abs() > b.half_east_m + 12.0
        })
        .collect();
    all.extend([
        slab([-8.0, 0.0, 0.0], [1.0, 9.0, 9.0]),
        slab([8.0, 0.0, 0.0], [1.0, 9.0, 9.0]),
        slab([0.0, -8.0, 0.0], [9.0, 1.0, 9.0]),
        slab([0.0, 8.0, 0.0], [9.0, 1.0, 9.0]),
        slab([0.0, 0.0, -8.0], [9.0, 9.0, 1.0]),
        slab([0.0, 0.0, 8.0], [9.0, 9.0, 1.0]),
    ]);
    all
}

/// Horizontal distance from the point `p` to the segment `a`–`b` (north, east metres).
pub fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// A random grid of 2..`max_side` rows and columns, up to 45 % blocked, with two free cells
/// (start and goal, possibly the same): the usual case for checking a planner against an oracle.
///
/// ```
/// use proptest::strategy::{Strategy, ValueTree};
/// let mut runner = proptest::test_runner::TestRunner::deterministic();
/// let (grid, start, goal) = skyplan_testkit::arb_grid_and_ends(8).new_tree(&mut runner).unwrap().current();
/// assert!(!grid.is_blocked(start) && !grid.is_blocked(goal));
/// ```
pub fn arb_grid_and_ends(max_side: u32) -> impl Strategy<Value = (Grid2, Cell, Cell)> {
    (2..max_side, 2..max_side, 0.0f64..0.45).prop_flat_map(|(rows, cols, density)| {
        let n = (rows * cols) as usize;
        (
            proptest::collection::vec(proptest::bool::weighted(density), n),
            0..n,
            0..n,
        )
            .prop_map(move |(mut blocked, a, b)| {
                blocked[a] = false;
                blocked[b] = false;
                let grid = Grid2::new(rows, cols, blocked, GridFrame::default())
                    .expect("a valid random grid");
                (grid.clone(), grid.cell(a), grid.cell(b))
            })
    })
}

/// Random grids of 1 to `max_side − 1` rows and columns, each cell blocked with a probability
/// drawn from `density`.
///
/// ```
/// use proptest::strategy::{Strategy, ValueTree};
/// let mut runner = proptest::test_runner::TestRunner::deterministic();
/// let grid = skyplan_testkit::arb_grid(8, 0.0..0.5).new_tree(&mut runner).unwrap().current();
/// assert!(grid.rows() < 8 && grid.cols() < 8);
/// ```
pub fn arb_grid(max_side: u32, density: Range<f64>) -> impl Strategy<Value = Grid2> {
    (1..max_side, 1..max_side, density).prop_flat_map(|(rows, cols, density)| {
        proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
            .prop_map(move |blocked| {
                Grid2::new(rows, cols, blocked, GridFrame::default()).expect("a valid random grid")
            })
    })
}

/// A tiny deterministic generator for tests that need plain random numbers without proptest's
/// shrinking (xorshift64; a zero seed is made odd).
///
/// ```
/// let mut rng = skyplan_testkit::XorShift::new(7);
/// let u = rng.unit();
/// assert!((0.0..1.0).contains(&u));
/// assert_eq!(skyplan_testkit::XorShift::new(7).unit(), u);
/// ```
pub struct XorShift(u64);

impl XorShift {
    /// A generator seeded with `seed` (scrambled, so that nearby seeds give unrelated streams).
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }

    /// A number in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
