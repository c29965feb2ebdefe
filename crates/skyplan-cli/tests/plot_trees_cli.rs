//! `skyplan plan --planner rrt-connect|rrt-star --plot`: the top view draws the planners' trees.

mod common;
use common::succeed;

#[test]
fn rrt_pictures_show_their_trees() {
    let dir = tempfile::tempdir().unwrap();
    for (planner, label) in [
        ("rrt-connect", "RRT-Connect trees"),
        ("rrt-star", "RRT* tree"),
    ] {
        succeed(
            dir.path(),
            &format!(
                "plan --planner {planner} --goal-ne 420,390 \
                 --time-limit-ms 200 --out route.json --plot trees.svg"
            ),
        );
        let svg = std::fs::read_to_string(dir.path().join("trees.svg")).unwrap();
        assert!(svg.contains(label), "{planner}: legend {label:?}");
    }
}
