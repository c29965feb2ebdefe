//! What a newcomer types wrong gets a hint with the fix; redirected output carries no control
//! characters and no float noise.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

/// Runs the real binary in `dir` with `args`.
fn skyplan(dir: &Path, args: &[&str]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_skyplan"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8(out.stderr.clone()).unwrap()
}

fn movingai(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/movingai")
        .join(name)
}

#[test]
fn a_position_typed_with_a_space_gets_the_comma_hint() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["plan", "--goal-ne", "420", "390"], "--goal-ne 420,390"),
        (
            &["plan", "--start-ne", "-100", "-50"],
            "--start-ne -100,-50",
        ),
        (
            &["fly", "--start-lla", "37.79", "-122.39"],
            "--start-lla 37.79,-122.39",
        ),
    ];
    for (args, fix) in cases {
        let out = skyplan(dir.path(), args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("unexpected argument"), "{args:?}: {err}");
        assert!(
            err.lines()
                .any(|l| l.starts_with("hint: ") && l.ends_with(fix)),
            "{args:?}: no hint ending in {fix:?}:\n{err}"
        );
    }
    // An option that takes one number gets clap's error alone: no comma to suggest.
    let out = skyplan(dir.path(), &["plan", "--alt-m", "5", "6"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!stderr(&out).contains("hint:"), "{}", stderr(&out));
}

#[test]
fn flying_to_a_closed_port_says_to_start_the_simulator() {
    let dir = tempfile::tempdir().unwrap();
    // A port that was free a moment ago: nobody listens on it.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let address = format!("tcp:127.0.0.1:{port}");
    let out = skyplan(dir.path(), &["fly", "--connect", &address]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("Connection refused"), "{err}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("hint: ") && l.contains("skyplan sim --listen")),
        "{err}"
    );
}

#[test]
fn scen_json_has_no_float_noise_and_matches_the_published_lengths() {
    let dir = tempfile::tempdir().unwrap();
    let (map, scen) = (movingai("den312d.map"), movingai("den312d.map.scen"));
    let out = skyplan(
        dir.path(),
        &[
            "scen",
            map.to_str().unwrap(),
            scen.to_str().unwrap(),
            "--json",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // The scenario file's own count, read independently: its lines after the version line.
    let published = std::fs::read_to_string(&scen).unwrap();
    let scenarios: Vec<&str> = published
        .lines()
        .skip(1)
        .filter(|l| !l.is_empty())
        .collect();
    assert_eq!(
        lines.len(),
        scenarios.len() + 1,
        "one line per scenario, one summary"
    );
    let decimals = |v: &Value| {
        let text = v.to_string();
        text.split_once('.')
            .map_or(0, |(_, fraction)| fraction.len())
    };
    for (line, row) in lines.iter().zip(&scenarios) {
        let optimal: f64 = row.split_whitespace().nth(8).unwrap().parse().unwrap();
        let cost = line["cost"].as_f64().unwrap();
        assert!((cost - optimal).abs() < 1e-6, "{line} against {row}");
        assert!(decimals(&line["time_us"]) <= 3, "{line}");
        assert!(decimals(&line["cost"]) <= 9, "{line}");
    }
    let summary = lines.last().unwrap();
    assert_eq!(summary["matched"], scenarios.len());
    for (key, value) in summary.as_object().unwrap() {
        if key.ends_with("_us") || key.ends_with("_ms") {
            assert!(decimals(value) <= 3, "{key}: {value}");
        }
    }
}

#[test]
fn bench_replan_redirected_has_no_carriage_returns() {
    let dir = tempfile::tempdir().unwrap();
    let out = skyplan(
        dir.path(),
        &[
            "bench",
            "--replan",
            "1",
            "--hidden-random",
            "2",
            "--seed",
            "1",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let table = String::from_utf8(out.stdout.clone()).unwrap();
    assert!(
        table.lines().any(|l| l.starts_with("dstar-lite")),
        "{table}"
    );
    for stream in [&out.stdout, &out.stderr] {
        assert!(
            !stream.iter().any(|b| b.is_ascii_control() && *b != b'\n'),
            "a control character in redirected output: {:?}",
            String::from_utf8_lossy(stream)
        );
    }
}
