//! `skyplan plan --planner rrt-connect|rrt-star --plot`: the top view draws the planners' trees.

use assert_cmd::Command;

#[test]
fn rrt_pictures_show_their_trees() {
    let dir = tempfile::tempdir().unwrap();
    for (planner, label) in [
        ("rrt-connect", "RRT-Connect trees"),
        ("rrt-star", "RRT* tree"),
    ] {
        let out = Command::cargo_bin("skyplan")
            .unwrap()
            .current_dir(dir.path())
            .args(["plan", "--planner", planner, "--goal-ne", "420,390"])
            .args(["--time-limit-ms", "200", "--out", "route.json"])
            .args(["--plot", "trees.svg"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{planner}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let svg = std::fs::read_to_string(dir.path().join("trees.svg")).unwrap();
        assert!(svg.contains(label), "{planner}: legend {label:?}");
    }
}
