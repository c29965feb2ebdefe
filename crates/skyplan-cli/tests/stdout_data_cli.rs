//! stdout is data when data goes there: with `plan --out -` (any format) or `plan --json`,
//! standard output is that one document, parsed whole here with a real parser; the human lines
//! (`map …`, `wrote …`, `time …`) are on standard error. `--json` writes no waypoint file unless
//! `--out` names one.

use serde_json::Value;
use std::path::Path;
use std::process::Output;

/// Runs the real binary in `dir` with `args`.
fn skyplan(dir: &Path, args: &[&str]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_skyplan"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8(bytes.to_vec()).unwrap()
}

/// The human summary is on stderr, whole: where the plan came from, what was written, the time.
fn assert_human_lines_on_stderr(err: &str, wrote: &str) {
    for head in ["map ", "grid ", "path ", "waypoints ", "time "] {
        assert!(
            err.lines().any(|l| l.starts_with(head)),
            "stderr lacks the `{head}` line:\n{err}"
        );
    }
    assert!(
        err.lines()
            .any(|l| l.starts_with("wrote ") && l.contains(wrote)),
        "stderr lacks `wrote … {wrote}`:\n{err}"
    );
}

/// Every file in `dir`, sorted.
fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The JSON waypoint file's rows as numbers.
fn json_rows(v: &Value) -> Vec<Vec<f64>> {
    v["waypoints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

#[test]
fn out_dash_csv_prints_only_the_csv_document() {
    let dir = tempfile::tempdir().unwrap();
    let out = skyplan(dir.path(), &["plan", "--out", "-", "--format", "csv"]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    // Every record of stdout parses with the header's six columns; no line is left over.
    let mut reader = csv::Reader::from_reader(stdout.as_bytes());
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        header,
        [
            "north_m",
            "east_m",
            "alt_m",
            "heading_rad",
            "lat_deg",
            "lon_deg"
        ]
    );
    let rows: Vec<Vec<f64>> = reader
        .records()
        .map(|r| {
            let r = r.unwrap_or_else(|e| panic!("stdout is not pure CSV ({e}):\n{stdout}"));
            r.iter()
                .map(|x| {
                    x.parse::<f64>()
                        .unwrap_or_else(|_| panic!("not a number: {x:?}"))
                })
                .collect()
        })
        .collect();
    assert_eq!(stdout.lines().count(), rows.len() + 1, "{stdout}");
    // The default route: from the home to N 420, E 390 at 5 m.
    let (first, last) = (&rows[0], &rows[rows.len() - 1]);
    assert_eq!((first[0], first[1]), (0.0, 0.0));
    assert_eq!((last[0], last[1]), (420.0, 390.0));
    assert!(rows.iter().all(|r| r[2] == 5.0), "{stdout}");
    // The human lines say how many waypoints went out, and to where.
    assert_human_lines_on_stderr(&stderr, "standard output (csv)");
    assert!(
        stderr.contains(&format!("mission of {} waypoints", rows.len())),
        "{stderr}"
    );
    assert!(
        files_in(dir.path()).is_empty(),
        "{:?}",
        files_in(dir.path())
    );
}

#[test]
fn out_dash_json_prints_only_the_json_document_and_it_matches_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = skyplan(dir.path(), &["plan", "--out", "-", "--format", "json"]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    // The whole of stdout is one JSON value (serde_json refuses trailing text).
    let doc: Value = serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("stdout is not one JSON document ({e}):\n{stdout}"));
    assert_eq!(doc["format"], "skyplan-waypoints");
    assert_human_lines_on_stderr(&stderr, "standard output (json)");
    // The same plan written to a file: the same waypoints, to the bit.
    let file = skyplan(dir.path(), &["plan", "--out", "w.json"]);
    assert_eq!(file.status.code(), Some(0), "{}", text(&file.stderr));
    assert!(text(&file.stdout).contains("wrote      w.json (json)"));
    let from_file: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("w.json")).unwrap()).unwrap();
    assert_eq!(json_rows(&doc), json_rows(&from_file));
    assert!(json_rows(&doc).len() >= 2);
}

#[test]
fn json_summary_is_all_of_stdout_and_writes_no_file_unless_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = skyplan(dir.path(), &["plan", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["status"], "ok");
    assert_eq!(v["outputs"]["waypoints"], Value::Null);
    assert!(
        files_in(dir.path()).is_empty(),
        "--json alone wrote {:?}",
        files_in(dir.path())
    );
    // With --out a file, the file is written and the summary names it.
    let out = skyplan(dir.path(), &["plan", "--json", "--out", "route.csv"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["outputs"]["waypoints"], "route.csv");
    assert_eq!(files_in(dir.path()), ["route.csv"]);
    let rows = csv::Reader::from_path(dir.path().join("route.csv"))
        .unwrap()
        .records()
        .count();
    assert_eq!(
        Some(rows as u64),
        v["waypoint_counts"]["mission"].as_u64(),
        "{v}"
    );
}

#[test]
fn json_with_show_keeps_the_picture_off_stdout() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "plan",
        "--random",
        "12x8",
        "--density",
        "0.25",
        "--seed",
        "3",
    ];
    let out = skyplan(dir.path(), &[&args[..], &["--show", "--json"]].concat());
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["status"], "ok");
    // Without --json the same picture is on stdout: the one on stderr is that picture.
    let plain = skyplan(dir.path(), &[&args[..], &["--show"]].concat());
    let picture = text(&plain.stdout);
    let first_row = picture.lines().next().unwrap();
    assert!(
        text(&out.stderr).contains(first_row),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn two_documents_for_stdout_are_refused_before_planning() {
    let dir = tempfile::tempdir().unwrap();
    let out = skyplan(
        dir.path(),
        &["plan", "--out", "-", "--format", "csv", "--json"],
    );
    assert_eq!(out.status.code(), Some(2));
    // The refusal is a JSON object, as every --json failure is, and names both options.
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (&v["status"], &v["kind"]),
        (&"error".into(), &"bad_request".into())
    );
    let why = v["message"].as_str().unwrap();
    assert!(why.contains("--out -") && why.contains("--json"), "{why}");
    assert!(files_in(dir.path()).is_empty());
}
