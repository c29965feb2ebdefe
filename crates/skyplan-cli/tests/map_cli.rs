//! `skyplan map tile`: the copies are the map, shifted; the result plans.

mod common;
use common::{code_of, succeed};

#[test]
fn tiled_city_has_k_squared_copies_and_plans_across_them() {
    let dir = tempfile::tempdir().unwrap();
    succeed(
        dir.path(),
        "map tile --times 2 --pitch-m 1000 --out city2.csv",
    );
    let small = skyplan_map::colliders::parse_colliders(skyplan_plan::FCND_CITY_CSV).unwrap();
    let text = std::fs::read_to_string(dir.path().join("city2.csv")).unwrap();
    let big = skyplan_map::colliders::parse_colliders(&text).unwrap();
    assert_eq!(big.home, small.home);
    assert_eq!(big.boxes.len(), 4 * small.boxes.len());
    let last = big.boxes.last().unwrap();
    let orig = small.boxes.last().unwrap();
    assert_eq!(
        (last.north_m, last.east_m),
        (orig.north_m + 1000.0, orig.east_m + 1000.0)
    );
    // Across the copies: the default goal of the north-east copy.
    succeed(
        dir.path(),
        "plan --map city2.csv --goal-ne 1420,1390 --json --out w.json",
    );
    assert_eq!(
        code_of(dir.path(), "map tile --times 0 --out x.csv"),
        Some(2)
    );
}
