//! MovingAI replay against the published optimal lengths (`data/movingai`, MovingAI benchmarks by N. Sturtevant).
//! A fast subset here; `.ci/run` replays every scenario of every map with the release binary.

use serde_json::Value;
use std::path::PathBuf;
mod common;
use common::{ok, skyplan};

fn movingai_dir() -> Option<PathBuf> {
    Some(PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/movingai"
    )))
}

/// Writes the first `n` scenarios of a scenario file to a temporary file.
fn head(scen: &std::path::Path, n: usize, dir: &std::path::Path) -> PathBuf {
    let text = std::fs::read_to_string(scen).unwrap();
    let out = dir.join(scen.file_name().unwrap());
    std::fs::write(
        &out,
        text.lines()
            .take(n.saturating_add(1))
            .collect::<Vec<_>>()
            .join("\n"),
    )
    .unwrap();
    out
}

#[test]
fn scenarios_match_published_optimal_lengths() {
    let Some(data) = movingai_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    // The default planner is auto: what it picks for this many scenarios (the rule in
    // skyplan_plan::auto::pick: JPS below 150 queries, else JPS+ on these maps' mean runs).
    for (map, n, picked) in [
        ("den312d", usize::MAX, "jps-plus"),
        ("Paris_1_256", 300, "jps-plus"),
        ("Boston_0_512", 150, "jps-plus"),
        ("maze512-32-9", 60, "jps"),
        ("random512-40-5", 150, "jps-plus"),
    ] {
        let map_path = data.join(format!("{map}.map"));
        let scen = head(&data.join(format!("{map}.map.scen")), n, tmp.path());
        let out = ok(skyplan(tmp.path())
            .arg("scen")
            .arg(&map_path)
            .arg(&scen)
            .arg("--json"));
        let lines: Vec<Value> = String::from_utf8(out.stdout)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let (records, summary) = lines.split_at(lines.len() - 1);
        assert!(!records.is_empty());
        for r in records {
            assert_eq!(r["ok"], true, "{map}: {r}");
            let (cost, opt) = (
                r["cost"].as_f64().unwrap(),
                r["optimal_length"].as_f64().unwrap(),
            );
            assert!((cost - opt).abs() <= 1e-6 * opt.max(1.0), "{map}: {r}");
            assert!(r["bucket"].is_u64() && r["time_us"].is_f64());
        }
        assert_eq!(summary[0]["matched"].as_u64(), Some(records.len() as u64));
        assert_eq!(summary[0]["planner"], "auto", "{map}");
        assert_eq!(
            summary[0]["auto"]["planner"], picked,
            "{map}: {}",
            summary[0]
        );
        assert_eq!(
            summary[0]["auto"]["queries"].as_u64(),
            Some(records.len() as u64)
        );
    }
}

#[test]
fn the_table_says_what_auto_picked_and_why() {
    let Some(data) = movingai_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let out = ok(skyplan(tmp.path())
        .arg("scen")
        .arg(data.join("den312d.map"))
        .arg(data.join("den312d.map.scen")));
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert!(
        lines
            .next()
            .unwrap()
            .contains(", 290 scenarios, planner auto (JPS+ table ready in ")
    );
    assert_eq!(
        lines.next(),
        Some(
            "auto picked JPS+: open ground, rooms or wide corridors (mean free run 9.1 cells) and 290 queries ≥ 150: the JPS+ table pays for itself"
        )
    );
}

#[test]
fn a_wrong_optimal_length_is_caught() {
    let Some(data) = movingai_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let scen = tmp.path().join("bad.scen");
    // den312d's first scenario with its optimal length changed.
    let text = std::fs::read_to_string(data.join("den312d.map.scen")).unwrap();
    let mut lines: Vec<String> = text.lines().take(3).map(str::to_string).collect();
    let mut fields: Vec<String> = lines[1].split('\t').map(str::to_string).collect();
    fields[8] = "1.5".into();
    lines[1] = fields.join("\t");
    std::fs::write(&scen, lines.join("\n")).unwrap();
    skyplan(tmp.path())
        .arg("scen")
        .arg(data.join("den312d.map"))
        .arg(&scen)
        .assert()
        .code(1)
        .stderr(predicates::str::contains("1 of 2 scenarios do not match"));
}

/// `scen … --preprocess PATH` refused: exit 2, the file and `why` named, nothing on stdout.
fn refused(mut scen: assert_cmd::Command, path: &std::path::Path, why: &str) {
    let out = scen.output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("--preprocess {}: ", path.display())) && err.contains(why),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}

/// The summary line of `scen --json`'s output.
fn summary(out: &std::process::Output) -> Value {
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    serde_json::from_str(text.lines().last().unwrap()).unwrap()
}

#[test]
fn a_saved_hierarchy_is_reused_by_auto_and_damaged_or_foreign_files_are_refused() {
    let Some(data) = movingai_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    // 300 scenarios on the random map: auto picks the hierarchy (mean free run 2.7).
    let scen = head(&data.join("random512-40-5.map.scen"), 300, tmp.path());
    let map = data.join("random512-40-5.map");
    let file = tmp.path().join("random.ch");
    let run = |extra: &[&std::ffi::OsStr]| {
        let mut c = skyplan(tmp.path());
        c.arg("scen").arg(&map).arg(&scen).arg("--json").args(extra);
        c
    };
    let saved = summary(&ok(&mut run(&[
        "--save-preprocess".as_ref(),
        file.as_os_str(),
    ])));
    assert_eq!(saved["auto"]["planner"], "ch");
    assert_eq!(saved["matched"].as_u64(), Some(300));
    let loaded = summary(&ok(&mut run(&["--preprocess".as_ref(), file.as_os_str()])));
    assert_eq!(loaded["auto"]["planner"], "ch");
    assert_eq!(loaded["matched"].as_u64(), Some(300));
    assert!(
        loaded["auto"]["why"]
            .as_str()
            .unwrap()
            .ends_with("a contraction hierarchy at hand: the fastest queries, nothing to build")
    );
    // Damaged, cut short, another map: exit 2, the file and what is wrong named, no output.
    let bytes = std::fs::read(&file).unwrap();
    let mut damaged = bytes.clone();
    damaged[bytes.len() / 2] ^= 0x10;
    let cases: [(&str, Vec<u8>, &str); 2] = [
        (
            "damaged.ch",
            damaged,
            "contraction hierarchy is damaged (its checksum does not match its contents)",
        ),
        (
            "short.ch",
            bytes[..bytes.len() / 3].to_vec(),
            "(truncated or damaged)",
        ),
    ];
    for (name, content, why) in cases {
        let path = tmp.path().join(name);
        std::fs::write(&path, content).unwrap();
        refused(
            run(&["--preprocess".as_ref(), path.as_os_str()]),
            &path,
            why,
        );
    }
    let out = skyplan(tmp.path())
        .args(["scen", "--planner", "ch", "--preprocess"])
        .arg(&file)
        .arg(data.join("den312d.map"))
        .arg(data.join("den312d.map.scen"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("built for a 512 × 512 grid") && err.contains("this grid is 81 × 65"),
        "{err}"
    );
}

#[test]
fn a_saved_first_move_table_is_used_by_auto_and_refused_when_damaged_or_misused() {
    let Some(data) = movingai_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let map = data.join("den312d.map");
    let scen = data.join("den312d.map.scen");
    let file = tmp.path().join("den312d.fm");
    let run = |extra: &[&std::ffi::OsStr]| {
        let mut c = skyplan(tmp.path());
        c.arg("scen").arg(&map).arg(&scen).arg("--json").args(extra);
        c
    };
    // Built and saved by --planner first-move: every scenario matches its published length.
    let saved = summary(&ok(&mut run(&[
        "--planner".as_ref(),
        "first-move".as_ref(),
        "--save-preprocess".as_ref(),
        file.as_os_str(),
    ])));
    assert_eq!(saved["matched"].as_u64(), Some(290));
    // 290 queries do not pay for building a table, but auto uses one at hand.
    let plain = summary(&ok(&mut run(&[])));
    assert_eq!(plain["auto"]["planner"], "jps-plus");
    let loaded = summary(&ok(&mut run(&["--preprocess".as_ref(), file.as_os_str()])));
    assert_eq!(loaded["auto"]["planner"], "first-move");
    assert_eq!(loaded["matched"].as_u64(), Some(290));
    // Damaged, cut short, for another planner or map: exit 2, the file and what is wrong named.
    let bytes = std::fs::read(&file).unwrap();
    let mut damaged = bytes.clone();
    damaged[bytes.len() / 2] ^= 0x10;
    let cases: [(&str, Vec<u8>, &[&str], &str); 3] = [
        (
            "damaged.fm",
            damaged,
            &[],
            "first-move table is damaged (its checksum does not match its contents)",
        ),
        (
            "short.fm",
            bytes[..bytes.len() / 3].to_vec(),
            &[],
            "(truncated or damaged)",
        ),
        (
            "for-jps.fm",
            bytes.clone(),
            &["--planner", "jps"],
            "a saved first-move table is for --planner first-move or auto, not jps",
        ),
    ];
    for (name, content, args, why) in cases {
        let path = tmp.path().join(name);
        std::fs::write(&path, content).unwrap();
        let mut c = run(&["--preprocess".as_ref(), path.as_os_str()]);
        c.args(args);
        refused(c, &path, why);
    }
    let out = skyplan(tmp.path())
        .args(["scen", "--preprocess"])
        .arg(&file)
        .arg(data.join("random512-40-5.map"))
        .arg(data.join("random512-40-5.map.scen"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("first-move table was built for a 81 × 65 grid")
            && err.contains("this grid is 512 × 512"),
        "{err}"
    );
    // Too large a map for a table: refused at once, saying why.
    let out = skyplan(tmp.path())
        .args(["scen", "--planner", "first-move"])
        .arg(data.join("random512-40-5.map"))
        .arg(data.join("random512-40-5.map.scen"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("it is for small maps"), "{err}");
    // --max-table moves that cap: den312d's 6.4 MB table is refused under 1M and built under
    // 10M (every scenario matching); the option is for first-move only.
    let with_cap = |planner: &str, size: &str| {
        let args = ["--planner", planner, "--max-table", size];
        run(&args.map(std::ffi::OsStr::new)).output().unwrap()
    };
    let refused_with = |out: std::process::Output, needles: &[&str]| {
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(needles.iter().all(|n| err.contains(n)), "{err}");
    };
    refused_with(
        with_cap("first-move", "1M"),
        &[
            "--max-table: a first-move table",
            "takes 6.4 MB, more than the 1.0 MB allowed",
        ],
    );
    let built = with_cap("first-move", "10M");
    let err = String::from_utf8_lossy(&built.stderr);
    assert_eq!(built.status.code(), Some(0), "{err}");
    assert_eq!(summary(&built)["matched"].as_u64(), Some(290));
    refused_with(
        with_cap("jps", "10M"),
        &["it needs --planner first-move, not jps"],
    );
}

/// A JPS+ table saved by `scen` keeps landmarks; `auto` (whose rule picks JPS+ on Paris) uses
/// the loaded table from the first scenario, and every scenario still matches its published
/// length; a table given to another planner, or a file of no known kind, is refused.
#[test]
fn a_saved_jps_plus_table_with_landmarks_serves_auto() {
    let Some(data) = movingai_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let map = data.join("Paris_1_256.map");
    let scen = data.join("Paris_1_256.map.scen");
    let file = tmp.path().join("paris.jpsplus");
    let run = |extra: &[&std::ffi::OsStr]| {
        let mut c = skyplan(tmp.path());
        c.arg("scen").arg(&map).arg(&scen).arg("--json").args(extra);
        c
    };
    let saved = summary(&ok(&mut run(&[
        "--planner".as_ref(),
        "jps-plus".as_ref(),
        "--save-preprocess".as_ref(),
        file.as_os_str(),
    ])));
    assert_eq!(saved["matched"].as_u64(), Some(1090));
    // 88-byte header, 8 bytes per cell, 8 landmarks: 4 bytes per cell each, cells, checksum.
    let cells = 256 * 256;
    assert_eq!(
        std::fs::metadata(&file).unwrap().len(),
        88 + 8 * cells + 8 * 8 + 4 * 8 * cells + 8
    );
    let loaded = summary(&ok(&mut run(&["--preprocess".as_ref(), file.as_os_str()])));
    assert_eq!(loaded["auto"]["planner"], "jps-plus");
    assert!(
        loaded["auto"]["why"]
            .as_str()
            .unwrap()
            .starts_with("a JPS+ table at hand with landmarks"),
        "{}",
        loaded["auto"]
    );
    assert_eq!(loaded["matched"].as_u64(), Some(1090));
    refused(
        run(&[
            "--planner".as_ref(),
            "ch".as_ref(),
            "--preprocess".as_ref(),
            file.as_os_str(),
        ]),
        &file,
        "a saved JPS+ table is for --planner jps-plus or auto, not ch",
    );
    let noise = tmp.path().join("noise.bin");
    std::fs::write(&noise, b"SKYPLAN-NOTHING\nmore bytes").unwrap();
    refused(
        run(&["--preprocess".as_ref(), noise.as_os_str()]),
        &noise,
        "not a saved JPS+ table, contraction hierarchy, subgoal graph or first-move table",
    );
}
