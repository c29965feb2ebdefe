//! Bad input as a new user types it: outputs that are not ours survive, resources are bounded
//! before anything is allocated, nonsense is refused with the range, and a failing command
//! writes nothing. Each case checks the exit code and a key phrase of the message.

use assert_cmd::Command;
use std::path::Path;

mod common;

fn skyplan(dir: &Path, args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::cargo_bin("skyplan")
        .unwrap()
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_input_table() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.toml"), "alt_m = \"high\"\n").unwrap();
    let city = skyplan_plan::FCND_CITY_CSV
        .lines()
        .take(3)
        .collect::<Vec<_>>();
    std::fs::write(
        dir.path().join("far.csv"),
        format!("{}\n1e308,0,10,5,5,5\n", city.join("\n")),
    )
    .unwrap();
    // A scenario whose goal (2,0) is on the wall `@`.
    std::fs::write(
        dir.path().join("w.map"),
        "type octile\nheight 3\nwidth 4\nmap\n..@.\n....\n....\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("w.scen"),
        "version 1\n0\tw.map\t4\t3\t0\t0\t2\t0\t2.0\n",
    )
    .unwrap();
    let cases: &[(&[&str], i32, &str)] = &[
        (
            &["plan", "--alt-m", "-5"],
            2,
            "--alt-m -5: expected a number from 0 to 10000 m",
        ),
        (&["plan", "--alt-m", "1e9"], 2, "--alt-m 1000000000"),
        (&["plan", "--safety-m", "-1"], 2, "--safety-m -1"),
        (&["plan", "--cell-m", "0"], 2, "--cell-m 0"),
        (&["plan", "--cell-m", "1e6"], 2, "--cell-m 1000000"),
        (
            &[
                "plan",
                "--planner",
                "prm",
                "--time-limit-ms",
                "18446744073709551615",
            ],
            2,
            "--time-limit-ms 18446744073709551615: expected 1 to 600000",
        ),
        (
            &["plan", "--planner", "prm", "--max-alt-m=-10"],
            2,
            "--max-alt-m -10",
        ),
        (&["plan", "--goal-alt-m", "30"], 2, "need"),
        (
            &["plan", "--random", "100000x100000", "--max-memory", "1G"],
            2,
            "--max-memory",
        ),
        (
            &["plan", "--cell-m", "0.01", "--max-memory", "1G"],
            2,
            "use a larger --cell-m",
        ),
        (
            &["plan", "--resolution", "1"],
            2,
            "--resolution: only bare .png/.pgm maps take it",
        ),
        (&["plan", "--config", "bad.toml"], 2, "bad.toml"),
        (
            &["plan", "--plot", "nodir/p.png"],
            2,
            "the directory nodir does not exist",
        ),
        (&["plan", "--out", "w.xyz"], 2, "cannot tell the format"),
        (&["plan", "--planner", "rrt"], 2, "rrt-connect"),
        (
            &["bench", "--out", "r.txt"],
            2,
            "expected a .csv or .json file name",
        ),
        (&["bench", "--random", "0"], 2, "--random 0"),
        (&["plan", "--goal-ne", "5000,0"], 2, "off the map"),
        // An overflowing box position names the file, line and field (was "a
        // 18446744073709551615 × 921 grid has more than 400000000 cells").
        (
            &["plan", "--map", "far.csv"],
            2,
            "far.csv: line 4, column 1 (posX): expected metres within ±1000000",
        ),
        // Not "cost Some(7.41…)": the scenario's line and the blocked end.
        (
            &["scen", "w.map", "w.scen"],
            1,
            "line 2: no path: the start or goal is on a blocked cell",
        ),
        (
            &["plan", "--goal-lla", "95,0"],
            2,
            "goal: invalid position: latitude 95° must be within ±84°",
        ),
        (
            &["plan", "--random", "100000x100000", "--max-memory", "1G"],
            2,
            "a random 100000x100000 workspace needs about",
        ),
    ];
    for (args, code, phrase) in cases {
        let (got, _, err) = skyplan(dir.path(), args);
        assert_eq!(got, Some(*code), "{args:?}: {err}");
        assert!(err.contains(phrase), "{args:?}: {err:?} lacks {phrase:?}");
        for debug in ["Some(", "None", "panicked", "Error {"] {
            assert!(!err.contains(debug), "{args:?}: {err}");
        }
        // No repeated text ("invalid position …: invalid position …").
        let first_line = err.lines().next().unwrap_or("");
        for part in first_line.split(": ").filter(|p| p.len() > 12) {
            assert_eq!(
                first_line.matches(part).count(),
                1,
                "{args:?} repeats {part:?}: {err}"
            );
        }
        if phrase.contains("random 100000x100000") {
            assert!(!err.contains("cell size"), "{args:?}: {err}");
        }
        // A failing command writes nothing.
        assert!(
            !dir.path().join("waypoints.json").exists(),
            "{args:?} wrote waypoints.json"
        );
    }
}

#[test]
fn a_huge_image_is_refused_from_its_header_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    // A PNG header claiming 20000 × 20000 pixels: refused from the header alone.
    let mut png = b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR".to_vec();
    png.extend_from_slice(&20_000u32.to_be_bytes());
    png.extend_from_slice(&20_000u32.to_be_bytes());
    png.extend_from_slice(&[8, 0, 0, 0, 0, 0, 0, 0, 0]);
    std::fs::write(dir.path().join("huge.png"), &png).unwrap();
    let t = std::time::Instant::now();
    let (code, _, err) = skyplan(
        dir.path(),
        &[
            "plan",
            "--map",
            "huge.png",
            "--resolution",
            "1",
            "--max-memory",
            "1G",
        ],
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("20000 × 20000") && err.contains("--max-memory"),
        "{err}"
    );
    assert!(t.elapsed().as_secs() < 30, "refusal took {:?}", t.elapsed());
}

#[cfg(unix)]
#[test]
fn outputs_that_are_not_regular_files_survive() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo.json");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let (code, _, err) = skyplan(dir.path(), &["plan", "--out", "fifo.json"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("not a regular file"), "{err}");
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    // Every command's outputs, refused before any work (a FIFO would block a write; a rename
    // over it would replace it): fleet's report and picture, bench's records, fly's log,
    // scen's saved hierarchy.
    for name in ["fifo.png", "fifo.csv", "fifo.ch"] {
        let made = std::process::Command::new("mkfifo")
            .arg(dir.path().join(name))
            .status()
            .unwrap();
        assert!(made.success());
    }
    std::fs::write(
        dir.path().join("m.map"),
        "type octile\nheight 2\nwidth 3\nmap\n...\n...\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("m.map.scen"),
        "version 1\n0\tm.map\t3\t2\t0\t0\t2\t1\t2.41421356\n",
    )
    .unwrap();
    for args in [
        &["fleet", "--random", "2", "--json", "fifo.json"][..],
        &["fleet", "--random", "2", "--plot", "fifo.png"],
        &[
            "bench",
            "--random",
            "1",
            "--planners",
            "jps",
            "--out",
            "fifo.json",
        ],
        &["fly", "--sim", "--log", "fifo.csv"],
        &[
            "scen",
            "m.map",
            "m.map.scen",
            "--planner",
            "ch",
            "--save-preprocess",
            "fifo.ch",
        ],
    ] {
        let t = std::time::Instant::now();
        let (code, _, err) = skyplan(dir.path(), args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.contains("not a regular file"), "{args:?}: {err}");
        assert!(t.elapsed().as_secs() < 20, "{args:?} ran before refusing");
    }
    for name in ["fifo.json", "fifo.png", "fifo.csv", "fifo.ch"] {
        let kind = std::fs::metadata(dir.path().join(name))
            .unwrap()
            .file_type();
        assert!(kind.is_fifo(), "{name}");
    }
    if Path::new("/dev/full").exists() {
        let (code, _, err) = skyplan(
            dir.path(),
            &["plan", "--out", "/dev/full", "--format", "hdf5"],
        );
        assert_eq!(code, Some(2), "{err}");
        assert!(
            std::fs::metadata("/dev/full")
                .unwrap()
                .file_type()
                .is_char_device()
        );
    }
    std::fs::create_dir(dir.path().join("sub.json")).unwrap();
    let (code, _, err) = skyplan(dir.path(), &["plan", "--out", "sub.json"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("a directory"), "{err}");
    // A symlink is followed: the link stays, its target gets the waypoints.
    std::fs::write(dir.path().join("target.json"), "old").unwrap();
    std::os::unix::fs::symlink("target.json", dir.path().join("link.json")).unwrap();
    let (code, _, err) = skyplan(dir.path(), &["plan", "--out", "link.json"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        std::fs::symlink_metadata(dir.path().join("link.json"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let text = std::fs::read_to_string(dir.path().join("target.json")).unwrap();
    assert!(
        text.contains("\"waypoints\"") || text.starts_with('{') || text.starts_with('['),
        "{text}"
    );
    // `-` is standard output (the data alone: tests/stdout_data_cli.rs).
    let (code, out, err) = skyplan(dir.path(), &["plan", "--out", "-", "--format", "csv"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.lines().count() > 3, "{out}");
}

#[test]
fn a_refused_connection_is_said_once() {
    // A port nobody listens on.
    let port = common::free_tcp_port();
    let dir = tempfile::tempdir().unwrap();
    let address = format!("tcp:127.0.0.1:{port}");
    let (code, _, err) = skyplan(dir.path(), &["fly", "--connect", &address]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains(&format!("cannot open tcpout:127.0.0.1:{port}")),
        "{err}"
    );
    assert_eq!(err.matches("Connection refused").count(), 1, "{err}");
}

/// `skyplan … | head -1`: the reader is gone before skyplan writes. Every command that prints
/// ends quietly with 141 (128 + SIGPIPE, as `cat` does), never a panic.
#[cfg(unix)]
#[test]
fn a_closed_stdout_ends_quietly() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let cases: &[&[&str]] = &[
        &["plan", "--random", "30x20", "--seed", "2", "--show"],
        &["plan", "--random", "30x20", "--seed", "2", "--json"],
        &[
            "plan",
            "--random",
            "30x20",
            "--seed",
            "2",
            "--home",
            "37.79,-122.39",
            "--out",
            "-",
            "--format",
            "csv",
        ],
        &["plan", "--random", "30x20", "--seed", "2"],
    ];
    for args in cases {
        // A pipe whose read end is closed before skyplan starts: every write meets EPIPE.
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let out = Command::new(env!("CARGO_BIN_EXE_skyplan"))
            .current_dir(dir.path())
            .args(*args)
            .stdout(writer)
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(141), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
}
