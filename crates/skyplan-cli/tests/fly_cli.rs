//! `skyplan fly` and `skyplan sim` end to end: the real binary, the built-in simulator over
//! loopback TCP, and an independent MAVLink peer (Python pymavlink).

use assert_cmd::Command;
use std::collections::BTreeSet;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

fn skyplan(dir: &Path) -> Command {
    let mut cmd = Command::cargo_bin("skyplan").unwrap();
    cmd.current_dir(dir);
    cmd
}

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

fn run(dir: &Path, args: &[&str]) -> Run {
    let out = skyplan(dir)
        .args(args)
        .timeout(Duration::from_secs(120))
        .output()
        .unwrap();
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// The flight log as (header, rows).
fn read_log(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|rec| rec.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

#[test]
fn fly_sim_flies_the_fcnd_route_on_the_bundled_map() {
    let dir = tempfile::tempdir().unwrap();
    // Home → the default goal across the city (the README route), 50× real time.
    let r = run(
        dir.path(),
        &[
            "fly",
            "--sim",
            "--speedup",
            "50",
            "--log",
            "flight.csv",
            "--timeout-s",
            "60",
        ],
    );
    assert_eq!(
        r.code,
        Some(0),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    let n: usize = r
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("result     landed and disarmed after reaching all "))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no result line:\n{}", r.stdout));
    assert!(n >= 2);
    for state in [
        "MANUAL → ARMING",
        "ARMING → TAKEOFF",
        "TAKEOFF → WAYPOINT",
        "WAYPOINT → LANDING",
        "LANDING → DISARMING",
        "DISARMING → MANUAL",
    ] {
        assert!(r.stdout.contains(state), "missing {state}:\n{}", r.stdout);
    }
    for k in 1..=n {
        assert!(
            r.stdout.contains(&format!(" {k} of {n} reached")),
            "waypoint {k}:\n{}",
            r.stdout
        );
    }
    assert!(
        r.stdout.contains("no collision with the map's obstacles"),
        "{}",
        r.stdout
    );

    // The log: every state, every waypoint targeted, ends on the ground at the goal.
    let (header, rows) = read_log(&dir.path().join("flight.csv"));
    assert_eq!(
        header[..5],
        ["time_s", "state", "north_m", "east_m", "alt_m"]
    );
    assert!(rows.len() > 100);
    let states: BTreeSet<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    for s in ["TAKEOFF", "WAYPOINT", "LANDING"] {
        assert!(states.contains(s), "{states:?}");
    }
    // Waypoint 1 is the start, reached the moment take-off ends; every other one is flown to.
    let targeted: BTreeSet<usize> = rows.iter().filter_map(|r| r[7].parse().ok()).collect();
    assert_eq!(targeted, (2..=n).collect());
    let f = |s: &str| s.parse::<f64>().unwrap();
    let last = rows.last().unwrap();
    assert!(
        (f(&last[2]) - 420.0).abs() < 1.5 && (f(&last[3]) - 390.0).abs() < 1.5,
        "{last:?}"
    );
    assert!(f(&last[4]).abs() < 0.3, "{last:?}");
    let times: Vec<f64> = rows.iter().map(|r| f(&r[0])).collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]));
    let max_alt = rows.iter().map(|r| f(&r[4])).fold(0.0, f64::max);
    assert!((4.75..5.5).contains(&max_alt), "{max_alt}");
}

#[test]
fn fly_sim_upload_flies_the_mission_in_auto() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &[
            "fly",
            "--sim",
            "--upload",
            "--speedup",
            "50",
            "--log",
            "flight.csv",
            "--timeout-s",
            "60",
        ],
    );
    assert_eq!(
        r.code,
        Some(0),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    let n: usize = r
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("result     landed and disarmed after reaching all "))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no result line:\n{}", r.stdout));
    assert!(n >= 2);
    // Home, take-off, the waypoints, land: every item requested once and acknowledged.
    let items = n + 3;
    assert!(
        r.stdout
            .contains(&format!("upload     accepted: {items} items in"))
            && r.stdout
                .contains(&format!("({items} requests answered, 0 resends)")),
        "{}",
        r.stdout
    );
    assert!(
        r.stdout
            .contains(&format!("sim        mission of {items} items received")),
        "{}",
        r.stdout
    );
    for line in [
        "MANUAL → ARMING",
        "ARMING → TAKEOFF",
        "TAKEOFF → WAYPOINT",
        "WAYPOINT → LANDING",
        "LANDING → DISARMING",
        "DISARMING → MANUAL",
        "sim        mode AUTO",
        // The vehicle flew it: no position target was streamed.
        "0 position targets sent",
        "no collision with the map's obstacles",
    ] {
        assert!(r.stdout.contains(line), "missing {line}:\n{}", r.stdout);
    }
    for k in 1..=n {
        assert!(
            r.stdout.contains(&format!(" {k} of {n} reached")),
            "waypoint {k}:\n{}",
            r.stdout
        );
    }
    let (_, rows) = read_log(&dir.path().join("flight.csv"));
    let f = |s: &str| s.parse::<f64>().unwrap();
    let last = rows.last().unwrap();
    assert!(
        (f(&last[2]) - 420.0).abs() < 1.5 && (f(&last[3]) - 390.0).abs() < 1.5,
        "{last:?}"
    );
    assert!(f(&last[4]).abs() < 0.3, "{last:?}");
}

#[test]
fn upload_only_uploads_to_a_separate_sim_and_exits() {
    let sim = SimProcess::start("20");
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &[
            "fly",
            "--connect",
            &sim.address,
            "--upload-only",
            "--goal-ne",
            "60,30",
        ],
    );
    assert_eq!(
        r.code,
        Some(0),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    assert!(r.stdout.contains("upload     accepted:"), "{}", r.stdout);
    assert!(
        r.stdout
            .contains("result     mission uploaded (--upload-only: not flown)"),
        "{}",
        r.stdout
    );
    assert!(!r.stdout.contains("→ ARMING"), "{}", r.stdout);
}

#[test]
fn a_link_lost_mid_flight_is_reported_with_a_nonzero_exit() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &[
            "fly",
            "--sim",
            "--speedup",
            "20",
            "--goal-ne",
            "60,30",
            "--sim-drop-link-after-s",
            "12",
            "--link-timeout-s",
            "1",
            "--log",
            "flight.csv",
        ],
    );
    assert_eq!(
        r.code,
        Some(1),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    assert!(
        r.stdout
            .contains("injected fault: the vehicle stops talking"),
        "{}",
        r.stdout
    );
    assert!(
        r.stderr
            .contains("flight failed: link lost in WAYPOINT: no heartbeat from the vehicle for"),
        "{}",
        r.stderr
    );
    // The log of what was flown is still written.
    let (_, rows) = read_log(&dir.path().join("flight.csv"));
    assert!(rows.iter().any(|r| r[1] == "WAYPOINT"));
}

#[test]
fn the_overall_timeout_lands_the_vehicle_and_fails() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &["fly", "--sim", "--speedup", "20", "--timeout-s", "1.5"],
    );
    assert_eq!(
        r.code,
        Some(1),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    assert!(
        r.stdout.contains("timeout    1.5 s wall exceeded: landing"),
        "{}",
        r.stdout
    );
    assert!(
        r.stdout.contains("→ LANDING") && r.stdout.contains("DISARMING → MANUAL"),
        "{}",
        r.stdout
    );
    assert!(
        r.stderr
            .contains("aborted (--timeout-s 1.5 exceeded); the vehicle landed"),
        "{}",
        r.stderr
    );
}

#[test]
fn bad_addresses_and_missing_vehicles_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &["fly", "--connect", "serial:/dev/ttyUSB0:57600"],
    );
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(
        r.stderr.contains("serial ports are not built in"),
        "{}",
        r.stderr
    );
    let r = run(dir.path(), &["fly", "--connect", "tcp:127.0.0.1"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    // Nothing listens on port 1.
    let r = run(dir.path(), &["fly", "--connect", "tcp:127.0.0.1:1"]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(
        r.stderr.contains("cannot open tcpout:127.0.0.1:1"),
        "{}",
        r.stderr
    );
    let r = run(dir.path(), &["fly", "--sim", "--speedup", "0"]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    let r = run(dir.path(), &["sim", "--listen", "tcpout:127.0.0.1:5760"]);
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(r.stderr.contains("the simulator listens"), "{}", r.stderr);
}

/// `skyplan sim` on a free port, with its address read from its first line.
struct SimProcess {
    child: std::process::Child,
    address: String,
}

impl SimProcess {
    fn start(speedup: &str) -> Self {
        let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("skyplan"))
            .args([
                "sim",
                "--listen",
                "tcp:127.0.0.1:0",
                "--speedup",
                speedup,
                "--duration-s",
                "120",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let mut lines = BufReader::new(stdout).lines();
        let first = lines.next().unwrap().unwrap();
        let address = first
            .split_whitespace()
            .find(|w| w.starts_with("tcp:"))
            .unwrap_or_else(|| panic!("no address in {first:?}"))
            .trim_end_matches(',')
            .to_string();
        // Keep draining its output so that it never blocks on a full pipe.
        std::thread::spawn(move || for _ in lines {});
        Self { child, address }
    }
}

impl Drop for SimProcess {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

#[test]
fn fly_connects_to_a_separate_sim_process() {
    let sim = SimProcess::start("20");
    let dir = tempfile::tempdir().unwrap();
    let r = run(
        dir.path(),
        &[
            "fly",
            "--connect",
            &sim.address,
            "--speedup",
            "20",
            "--goal-ne",
            "60,30",
            "--timeout-s",
            "60",
        ],
    );
    assert_eq!(
        r.code,
        Some(0),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    assert!(
        r.stdout
            .contains("result     landed and disarmed after reaching all"),
        "{}",
        r.stdout
    );
}

/// The Python with the peers: `SKYPLAN_PYTHON` (`.ci/run` sets its virtual environment), else
/// `python3`.
fn python() -> String {
    std::env::var("SKYPLAN_PYTHON").unwrap_or_else(|_| "python3".to_string())
}

#[test]
#[ignore = "needs Python with pymavlink (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn pymavlink_drives_skyplan_sim() {
    let sim = SimProcess::start("10");
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fly/pymavlink_peer.py");
    let t0 = Instant::now();
    let out = std::process::Command::new(python())
        .args([script, &sim.address])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "pymavlink peer failed after {:.1} s:\n{stdout}\n{}",
        t0.elapsed().as_secs_f64(),
        String::from_utf8_lossy(&out.stderr)
    );
    for expected in [
        "refusal reason: Takeoff: vehicle not armed",
        "mission upload accepted after 4 items",
        "took off to 95 % of 5 m",
        "position target reached",
        "landed and disarmed",
        "mission items reached: [1, 2, 3]",
        "OK",
    ] {
        assert!(stdout.contains(expected), "missing {expected:?}:\n{stdout}");
    }
}

#[test]
#[ignore = "needs Python with mavsdk (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn skyplan_uploads_its_mission_to_mavsdk_mission_raw_server() {
    // A free UDP port for MAVSDK to listen on.
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan.json");
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fly/mavsdk_autopilot.py");
    let mut peer = std::process::Command::new(python())
        .args([
            script,
            &port.to_string(),
            "37.792480",
            "-122.397450",
            plan.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(peer.stdout.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    assert!(first.starts_with("listening"), "{first}");
    let reader = std::thread::spawn(move || lines.map_while(|l| l.ok()).collect::<Vec<_>>());
    let r = run(
        dir.path(),
        &[
            "fly",
            "--connect",
            &format!("udpout:127.0.0.1:{port}"),
            "--upload-only",
            "--out",
            "plan.json",
            "--wait-s",
            "20",
        ],
    );
    let status = peer.wait().unwrap();
    let peer_out = reader.join().unwrap().join("\n");
    assert_eq!(
        r.code,
        Some(0),
        "stdout:\n{}\nstderr:\n{}\nMAVSDK peer:\n{peer_out}",
        r.stdout,
        r.stderr
    );
    assert!(
        status.success() && peer_out.lines().any(|l| l == "OK"),
        "MAVSDK peer failed:\n{peer_out}\nskyplan:\n{}",
        r.stdout
    );
    assert!(r.stdout.contains("upload     accepted:"), "{}", r.stdout);
    let n_items = peer_out.lines().filter(|l| l.starts_with("item ")).count();
    assert!(n_items >= 5, "{peer_out}");
}

/// Starts `skyplan fly` with `args`, sends it SIGINT (`kill -INT`, as a terminal's Ctrl-C
/// does) once its output shows `trigger`, and returns how it ended.
fn fly_and_interrupt(args: &[&str], trigger: &str) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("skyplan"))
        .current_dir(dir.path())
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id().to_string();
    let (tx, rx) = std::sync::mpsc::channel::<String>();
    let stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        for line in BufReader::new(stdout).lines().map_while(|l| l.ok()) {
            all.push_str(&line);
            all.push('\n');
            let _ = tx.send(line);
        }
        all
    });
    let mut stderr = child.stderr.take().unwrap();
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut stderr, &mut s);
        s
    });
    let start = Instant::now();
    let mut sent = false;
    while start.elapsed() < Duration::from_secs(60) {
        match rx.recv_timeout(Duration::from_millis(100)) {
            Ok(line) if line.contains(trigger) => {
                let status = std::process::Command::new("kill")
                    .args(["-INT", &pid])
                    .status()
                    .unwrap();
                assert!(status.success());
                sent = true;
                break;
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            _ => {}
        }
    }
    // Then it must end on its own.
    let deadline = Instant::now() + Duration::from_secs(60);
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("skyplan fly did not end after SIGINT");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = reader.join().unwrap();
    let stderr = err_reader.join().unwrap();
    assert!(sent, "never saw {trigger:?}:\n{stdout}\n{stderr}");
    Run {
        code,
        stdout,
        stderr,
    }
}

#[test]
fn ctrl_c_in_flight_lands_reports_and_fails() {
    let r = fly_and_interrupt(&["fly", "--sim", "--speedup", "20"], "TAKEOFF → WAYPOINT");
    assert_eq!(
        r.code,
        Some(1),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    for line in [
        "interrupt  Ctrl-C: landing",
        "WAYPOINT → LANDING",
        "LANDING → DISARMING",
        "DISARMING → MANUAL",
        "result     FAILED: aborted (interrupted by Ctrl-C); the vehicle landed",
        "sim        touched down",
    ] {
        assert!(r.stdout.contains(line), "missing {line}:\n{}", r.stdout);
    }
    assert!(
        r.stderr
            .contains("flight failed: aborted (interrupted by Ctrl-C); the vehicle landed"),
        "{}",
        r.stderr
    );
    assert!(!r.stdout.contains("result     landed and disarmed"));
}

#[test]
fn ctrl_c_with_on_interrupt_hold_leaves_the_vehicle_loitering() {
    let r = fly_and_interrupt(
        &[
            "fly",
            "--sim",
            "--speedup",
            "20",
            "--upload",
            "--on-interrupt",
            "hold",
        ],
        "TAKEOFF → WAYPOINT",
    );
    assert_eq!(
        r.code,
        Some(1),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    for line in [
        "interrupt  Ctrl-C: holding position (LOITER)",
        "sim        mode LOITER",
        "ARMED, state WAYPOINT",
    ] {
        assert!(r.stdout.contains(line), "missing {line}:\n{}", r.stdout);
    }
    assert!(
        r.stderr.contains(
            "stopped in WAYPOINT (interrupted by Ctrl-C); the vehicle is holding its position in the air: take over"
        ),
        "{}",
        r.stderr
    );
    assert!(!r.stdout.contains("→ LANDING"), "{}", r.stdout);
}

#[test]
fn failsafe_rtl_is_commanded_when_a_lost_link_comes_back() {
    let dir = tempfile::tempdir().unwrap();
    // Silent from 12 s to 52 s of vehicle time (2 s wall at 20×): lost after 1 s, back after ~2 s.
    let r = run(
        dir.path(),
        &[
            "fly",
            "--sim",
            "--speedup",
            "20",
            "--goal-ne",
            "60,30",
            "--sim-drop-link-after-s",
            "12",
            "--sim-link-gap-s",
            "40",
            "--link-timeout-s",
            "1",
            "--failsafe",
            "rtl",
            "--log",
            "flight.csv",
        ],
    );
    assert_eq!(
        r.code,
        Some(1),
        "stdout:\n{}\nstderr:\n{}",
        r.stdout,
        r.stderr
    );
    for line in [
        "injected fault: the vehicle stops talking",
        "lost in WAYPOINT: no heartbeat for",
        "waiting up to 6.0 s for it to return (--failsafe rtl)",
        "injected fault over: the vehicle talks again",
        "commanding RTL (--failsafe rtl)",
        "sim        mode RTL",
        "WAYPOINT → LANDING",
        "DISARMING → MANUAL",
        "sim        touched down",
        "no collision with the map's obstacles",
    ] {
        assert!(r.stdout.contains(line), "missing {line}:\n{}", r.stdout);
    }
    assert!(
        r.stderr
            .contains("flight failed: aborted (link lost in WAYPOINT for")
            && r.stderr
                .contains("--failsafe rtl on its return); the vehicle landed"),
        "{}",
        r.stderr
    );
    // It landed back where it took off.
    let (_, rows) = read_log(&dir.path().join("flight.csv"));
    let f = |s: &str| s.parse::<f64>().unwrap();
    let first = &rows[0];
    let last = rows.last().unwrap();
    assert!(
        (f(&last[2]) - f(&first[2])).hypot(f(&last[3]) - f(&first[3])) < 1.5,
        "{first:?} → {last:?}"
    );
    assert!(f(&last[4]).abs() < 0.3, "{last:?}");
}
