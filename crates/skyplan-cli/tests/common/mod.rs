//! Helpers shared by the CLI tests: running the binary, reading its JSON, and the independent
//! exact re-check of 3D routes against every box.
#![allow(dead_code)]

use assert_cmd::Command;
use serde_json::Value;
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, WorldSpec, path_length_m};
use std::path::Path;

/// The bundled city map's text.
pub const CITY_CSV: &str = include_str!("../../../../data/colliders.csv");

/// The binary, run in `dir`.
pub fn skyplan(dir: &Path) -> Command {
    let mut cmd = Command::cargo_bin("skyplan").unwrap();
    cmd.current_dir(dir);
    cmd
}

/// Runs the binary with `args` in `dir`: exit code, stdout as JSON (null if it is not JSON),
/// stderr.
pub fn run(dir: &Path, args: &[&str]) -> (i32, Value, String) {
    let out = skyplan(dir).args(args).output().unwrap();
    let v = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    (
        out.status.code().unwrap_or(-1),
        v,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `skyplan plan --json LINE` (split into words): exit code and the JSON object (stdout
/// must be JSON).
pub fn plan_json(dir: &Path, line: &str) -> (i32, Value) {
    let (code, v, err) = run(dir, &[&["plan", "--json"], &words(line)[..]].concat());
    assert!(!v.is_null(), "stdout is not JSON; stderr: {err}");
    (code, v)
}

/// A loopback UDP port that was free a moment ago (bound, noted and released), for a peer to
/// bind.
pub fn free_udp_port() -> u16 {
    let socket = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    socket.local_addr().unwrap().port()
}

/// A loopback TCP port that was free a moment ago (bound, noted and released): nobody listens
/// on it until someone binds it.
pub fn free_tcp_port() -> u16 {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    listener.local_addr().unwrap().port()
}

/// A JSON number.
pub fn num(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// The waypoints of a 3D answer, from `start` to `goal` exactly, re-checked free against every
/// box of `map_text` grown by `safety_m` inside the answer's flight volume (brute force, exact
/// slab tests), with `cost_m` equal to their length.
pub fn checked_path_3d(
    map_text: &str,
    v: &Value,
    safety_m: f64,
    start: Neu,
    goal: Neu,
) -> Vec<Neu> {
    assert_eq!(v["status"], "ok", "{v}");
    assert_eq!(v["planner_status"], "exact", "{v}");
    let rows: Vec<[f64; 4]> = serde_json::from_value(v["waypoints"].clone()).unwrap();
    let path: Vec<Neu> = rows.iter().map(|r| [r[0], r[1], r[2]]).collect();
    assert!(path.len() >= 2);
    assert_eq!(path[0], start);
    assert_eq!(*path.last().unwrap(), goal);
    let corner = |c: &Value| -> Neu { [0, 1, 2].map(|i| num(&c[i])) };
    let bounds = Aabb {
        min: corner(&v["flight_volume"]["min"]),
        max: corner(&v["flight_volume"]["max"]),
    };
    let map = skyplan_map::colliders::parse_colliders(map_text).unwrap();
    let spec = WorldSpec {
        safety_m,
        min_alt_m: bounds.min[2],
        max_alt_m: bounds.max[2],
        margin_bounds_m: 0.0,
    };
    let world = BoxWorld3::with_bounds(&map.boxes, &spec, bounds).unwrap();
    let bf = world.brute_force();
    for (k, w) in path.windows(2).enumerate() {
        assert!(
            bf.segment_is_free(w[0], w[1]),
            "segment {k} {:?} → {:?} is not free",
            w[0],
            w[1]
        );
    }
    let cost = num(&v["cost_m"]);
    assert!(
        (cost - path_length_m(&path)).abs() < 1e-6,
        "cost {cost} vs {}",
        path_length_m(&path)
    );
    assert!(cost + 1e-9 >= num(&v["straight_line_m"]));
    path
}

/// The altitude above home, metres, where `fly` says the vehicle ended: its summary line
/// `vehicle    at N …, E …, A m above home`.
pub fn final_alt_m(text: &str) -> f64 {
    (text.lines())
        .find_map(|l| l.strip_prefix("vehicle    at N "))
        .and_then(|l| l.split(", ").nth(2))
        .and_then(|a| a.strip_suffix(" m above home"))
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("no final altitude in:\n{text}"))
}

/// The words of a command line, split at white space (no argument in these tests holds a space).
pub fn words(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

/// `skyplan LINE` in `dir`, LINE split into words.
pub fn cmd(dir: &Path, line: &str) -> Command {
    let mut cmd = skyplan(dir);
    cmd.args(words(line));
    cmd
}

/// Runs `cmd` and asserts that it succeeded (its stderr in the message).
pub fn ok(cmd: &mut Command) -> std::process::Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `skyplan LINE` in `dir` and asserts that it succeeded (its stderr in the message).
pub fn succeed(dir: &Path, line: &str) -> std::process::Output {
    ok(&mut cmd(dir, line))
}

/// Runs `skyplan LINE` in `dir`, asserts that it succeeded, and returns its stdout as JSON.
pub fn ok_json(dir: &Path, line: &str) -> Value {
    json_of(&succeed(dir, line))
}

/// A run's stdout as JSON (the panic shows both streams).
pub fn json_of(out: &std::process::Output) -> Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{e}: stdout {:?} stderr {:?}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

/// The exit code of `skyplan LINE` in `dir`.
pub fn code_of(dir: &Path, line: &str) -> Option<i32> {
    cmd(dir, line).output().unwrap().status.code()
}

/// Runs `skyplan LINE` in `dir`: it must exit with `code`, its stderr holding each of `needles`.
/// Returns the stderr.
pub fn fails_with(dir: &Path, line: &str, code: i32, needles: &[&str]) -> String {
    let out = cmd(dir, line).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "skyplan {line}: {err}");
    for needle in needles {
        assert!(
            err.contains(needle),
            "skyplan {line}: no {needle:?} in {err}"
        );
    }
    err.into_owned()
}

/// The waypoints of a JSON answer (or waypoint file) as rows north, east, altitude, heading.
pub fn rows(v: &Value) -> Vec<[f64; 4]> {
    serde_json::from_value(v["waypoints"].clone()).unwrap()
}

/// Asserts that every segment between consecutive rows is free on `grid` under `touch`.
pub fn assert_segments_free(
    grid: &skyplan_cspace::Grid2,
    rows: &[[f64; 4]],
    touch: skyplan_cspace::Touch,
) {
    for w in rows.windows(2) {
        assert!(
            grid.segment_is_free_ne((w[0][0], w[0][1]), (w[1][0], w[1][1]), touch),
            "{w:?}"
        );
    }
}

/// The Python with the peers: `SKYPLAN_PYTHON` (`.ci/run` sets its virtual environment), else
/// `python3`.
pub fn python() -> String {
    std::env::var("SKYPLAN_PYTHON").unwrap_or_else(|_| "python3".to_string())
}

/// Asserts that no waypoint file was written in `dir` (`why` in the message).
pub fn assert_no_waypoints(dir: &Path, why: &str) {
    assert!(!dir.join("waypoints.json").exists(), "{why}");
}

/// A new temporary directory holding `files` (name, text).
pub fn dir_with(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    dir
}

/// `skyplan sim --listen tcp:127.0.0.1:0 ARGS` in its own process, its address read from its
/// first line and the rest of its output drained (it never blocks on a full pipe); killed when
/// dropped.
pub struct SimProcess {
    pub child: std::process::Child,
    /// `tcp:127.0.0.1:PORT`
    pub address: String,
    pub port: u16,
}

impl SimProcess {
    pub fn start(args: &[&str]) -> Self {
        use std::io::{BufRead, BufReader};
        let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("skyplan"))
            .args(["sim", "--listen", "tcp:127.0.0.1:0"])
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::inherit())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        let first = lines.next().unwrap().unwrap();
        let address = first
            .split_whitespace()
            .find(|w| w.starts_with("tcp:"))
            .unwrap_or_else(|| panic!("no address in {first:?}"))
            .trim_end_matches(',')
            .to_string();
        let port = address.rsplit(':').next().unwrap().parse().unwrap();
        std::thread::spawn(move || for _ in lines {});
        Self {
            child,
            address,
            port,
        }
    }

    /// The process has not exited.
    pub fn running(&mut self) -> bool {
        self.child.try_wait().unwrap().is_none()
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A finished run of the binary: its exit code and both streams.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

impl Run {
    /// Asserts the exit code (both streams in the message).
    pub fn expect_code(&self, code: i32) -> &Self {
        assert_eq!(
            self.code,
            Some(code),
            "stdout:\n{}\nstderr:\n{}",
            self.stdout,
            self.stderr
        );
        self
    }
}

/// Runs the binary with `args` in `dir`, for at most two minutes.
pub fn run_args(dir: &Path, args: &[&str]) -> Run {
    let out = skyplan(dir)
        .args(args)
        .timeout(std::time::Duration::from_secs(120))
        .output()
        .unwrap();
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// The part of the route segment `a`–`b` (rows north, east, altitude, …) whose altitude lies in
/// `[lo, hi]`, as its two north/east ends; `None` if no part does.
pub fn part_in_band(a: [f64; 4], b: [f64; 4], lo: f64, hi: f64) -> Option<([f64; 2], [f64; 2])> {
    let (za, zb) = (a[2], b[2]);
    let (t0, t1) = if za == zb {
        if za < lo || za > hi {
            return None;
        }
        (0.0, 1.0)
    } else {
        let (s, t) = ((lo - za) / (zb - za), (hi - za) / (zb - za));
        (s.min(t).max(0.0), s.max(t).min(1.0))
    };
    let at = |t: f64| [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
    (t0 <= t1).then(|| (at(t0), at(t1)))
}
