//! OMPL in C++ as the 3D peer (`skyplan bench --3d --peers`): `bench/peers3d.cpp`, compiled in as
//! text, built once per machine with the system's C++ compiler against Debian's `libompl-dev`
//! (found with `pkg-config ompl`), then run on the same grown boxes and queries. Building and
//! running it is this module's I/O, by design; a machine without OMPL gets a note, not an error.

use crate::python_peers::PeerRuns3;
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The peer's source (`bench/peers3d.cpp`).
pub const PEERS3D_CPP: &str = include_str!("../../../bench/peers3d.cpp");

/// The problem file the peer reads: counts, bounds, the boxes, the queries (see the source).
pub fn problem_text(world: &BoxWorld3, qs: &[(Neu, Neu)]) -> String {
    let b = world.bounds();
    let boxes = world.inflated_boxes();
    let mut s = format!("{} {}\n", boxes.len(), qs.len());
    let row = |s: &mut String, a: Neu, c: Neu| {
        let _ = writeln!(s, "{} {} {} {} {} {}", a[0], a[1], a[2], c[0], c[1], c[2]);
    };
    row(&mut s, b.min, b.max);
    for x in boxes {
        row(&mut s, x.min, x.max);
    }
    for &(a, c) in qs {
        row(&mut s, a, c);
    }
    s
}

/// FNV-1a of the source: the cached binary's name changes when the source does.
fn fingerprint(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The built peer: `$TMPDIR/skyplan-ompl-cpp-<fingerprint>/peers3d`, compiled when missing.
pub fn build() -> Result<PathBuf, String> {
    let dir = std::env::temp_dir().join(format!(
        "skyplan-ompl-cpp-{:016x}",
        fingerprint(PEERS3D_CPP)
    ));
    let bin = dir.join("peers3d");
    if bin.is_file() {
        return Ok(bin);
    }
    let flags = Command::new("pkg-config")
        .args(["--cflags", "ompl"])
        .output()
        .map_err(|e| {
            format!(
                "OMPL C++ skipped: cannot run pkg-config ({e}); install libompl-dev and pkg-config"
            )
        })?;
    if !flags.status.success() {
        return Err(
            "OMPL C++ skipped: pkg-config does not know ompl; install libompl-dev (Debian: apt-get install libompl-dev)".into(),
        );
    }
    // Only the include folders: the package's own -std=c++14 is too old for the source.
    let includes: Vec<String> = String::from_utf8_lossy(&flags.stdout)
        .split_whitespace()
        .filter(|f| f.starts_with("-I"))
        .map(String::from)
        .collect();
    std::fs::create_dir_all(&dir)
        .map_err(|e| format!("OMPL C++ skipped: cannot create {}: {e}", dir.display()))?;
    let src = dir.join("peers3d.cpp");
    std::fs::write(&src, PEERS3D_CPP)
        .map_err(|e| format!("OMPL C++ skipped: cannot write {}: {e}", src.display()))?;
    let cxx = std::env::var("CXX").unwrap_or_else(|_| "c++".into());
    // Built under another name and renamed, so a half-built binary is never run.
    let partial = dir.join(format!("peers3d.{}.partial", std::process::id()));
    let out = Command::new(&cxx)
        .args(["-O2", "-std=c++17"])
        .args(&includes)
        .arg(&src)
        .arg("-o")
        .arg(&partial)
        .arg("-lompl")
        .output()
        .map_err(|e| format!("OMPL C++ skipped: cannot run the C++ compiler {cxx}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "OMPL C++ skipped: {cxx} failed on {}: {}",
            src.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    std::fs::rename(&partial, &bin)
        .map_err(|e| format!("OMPL C++ skipped: cannot place {}: {e}", bin.display()))?;
    Ok(bin)
}

/// Runs the built peer on a problem file: its stdout.
fn run(bin: &Path, problem: &str, budget_s: f64) -> Result<String, String> {
    let dir = std::env::temp_dir().join(format!("skyplan-ompl-cpp-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir)
        .map_err(|e| format!("OMPL C++ skipped: cannot create {}: {e}", dir.display()))?;
    let file = dir.join("problem.txt");
    let output = std::fs::write(&file, problem)
        .map_err(|e| format!("OMPL C++ skipped: {e}"))
        .and_then(|()| {
            Command::new(bin)
                .arg(&file)
                .arg(budget_s.to_string())
                .output()
                .map_err(|e| format!("OMPL C++ skipped: cannot run {}: {e}", bin.display()))
        });
    let _ = std::fs::remove_dir_all(&dir);
    let o = output?;
    if o.status.success() {
        Ok(String::from_utf8_lossy(&o.stdout).into_owned())
    } else {
        Err(format!(
            "OMPL C++ failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        ))
    }
}

/// OMPL's RRTConnect, PRM and RRT\* in C++ on the world's grown boxes and the queries, each
/// within `budget_s` seconds: their runs (`ompl-cpp-…`), and the raw lines (with each solved
/// path's points) for a re-check.
pub fn ompl_cpp_peers(
    world: &BoxWorld3,
    qs: &[(Neu, Neu)],
    budget_s: f64,
) -> Result<(PeerRuns3, String), String> {
    let bin = build()?;
    let stdout = run(&bin, &problem_text(world, qs), budget_s)?;
    Ok((crate::three_d::parse_peer_lines(&stdout), stdout))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// OMPL C++ on the city: every path it calls solved starts and ends at its query and is free
    /// by skyplan's own exact segment test (an independent re-check of the peer's), and the peer's
    /// `recheck_ok` agrees; RRTConnect solves every query.
    #[test]
    #[ignore = "needs libompl-dev, pkg-config and a C++ compiler (.ci/run installs them)"]
    fn ompl_in_cpp_solves_the_city_queries_with_exactly_free_paths() {
        let map = skyplan_map::colliders::parse_colliders(skyplan_plan::FCND_CITY_CSV).unwrap();
        let world = crate::bench3d::bench_world(&map, 5.0).unwrap();
        let qs = crate::three_d::random_queries(&world, 4, 3);
        let ((runs, notes), lines) = ompl_cpp_peers(&world, &qs, 1.0).unwrap();
        assert!(notes.is_empty(), "{notes:?}");
        let names: Vec<&str> = runs.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            ["ompl-cpp-rrtconnect", "ompl-cpp-prm", "ompl-cpp-rrtstar"]
        );
        let rrt_connect = &runs[0].1;
        assert_eq!(rrt_connect.len(), qs.len());
        assert!(rrt_connect.iter().all(|r| r.length_m.is_some()));
        let mut checked = 0;
        for line in lines.lines() {
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            if v["solved"] != true {
                continue;
            }
            let path: Vec<Neu> = serde_json::from_value(v["path"].clone()).unwrap();
            let (start, goal) = qs[v["query"].as_u64().unwrap() as usize];
            let close = |a: Neu, b: Neu| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-6);
            assert!(
                close(path[0], start) && close(path[path.len() - 1], goal),
                "{line}"
            );
            let free = path.windows(2).all(|w| world.segment_is_free(w[0], w[1]));
            assert!(free, "not free by skyplan's check: {line}");
            assert_eq!(v["recheck_ok"], free, "{line}");
            checked += 1;
        }
        assert!(checked >= qs.len(), "{lines}");
    }
}
