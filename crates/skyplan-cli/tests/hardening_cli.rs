//! Bad input as a new user types it: outputs that are not ours survive, resources are bounded
//! before anything is allocated, nonsense is refused with the range, and a failing command
//! writes nothing. Each case checks the exit code and a key phrase of the message.

use assert_cmd::Command;
use std::path::Path;

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
    let cases: &[(&[&str], i32, &str)] = &[
        (
            &["plan", "--alt-m", "-5"],
            2,
            "alt_m -5: expected a number from 0 to 10000 m",
        ),
        (&["plan", "--alt-m", "1e9"], 2, "alt_m 1000000000"),
        (&["plan", "--safety-m", "-1"], 2, "safety_m -1"),
        (&["plan", "--cell-m", "0"], 2, "cell_m 0"),
        (&["plan", "--cell-m", "1e6"], 2, "cell_m 1000000"),
        (
            &[
                "plan",
                "--planner",
                "prm",
                "--time-limit-ms",
                "18446744073709551615",
            ],
            2,
            "time_limit_ms 18446744073709551615: expected 1 to 600000",
        ),
        (
            &["plan", "--planner", "prm", "--max-alt-m=-10"],
            2,
            "max_alt_m -10",
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
            "use a larger cell_m",
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
    ];
    for (args, code, phrase) in cases {
        let (got, _, err) = skyplan(dir.path(), args);
        assert_eq!(got, Some(*code), "{args:?}: {err}");
        assert!(err.contains(phrase), "{args:?}: {err:?} lacks {phrase:?}");
        for debug in ["Some(", "None", "panicked", "Error {"] {
            assert!(!err.contains(debug), "{args:?}: {err}");
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
    // `-` is standard output.
    let (code, out, err) = skyplan(
        dir.path(),
        &["plan", "--out", "-", "--format", "csv", "--json"],
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(out.lines().count() > 3, "{out}");
}
