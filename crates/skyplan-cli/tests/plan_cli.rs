//! The real `skyplan` binary in temporary directories, on the bundled map and small fixtures.

use serde_json::Value;
use skyplan_cspace::{Cell, Grid2, GridSpec, Touch};
use skyplan_search::MoveModel;
use skyplan_search::oracle::dijkstra_exact;
use std::path::Path;
mod common;
use common::{
    CITY_CSV, assert_no_waypoints, assert_segments_free, cmd, dir_with, fails_with, ok_json, rows,
};

/// `skyplan plan --json LINE`, which must succeed: its JSON.
fn run_json(dir: &Path, line: &str) -> Value {
    ok_json(dir, &format!("plan --json {line}"))
}

fn city_grid(spec: GridSpec) -> Grid2 {
    let map = skyplan_map::colliders::parse_colliders(CITY_CSV).unwrap();
    Grid2::from_colliders(&map, spec).unwrap()
}

/// The grid cell of a JSON start or goal.
fn cell(p: &Value) -> Cell {
    Cell::new(
        p["cell"][0].as_u64().unwrap() as u32,
        p["cell"][1].as_u64().unwrap() as u32,
    )
}

/// A JSON file in `dir`.
fn read_json(dir: &Path, name: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join(name)).unwrap()).unwrap()
}

/// The default job: optimal against the exact oracle, every flown segment free, FCND headings.
#[test]
fn default_plan_is_optimal_free_and_headed() {
    let dir = tempfile::tempdir().unwrap();
    let v = run_json(dir.path(), "--out waypoints.json");
    assert_eq!(v["status"], "ok");
    assert_eq!(v["grid"]["rows"], 921);
    assert_eq!(v["grid"]["blocked_cells"], 519_210);
    let grid = city_grid(GridSpec::default());
    let (start, goal) = (cell(&v["start"]), cell(&v["goal"]));
    let truth = dijkstra_exact(&grid, start, goal, MoveModel::Octile).unwrap();
    assert_eq!(v["cost_m"].as_f64().unwrap(), truth.to_f64());

    let wps = rows(&v);
    assert!(wps.len() >= 2);
    assert_eq!(
        (wps[0][0], wps[0][1]),
        (0.0, 0.0),
        "the mission starts where the vehicle is"
    );
    let last = wps[wps.len() - 1];
    assert_eq!((last[0], last[1]), (420.0, 390.0));
    assert_eq!(wps[0][3], 0.0);
    assert_segments_free(&grid, &wps, Touch::Closed);
    for w in wps.windows(2) {
        assert_eq!(w[1][2], 5.0);
        let heading = (w[1][1] - w[0][1]).atan2(w[1][0] - w[0][0]);
        assert!((w[1][3] - heading).abs() < 1e-12);
    }
    let counts = &v["waypoint_counts"];
    assert!(counts["after_shortcut"].as_u64() <= counts["after_pruning"].as_u64());
    assert!(counts["after_pruning"].as_u64() < counts["grid_path"].as_u64());
    assert!(v["search_time_us"].as_u64().is_some());
    let file = read_json(dir.path(), "waypoints.json");
    assert_eq!(
        rows(&file),
        wps,
        "the file holds the same waypoints as stdout"
    );
}

#[test]
fn lat_lon_goal_and_start_give_the_same_plan_as_local_ones() {
    let dir = tempfile::tempdir().unwrap();
    let local = run_json(dir.path(), "--start-ne -100,-50 --goal-ne 199.5,-298.5");
    let geo = |p: &Value| {
        format!(
            "{},{}",
            p["lat_deg"].as_f64().unwrap(),
            p["lon_deg"].as_f64().unwrap()
        )
    };
    let global = run_json(
        dir.path(),
        &format!(
            "--start-lla {} --goal-lla {}",
            geo(&local["start"]),
            geo(&local["goal"])
        ),
    );
    assert_eq!(local["start"]["cell"], global["start"]["cell"]);
    assert_eq!(local["goal"]["cell"], global["goal"]["cell"]);
    assert_eq!(local["cost_m"], global["cost_m"]);
    let (a, b) = (rows(&local), rows(&global));
    assert!(
        (a[0][0] - b[0][0]).abs() < 1e-3 && (a[0][1] - b[0][1]).abs() < 1e-3,
        "round trip within 1 mm"
    );
}

#[test]
fn move_models_and_planners_agree_with_the_oracle() {
    let dir = tempfile::tempdir().unwrap();
    let grid = city_grid(GridSpec {
        alt_m: 20.0,
        safety_m: 3.0,
        cell_m: 2.0,
    });
    let common = "--alt-m 20 --safety-m 3 --cell-m 2 --start-ne -251,-370 --goal-ne 550,420";
    for (extra, model) in [
        ("--connectivity 4", MoveModel::FourConnected),
        ("--corner-cutting", MoveModel::OctileCornerCutting),
        ("--planner dijkstra", MoveModel::Octile),
    ] {
        let v = run_json(dir.path(), &format!("{common} {extra}"));
        let truth = dijkstra_exact(&grid, cell(&v["start"]), cell(&v["goal"]), model).unwrap();
        assert_eq!(
            v["cost_m"].as_f64().unwrap(),
            truth.to_f64() * 2.0,
            "{extra:?}"
        );
        let touch = if model == MoveModel::OctileCornerCutting {
            Touch::Open
        } else {
            Touch::Closed
        };
        assert_segments_free(&grid, &rows(&v), touch);
    }
}

#[test]
fn every_output_format_is_written_by_extension_and_by_flag() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["w.json", "w.csv", "w.h5", "w.geojson", "w.plan"] {
        cmd(dir.path(), &format!("plan --out {name}"))
            .assert()
            .success();
        assert!(
            dir.path().join(name).metadata().unwrap().len() > 0,
            "{name}"
        );
    }
    cmd(dir.path(), "plan --out route.txt --format csv")
        .assert()
        .success();
    let csv = std::fs::read_to_string(dir.path().join("route.txt")).unwrap();
    assert!(csv.starts_with("north_m,east_m,alt_m,heading_rad,lat_deg,lon_deg"));
    let geo = read_json(dir.path(), "w.geojson");
    let first = &geo["features"][0]["geometry"]["coordinates"][0];
    assert!(
        (first[0].as_f64().unwrap() + 122.39745).abs() < 1e-9,
        "GeoJSON is lon, lat: {first}"
    );
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(
        leftovers.is_empty(),
        "temporary files left behind: {leftovers:?}"
    );
}

#[test]
fn plots_are_real_png_and_svg_files() {
    let dir = tempfile::tempdir().unwrap();
    cmd(dir.path(), "plan --plot p.png").assert().success();
    let png = std::fs::read(dir.path().join("p.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    cmd(dir.path(), "plan --plot p.svg").assert().success();
    let svg = std::fs::read_to_string(dir.path().join("p.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("NORTH") && svg.contains("EAST"));
    fails_with(dir.path(), "plan --plot p.gif", 2, &[".png or .svg"]);
}

#[test]
fn config_file_supplies_defaults_and_flags_win() {
    let dir = dir_with(&[(
        "fcnd.toml",
        "target_altitude = 10.0\nsafety_distance = 3.0\ngoal_ne = [99.5, 0.5]\nmethod = \"dijkstra\"\nout = \"cfg.csv\"\n",
    )]);
    let v = run_json(dir.path(), "--config fcnd.toml --safety-m 4");
    assert_eq!(v["grid"]["alt_m"], 10.0);
    assert_eq!(v["grid"]["safety_m"], 4.0);
    assert_eq!(v["planner"], "dijkstra");
    assert_eq!(v["goal"]["north_m"], 99.5);
    assert!(dir.path().join("cfg.csv").exists());
    std::fs::write(dir.path().join("bad.toml"), "alt_m = 5\nsafty_m = 3\n").unwrap();
    fails_with(
        dir.path(),
        "plan --config bad.toml",
        2,
        &["bad.toml", "safty_m"],
    );
}

/// The route options are `PlanRequest`'s own (one definition for the CLI, the config, the HTTP
/// API and Python): every key is an option of `plan` and `fly`, and a config key counts as its
/// option does (the config's `seed` draws the same random workspace as `--seed`).
#[test]
fn every_request_key_is_an_option_and_config_keys_count_as_options() {
    let keys = serde_json::to_value(skyplan_plan::PlanRequest::default()).unwrap();
    for command in ["plan", "fly"] {
        let help = common::succeed(Path::new("."), &format!("{command} --help"));
        let help = String::from_utf8(help.stdout).unwrap();
        for key in keys.as_object().unwrap().keys() {
            let option = match key.as_str() {
                "geometry" => continue, // an API option: the CLI asks for it with --plot/--show
                "shortcut" => "--no-shortcut".to_string(),
                k => format!("--{}", k.replace('_', "-")),
            };
            let listed = (help.lines()).any(|l| l.split_whitespace().next() == Some(&option));
            assert!(listed, "{command} --help lacks {option}");
        }
    }
    let dir = dir_with(&[("seed.toml", "seed = 2\n")]);
    let blocked = |line: &str| run_json(dir.path(), line)["grid"]["blocked_cells"].clone();
    let from_config = blocked("--random 30x20 --density 0.1 --config seed.toml");
    assert_eq!(
        from_config,
        blocked("--random 30x20 --density 0.1 --seed 2")
    );
    assert_ne!(
        from_config,
        blocked("--random 30x20 --density 0.1"),
        "seed 1 draws another workspace"
    );
}

#[test]
fn bad_map_input_names_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "nohome.csv",
            "posX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n1,2,3,4,5,6\n",
            "nohome.csv: line 1",
        ),
        (
            "cols.csv",
            "lat0 37.79, lon0 -122.39\n1,2,3,4,5\n",
            "cols.csv: line 2, column 5",
        ),
        (
            "nan.csv",
            "lat0 37.79, lon0 -122.39\n1,2,3,4,5,6\n1,2,NaN,4,5,6\n",
            "nan.csv: line 3, column 3 (posZ)",
        ),
        (
            "neg.csv",
            "lat0 37.79, lon0 -122.39\n1,2,3,-4,5,6\n",
            "line 2, column 4 (halfSizeX)",
        ),
        ("empty.csv", "", "line 1"),
        (
            "nobox.csv",
            "lat0 37.79, lon0 -122.39\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n",
            "no obstacle boxes",
        ),
    ];
    for (name, text, needle) in cases {
        std::fs::write(dir.path().join(name), text).unwrap();
        let err = fails_with(dir.path(), &format!("plan --map {name}"), 2, &[needle]);
        assert!(!err.contains("panicked"), "{err}");
    }
    fails_with(dir.path(), "plan --map missing.csv", 2, &["missing.csv"]);
    assert_no_waypoints(dir.path(), "no output after bad input");
}

#[test]
fn bad_positions_say_which_where_and_the_nearest_free_cell() {
    let dir = tempfile::tempdir().unwrap();
    // (0, -310) lies inside the first building of the map plus its margin.
    let cases: [(&str, &[&str]); 6] = [
        (
            "--goal-ne -310.2,-439.2",
            &[
                "goal N -310.20 m, E -439.20 m",
                "inside an obstacle",
                "nearest free cell centre is N",
                "lat 37.",
            ],
        ),
        (
            "--start-ne 5000,0",
            &["start N 5000.00 m, E 0.00 m", "off the map"],
        ),
        ("--goal-lla 37.79,-110.0", &["UTM zone 12"]),
        ("--alt-m nan", &[]),
        ("--connectivity 6", &[]),
        ("--out w.xyz", &["extension"]),
    ];
    for (line, needles) in cases {
        fails_with(dir.path(), &format!("plan {line}"), 2, needles);
    }
}

#[test]
fn an_enclosed_goal_is_reported_unreachable_with_exit_3() {
    let dir = tempfile::tempdir().unwrap();
    // A courtyard: four walls around (0, 0); the start is outside.
    let map = "lat0 37.79, lon0 -122.39\n\
               10,0,5,1,11,5\n-10,0,5,1,11,5\n0,10,5,11,1,5\n0,-10,5,11,1,5\n40,40,1,1,1,1\n-40,-40,1,1,1,1\n";
    std::fs::write(dir.path().join("yard.csv"), map).unwrap();
    let out = cmd(
        dir.path(),
        "plan --json --map yard.csv --safety-m 1 --start-ne 30,30 --goal-ne 0,0",
    )
    .output()
    .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (&v["status"], &v["kind"]),
        (&"error".into(), &"no_path".into())
    );
    let msg = v["message"].as_str().unwrap();
    assert!(
        msg.contains("unreachable") && msg.contains("goal's") && msg.contains("cells"),
        "{msg}"
    );
    assert_no_waypoints(dir.path(), "no output without a path");
}

#[test]
fn unwritable_output_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    fails_with(
        dir.path(),
        "plan --out no/such/dir/w.json",
        2,
        &["no/such/dir/w.json"],
    );
}

#[test]
fn theta_star_is_shorter_than_the_octile_optimum_and_still_free() {
    let dir = tempfile::tempdir().unwrap();
    let v = run_json(dir.path(), "--planner theta");
    let (cost, octile, straight) = (
        v["cost_m"].as_f64().unwrap(),
        v["octile_optimum_m"].as_f64().unwrap(),
        v["straight_line_m"].as_f64().unwrap(),
    );
    assert!(
        straight <= cost && cost < octile,
        "{straight} ≤ {cost} < {octile}"
    );
    let grid = city_grid(GridSpec::default());
    assert_segments_free(&grid, &rows(&v), Touch::Closed);
}

/// `plan --save-preprocess` keeps the JPS+ table the plan built; `--preprocess` plans with it
/// (the same route, nothing built); a cut file, another planner and another grid are refused
/// before anything is written.
#[test]
fn a_saved_jps_plus_table_plans_the_same_route_without_building() {
    let dir = tempfile::tempdir().unwrap();
    let saved = run_json(
        dir.path(),
        "--planner jps-plus --save-preprocess city.jpsplus",
    );
    assert_eq!(saved["jps_plus_table"], "built");
    let bytes = std::fs::read(dir.path().join("city.jpsplus")).unwrap();
    assert!(bytes.len() > 921 * 921, "{} bytes", bytes.len());
    let loaded = run_json(dir.path(), "--planner jps-plus --preprocess city.jpsplus");
    assert_eq!(loaded["jps_plus_table"], "reused");
    assert_eq!(loaded["cost_m"], saved["cost_m"]);
    assert_eq!(loaded["waypoints"], saved["waypoints"]);
    let plain = run_json(dir.path(), "--planner jps");
    assert_eq!(
        loaded["cost_m"], plain["cost_m"],
        "JPS+ and JPS are both exact"
    );
    // `auto` loads it too (one query: its rule says JPS, the table at hand is faster), and its
    // landmarks (kept in saved tables) leave the cost optimal with fewer expansions than JPS.
    let auto = run_json(dir.path(), "--planner auto --preprocess city.jpsplus");
    assert_eq!(auto["auto"]["planner"], "jps-plus", "{}", auto["auto"]);
    assert_eq!(auto["jps_plus_table"], "reused");
    assert_eq!(auto["cost_m"], plain["cost_m"]);
    assert!(
        auto["expansions"].as_u64().unwrap() < plain["expansions"].as_u64().unwrap(),
        "landmarks: {} expansions, JPS {}",
        auto["expansions"],
        plain["expansions"]
    );
    std::fs::write(dir.path().join("noise.bin"), b"not a table at all").unwrap();
    fails_with(
        dir.path(),
        "plan --planner auto --preprocess noise.bin",
        2,
        &[
            "--preprocess noise.bin",
            "not a saved JPS+ table, contraction hierarchy",
        ],
    );

    std::fs::write(dir.path().join("cut.jpsplus"), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::remove_file(dir.path().join("waypoints.json")).ok();
    fails_with(
        dir.path(),
        "plan --planner jps-plus --preprocess cut.jpsplus",
        2,
        &["--preprocess cut.jpsplus", "truncated"],
    );
    fails_with(
        dir.path(),
        "plan --planner astar --preprocess city.jpsplus",
        2,
        &["--preprocess city.jpsplus", "only jps-plus", "ch"],
    );
    fails_with(
        dir.path(),
        "plan --planner jps-plus --alt-m 20 --preprocess city.jpsplus",
        2,
        &["--preprocess city.jpsplus", "another grid", "20 m altitude"],
    );
    assert_no_waypoints(dir.path(), "a refused --preprocess writes no waypoints");
    fails_with(
        dir.path(),
        "plan --planner jps-plus --save-preprocess -",
        2,
        &["--save-preprocess -", "file name"],
    );
}

/// The same for a contraction hierarchy, a subgoal graph and a first-move table on a MovingAI
/// map; one built for the octile grid is refused for the corner-cutting one.
#[test]
fn a_saved_hierarchy_subgoal_graph_or_first_move_table_plans_the_same_route_without_building() {
    let map = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/movingai/den312d.map"
    );
    let ends = "--start-ne 3.5,10.5 --goal-ne 70.5,40.5";
    let dir = tempfile::tempdir().unwrap();
    // An independent oracle: Dijkstra over the same grid.
    let dijkstra = run_json(
        dir.path(),
        &format!("--map {map} {ends} --planner dijkstra"),
    );
    let truth = dijkstra["cost_m"].as_f64().unwrap();
    for (planner, detail, file) in [
        ("ch", "contraction_hierarchy", "den.ch"),
        ("subgoal", "subgoal_graph", "den.sg"),
        ("first-move", "first_move_table", "den.fm"),
    ] {
        let saved = run_json(
            dir.path(),
            &format!("--map {map} {ends} --planner {planner} --save-preprocess {file}"),
        );
        assert_eq!(saved[detail], "built");
        let loaded = run_json(
            dir.path(),
            &format!("--map {map} {ends} --planner {planner} --preprocess {file}"),
        );
        assert_eq!(loaded[detail], "reused");
        assert_eq!(loaded["cost_m"], saved["cost_m"]);
        let cost = loaded["cost_m"].as_f64().unwrap();
        assert!(
            (cost - truth).abs() < 1e-9,
            "{planner} {cost} against dijkstra {truth}"
        );
        fails_with(
            dir.path(),
            &format!(
                "plan --map {map} {ends} --planner {planner} --corner-cutting --preprocess {file}"
            ),
            2,
            &[&format!("--preprocess {file}"), "corner cutting"],
        );
    }
}
