//! `skyplan fly --fence`: the no-fly zones uploaded as the vehicle's fence (`mission_type`
//! FENCE) and read back before arming — to the built-in simulator (GUIDED and `--upload`), and
//! to an independent vehicle written with pymavlink, whose decoded items are compared with the
//! GeoJSON file itself; a vehicle that refuses the fence is never armed.

use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::Stdio;
mod common;
use common::{Run, fails_with, free_udp_port, python, run_args, words};

fn sample() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/no-fly-sample.geojson")
}

fn run(dir: &Path, line: &str) -> Run {
    run_args(dir, &words(line))
}

/// The line of stdout starting with `prefix`, and its index.
fn line_at(stdout: &str, prefix: &str) -> (usize, String) {
    stdout
        .lines()
        .enumerate()
        .find(|(_, l)| l.starts_with(prefix))
        .map(|(i, l)| (i, l.to_string()))
        .unwrap_or_else(|| panic!("no line {prefix:?} in:\n{stdout}"))
}

#[test]
fn fly_sim_uploads_the_zones_as_the_fence_before_arming() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &format!(
            "fly --sim --speedup 50 --timeout-s 90 --fence --no-fly {}",
            sample().display()
        ),
    );
    r.expect_code(0);
    let out = &r.stdout;
    // The sample: a 30 m circle and a square (timed), both at 0–120 m, are uploaded; the
    // approach path at 60–120 m is above the 5 m route: left out, and said so.
    for needle in [
        "fence      zone 0: exclusion circle, radius 30 m; lost: its band 0–120 m",
        "fence      zone 1: exclusion polygon of 4 vertices; lost: its band 0–120 m (the fence keeps the vehicle out at every altitude); its time window",
        "fence      zone 2 (exclusion, band 60–120 m): left out",
        "fence      2 shapes as 5 items (mission_type FENCE, MAV_FRAME_GLOBAL_INT), as the file gives them: the autopilot applies its own FENCE_MARGIN",
        "sim        fence of 5 items received and stored (not enabled)",
        "result     landed and disarmed after reaching all",
    ] {
        assert!(out.contains(needle), "{needle:?} not in:\n{out}");
    }
    let (read_back, _) = line_at(out, "fence      accepted and read back: 5 items match");
    let (arming, _) = line_at(out, "state          ");
    assert!(read_back < arming, "the fence after arming:\n{out}");
}

#[test]
fn fly_sim_upload_sends_the_fence_before_the_mission() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &format!(
            "fly --sim --upload --speedup 50 --timeout-s 90 --fence --no-fly {}",
            sample().display()
        ),
    );
    r.expect_code(0);
    let (fence, _) = line_at(&r.stdout, "fence      accepted and read back: 5 items");
    let (mission, _) = line_at(&r.stdout, "upload     accepted:");
    assert!(fence < mission, "{}", r.stdout);
    assert!(
        r.stdout
            .contains("result     landed and disarmed after reaching all")
    );
}

#[test]
fn fence_without_zones_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    fails_with(
        dir.path(),
        "fly --sim --fence",
        2,
        &["--fence uploads the no-fly zones as the vehicle's fence: give them with --no-fly FILE"],
    );
}

#[test]
fn a_zone_hole_the_route_flies_in_is_refused_before_arming() {
    // A square ring about the home: the route from the home to 30 m north stays in its hole,
    // which a fence cannot carry (its outer ring would forbid the route).
    let ring = |h: f64| {
        let (lat, lon) = (37.792480, -122.397450);
        format!(
            "[[{a},{b}],[{c},{b}],[{c},{d}],[{a},{d}],[{a},{b}]]",
            a = lon - h,
            b = lat - h,
            c = lon + h,
            d = lat + h
        )
    };
    let zones = format!(
        r#"{{"type": "FeatureCollection", "features": [{{"type": "Feature", "properties": {{"floor_m": 0, "ceiling_m": 100}}, "geometry": {{"type": "Polygon", "coordinates": [{}, {}]}}}}]}}"#,
        ring(0.002),
        ring(0.001)
    );
    let dir = common::dir_with(&[("holes.geojson", &zones)]);
    let r = run(
        dir.path(),
        "fly --sim --speedup 50 --timeout-s 60 --goal-ne 30,0 --fence --no-fly holes.geojson",
    );
    r.expect_code(2);
    assert!(
        r.stderr.contains("zone 0 is an exclusion polygon with holes, which a fence cannot carry, and the route flies through its hole 1"),
        "{}",
        r.stderr
    );
    assert!(!r.stdout.contains("ARMING"), "{}", r.stdout);
}

/// `fly --fence` (plus `extra`) against the pymavlink vehicle in `mode` (accept or refuse):
/// skyplan's run and the peer's lines.
fn fly_to_pymavlink(mode: &str, extra: &str) -> (Run, Vec<String>, bool) {
    let port = free_udp_port();
    let dir = tempfile::tempdir().unwrap();
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fly/pymavlink_fence_vehicle.py"
    );
    let mut peer = std::process::Command::new(python())
        .args([script, &port.to_string(), "37.792480", "-122.397450", mode])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(peer.stdout.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    assert!(first.starts_with("listening"), "{first}");
    let reader = std::thread::spawn(move || lines.map_while(|l| l.ok()).collect::<Vec<_>>());
    let r = run(
        dir.path(),
        &format!(
            "fly --connect udpout:127.0.0.1:{port} --wait-s 20 --fence --no-fly {}{extra}",
            sample().display()
        ),
    );
    let ok = peer.wait().unwrap().success();
    (r, reader.join().unwrap(), ok)
}

/// The GeoJSON zones the route flies in the band of (the stadium circle and the helipad
/// square), straight from the file: `(command, param1, lat × 10⁷, lon × 10⁷)` per fence item.
fn expected_items() -> Vec<(u64, f64, i64, i64)> {
    let v: Value = serde_json::from_str(&std::fs::read_to_string(sample()).unwrap()).unwrap();
    let f = &v["features"];
    let e7 = |x: &Value| (x.as_f64().unwrap() * 1e7).round() as i64;
    let c = &f[0]["geometry"]["coordinates"];
    let mut want = vec![(
        5004,
        f[0]["properties"]["radius_m"].as_f64().unwrap(),
        e7(&c[1]),
        e7(&c[0]),
    )];
    let ring = f[1]["geometry"]["coordinates"][0].as_array().unwrap();
    let open = &ring[..ring.len() - 1]; // GeoJSON repeats the first position
    for p in open {
        want.push((5002, open.len() as f64, e7(&p[1]), e7(&p[0])));
    }
    want
}

#[test]
#[ignore = "needs Python with pymavlink (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn a_pymavlink_vehicle_receives_the_geojson_zones_as_its_fence() {
    let (r, peer, peer_ok) = fly_to_pymavlink("accept", " --upload-only");
    let peer_out = peer.join("\n");
    assert!(
        r.code == Some(0) && peer_ok,
        "skyplan:\n{}\n{}\npymavlink vehicle:\n{peer_out}",
        r.stdout,
        r.stderr
    );
    // What pymavlink decoded: every item of type FENCE in MAV_FRAME_GLOBAL_INT, in order.
    let items: Vec<Value> = peer
        .iter()
        .filter_map(|l| l.strip_prefix("item "))
        .map(|j| serde_json::from_str(j).unwrap())
        .collect();
    let decoded: Vec<(u64, f64, i64, i64)> = items
        .iter()
        .map(|i| {
            assert_eq!(i["mission_type"], 1, "{i}");
            assert_eq!(i["frame"], 5, "{i}"); // MAV_FRAME_GLOBAL_INT
            (
                i["command"].as_u64().unwrap(),
                i["param1"].as_f64().unwrap(),
                i["x"].as_i64().unwrap(),
                i["y"].as_i64().unwrap(),
            )
        })
        .collect();
    let want = expected_items();
    assert_eq!(decoded[0], want[0], "the circle");
    // The polygon's vertices: those of the file (in the file's order or reversed, from any one).
    let mut got_vertices = decoded[1..].to_vec();
    let mut want_vertices = want[1..].to_vec();
    got_vertices.sort_by_key(|v| (v.2, v.3));
    want_vertices.sort_by_key(|v| (v.2, v.3));
    assert_eq!(got_vertices, want_vertices, "the polygon");
    assert_eq!(decoded.len(), 5);
    for needle in ["read-back requested", "read-back acknowledged: True", "OK"] {
        assert!(peer.iter().any(|l| l == needle), "{needle:?}:\n{peer_out}");
    }
    assert!(
        r.stdout
            .contains("fence      accepted and read back: 5 items match"),
        "{}",
        r.stdout
    );
}

#[test]
#[ignore = "needs Python with pymavlink (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn a_vehicle_that_refuses_the_fence_is_never_armed() {
    let (r, peer, peer_ok) = fly_to_pymavlink("refuse", "");
    let peer_out = peer.join("\n");
    r.expect_code(1);
    assert!(
        r.stderr.contains(
            "fence upload: the vehicle rejected the fence: UNSUPPORTED; the flight stops before arming"
        ),
        "{}",
        r.stderr
    );
    assert!(!r.stdout.contains("ARMING"), "{}", r.stdout);
    assert!(peer_ok, "pymavlink vehicle:\n{peer_out}");
    assert!(
        peer.iter().any(|l| l == "no arming after the refusal"),
        "{peer_out}"
    );
}
