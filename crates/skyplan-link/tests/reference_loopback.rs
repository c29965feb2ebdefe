//! A reference flown over a real loopback TCP socket: setpoints with velocity and acceleration
//! (SET_POSITION_TARGET_GLOBAL_INT, type_mask 0x0800) from the ground station to the simulator.

use skyplan_flight::executor::{ExecutorConfig, FlightState, Note, Outcome, ReferenceExecutor};
use skyplan_flight::reference::{MinJerkLine, Reference, Setpoint};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_link::ground::{
    GroundConfig, GroundProtocol, GroundStation, POSITION_VELOCITY_ACCELERATION_AND_YAW, Update,
    grid_convergence_rad,
};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::mavlink::dialects::common::MavMessage;
use skyplan_link::vehicle::{SimNote, SimServerConfig, sim_target, stamped};
use std::sync::Arc;
use std::time::Duration;

const HOME: Lla = Lla {
    lat_deg: 37.792480,
    lon_deg: -122.397450,
    alt_m: 0.0,
};

/// The ground's message of a setpoint carries the mask 0x0800, the position, the velocity and
/// the acceleration turned to true north, the stamp; the vehicle side decodes them back.
#[test]
fn a_setpoint_goes_out_with_velocity_and_acceleration_and_comes_back() {
    let frame = LocalFrame::new(HOME).unwrap();
    let gamma = grid_convergence_rad(&frame, HOME).unwrap();
    assert!(gamma.to_degrees() > 0.3); // turned, so that a missing turn shows
    let setpoint = Setpoint {
        point_ned: [30.0, -20.0, -12.0],
        vel_ned_m_s: [6.0, -2.0, 0.5],
        accel_ned_m_s2: [-1.0, 0.25, 0.1],
        yaw_rad: 0.5,
    };
    let m = GroundProtocol::new()
        .track_target(&frame, &setpoint, gamma, 123_456)
        .unwrap();
    let MavMessage::SET_POSITION_TARGET_GLOBAL_INT(t) = &m else {
        panic!("{m:?}");
    };
    assert_eq!(t.type_mask.bits(), 0x0800);
    assert_eq!(POSITION_VELOCITY_ACCELERATION_AND_YAW, 0x0800);
    assert_eq!(t.time_boot_ms, 123_456);
    assert!((f64::from(t.alt) - 12.0).abs() < 1e-6);
    assert!((f64::from(t.yaw) - (0.5 + gamma)).abs() < 1e-6);
    // True north: the map's grid north is `gamma` east of it.
    let (c, s) = (gamma.cos(), gamma.sin());
    let turned = |[n, e, d]: [f64; 3]| [n * c - e * s, n * s + e * c, d];
    let close = |a: [f32; 3], b: [f64; 3]| (0..3).all(|i| (f64::from(a[i]) - b[i]).abs() < 1e-5);
    assert!(
        close([t.vx, t.vy, t.vz], turned(setpoint.vel_ned_m_s)),
        "{t:?}"
    );
    assert!(
        close([t.afx, t.afy, t.afz], turned(setpoint.accel_ned_m_s2)),
        "{t:?}"
    );
    // The map frame's point, back from the message's latitude and longitude.
    let lla = Lla {
        lat_deg: f64::from(t.lat_int) * 1e-7,
        lon_deg: f64::from(t.lon_int) * 1e-7,
        alt_m: 0.0,
    };
    let ned = frame.ned_from_lla(lla).unwrap();
    assert!((ned.north_m - 30.0).abs() < 0.02 && (ned.east_m + 20.0).abs() < 0.02);
    // The vehicle side: velocity and acceleration given (their mask bits clear), the yaw too.
    let decoded = sim_target(
        t.type_mask.bits(),
        [1.0, 2.0, -12.0],
        [t.vx, t.vy, t.vz],
        [t.afx, t.afy, t.afz],
        t.yaw,
    );
    let v = decoded.velocity_ned_m_s.unwrap();
    let a = decoded.accel_ned_m_s2.unwrap();
    assert!(close([t.vx, t.vy, t.vz], v) && close([t.afx, t.afy, t.afz], a));
    assert!((decoded.yaw_rad - f64::from(t.yaw)).abs() < 1e-12);
    // Stamped 0.2 s before the vehicle's now: brought forward at constant acceleration.
    let now = stamped(decoded, t.time_boot_ms, 123.656);
    assert!((now.position_ned_m[0] - (1.0 + v[0] * 0.2 + 0.5 * a[0] * 0.04)).abs() < 1e-9);
    // A position-only target's mask (0x9F8) gives neither, as before.
    let plain = sim_target(0x9F8, [1.0, 2.0, -3.0], [9.0; 3], [9.0; 3], 0.0);
    assert_eq!((plain.velocity_ned_m_s, plain.accel_ned_m_s2), (None, None));
    // A force is not an acceleration.
    assert_eq!(
        sim_target(0x0A00, [0.0; 3], [1.0; 3], [1.0; 3], 0.0).accel_ned_m_s2,
        None
    );
}

/// Three legs of 60–100 m at up to 8 m/s, flown by the simulator at 20× over TCP: lands at the
/// goal, tracks the reference within 0.5 m, and takes its duration within 5 %.
#[test]
fn flies_a_min_jerk_reference_over_tcp_within_half_a_metre() {
    let points = vec![
        [0.0, 0.0, -10.0],
        [90.0, 0.0, -10.0],
        [90.0, 70.0, -12.0],
        [30.0, 70.0, -12.0],
    ];
    let reference = Arc::new(MinJerkLine::at_peak_speed(points.clone(), 8.0).unwrap());
    let config = SimServerConfig {
        speedup: 20.0,
        ..SimServerConfig::at(HOME)
    };
    let sim = InProcessSim::start(config, None).unwrap();
    let ground = GroundConfig {
        speedup: 20.0,
        timeout_s: Some(60.0),
        ..GroundConfig::default()
    };
    let mut gcs = GroundStation::connect(&sim.address(), ground).unwrap();
    gcs.wait_for_vehicle(Duration::from_secs(10), |_, _| {})
        .unwrap();
    let mut ex = ReferenceExecutor::new(reference.clone(), ExecutorConfig::default()).unwrap();
    let frame = LocalFrame::new(HOME).unwrap();
    let mut states = vec![FlightState::Manual];
    let summary = gcs
        .fly(&mut ex, &frame, |u| {
            if let Update::Notes(_, notes) = u {
                for n in notes {
                    if let Note::State { to, .. } = n {
                        states.push(to);
                    }
                }
            }
        })
        .unwrap();
    let (report, sim_notes) = sim.finish();
    let report = report.unwrap();
    assert_eq!(ex.outcome(), Some(&Outcome::Completed), "{sim_notes:?}");
    use FlightState::*;
    assert_eq!(
        states,
        vec![
            Manual, Arming, Takeoff, Waypoint, Landing, Disarming, Manual
        ]
    );
    assert!(sim_notes.contains(&SimNote::Landed));
    // Landed at the goal (the simulator's own final position, true-north frame about home:
    // within the 0.37° turn of 80 m ≈ 0.5 m plus the acceptance radius of the map's goal).
    let last = report.final_state.position_ned_m;
    let goal = points[3];
    assert!(
        (last[0] - goal[0]).hypot(last[1] - goal[1]) < 2.0,
        "{last:?}"
    );
    assert!(report.final_state.on_ground && !report.final_state.armed);
    let tracking = summary.tracking.unwrap();
    assert_eq!(tracking, ex.tracking().unwrap());
    assert!(tracking.max_tracking_error_m <= 0.5, "{tracking:?}");
    // The position stream is 10 Hz of vehicle time; at 20× on a busy machine some are late or
    // merged: at least half of them compared.
    let expected = reference.duration_s() / 0.1;
    assert!(tracking.samples as f64 >= 0.5 * expected, "{tracking:?}");
    assert!(
        tracking.setpoints_sent as f64 >= reference.duration_s() * 10.0,
        "{tracking:?}"
    );
    let ratio = tracking.time_ratio().unwrap();
    assert!((0.95..=1.05).contains(&ratio), "{tracking:?}");
    eprintln!(
        "tracking: max error {:.3} m, flown {:.2} s of a {:.2} s reference (ratio {ratio:.4}), {} samples, {} setpoints",
        tracking.max_tracking_error_m,
        tracking.flown_s.unwrap(),
        tracking.duration_s,
        tracking.samples,
        tracking.setpoints_sent
    );
}

/// What the ground station has heard from an ArduPilot vehicle: its heartbeat, its EKF origin
/// (10 m above mean sea level) and a position (home 12 m above mean sea level).
fn ardupilot_heard(
    autopilot: skyplan_link::mavlink::dialects::common::MavAutopilot,
) -> GroundProtocol {
    use skyplan_link::Received;
    use skyplan_link::mavlink::MavHeader;
    use skyplan_link::mavlink::dialects::common::*;
    let mut p = GroundProtocol::new();
    let header = MavHeader {
        system_id: 1,
        component_id: 1,
        sequence: 0,
    };
    let (lat, lon) = ((HOME.lat_deg * 1e7) as i32, (HOME.lon_deg * 1e7) as i32);
    for message in [
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot,
            ..Default::default()
        }),
        MavMessage::GPS_GLOBAL_ORIGIN(GPS_GLOBAL_ORIGIN_DATA {
            latitude: lat,
            longitude: lon,
            altitude: 10_000,
            ..Default::default()
        }),
        MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
            lat,
            lon,
            alt: 12_500,
            relative_alt: 500,
            ..Default::default()
        }),
    ] {
        p.absorb(0.0, &Received { header, message });
    }
    p
}

/// ArduPilot keeps a target's acceleration only from SET_POSITION_TARGET_LOCAL_NED: once its
/// EKF origin is known, a setpoint goes out in its frame (north and east of the origin by the
/// spherical flat-earth formulas, down from the origin's altitude), velocity and acceleration
/// turned to true north as before; PX4 keeps GLOBAL_INT.
#[test]
fn an_ardupilot_setpoint_goes_out_in_its_local_frame_with_the_acceleration() {
    use skyplan_link::mavlink::dialects::common::MavAutopilot;
    let frame = LocalFrame::new(HOME).unwrap();
    let gamma = grid_convergence_rad(&frame, HOME).unwrap();
    let setpoint = Setpoint {
        point_ned: [300.0, -200.0, -12.0],
        vel_ned_m_s: [6.0, -2.0, 0.5],
        accel_ned_m_s2: [-1.0, 0.25, 0.1],
        yaw_rad: 0.5,
    };
    let p = ardupilot_heard(MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA);
    let m = p.track_target(&frame, &setpoint, gamma, 7).unwrap();
    let MavMessage::SET_POSITION_TARGET_LOCAL_NED(t) = &m else {
        panic!("{m:?}");
    };
    assert_eq!(t.type_mask.bits(), POSITION_VELOCITY_ACCELERATION_AND_YAW);
    assert_eq!(t.time_boot_ms, 7);
    // Independently: the target's latitude and longitude on a sphere of ArduPilot's radius,
    // metres of latitude and of longitude at the origin's latitude.
    let lla = frame
        .lla_from_ned(skyplan_frames::Ned {
            north_m: 300.0,
            east_m: -200.0,
            down_m: 0.0,
        })
        .unwrap();
    let r = 6_378_100.0_f64;
    let origin_lat = f64::from((HOME.lat_deg * 1e7) as i32) * 1e-7;
    let origin_lon = f64::from((HOME.lon_deg * 1e7) as i32) * 1e-7;
    let north = (lla.lat_deg - origin_lat).to_radians() * r;
    let east = (lla.lon_deg - origin_lon).to_radians() * r * origin_lat.to_radians().cos();
    assert!((f64::from(t.x) - north).abs() < 0.01, "{} vs {north}", t.x);
    assert!((f64::from(t.y) - east).abs() < 0.01, "{} vs {east}", t.y);
    // 12 m above home, home 2 m above the origin.
    assert!((f64::from(t.z) + 14.0).abs() < 1e-4, "{}", t.z);
    let (c, s) = (gamma.cos(), gamma.sin());
    let turned = |[n, e, d]: [f64; 3]| [n * c - e * s, n * s + e * c, d];
    let close = |a: [f32; 3], b: [f64; 3]| (0..3).all(|i| (f64::from(a[i]) - b[i]).abs() < 1e-5);
    assert!(close([t.vx, t.vy, t.vz], turned(setpoint.vel_ned_m_s)));
    assert!(close(
        [t.afx, t.afy, t.afz],
        turned(setpoint.accel_ned_m_s2)
    ));
    assert!((f64::from(t.yaw) - (0.5 + gamma)).abs() < 1e-6);
    // PX4 takes GLOBAL_INT targets whole.
    let p = ardupilot_heard(MavAutopilot::MAV_AUTOPILOT_PX4);
    let m = p.track_target(&frame, &setpoint, gamma, 7).unwrap();
    assert!(
        matches!(m, MavMessage::SET_POSITION_TARGET_GLOBAL_INT(_)),
        "{m:?}"
    );
}

/// PARAM_REQUEST_READ by name over TCP: the simulator answers what it holds (after a
/// PARAM_SET, the new value) and, as ArduPilot, nothing for a name it has not.
#[test]
fn parameters_are_read_by_name_and_an_unknown_one_is_said_so() {
    let sim = InProcessSim::start(SimServerConfig::at(HOME), None).unwrap();
    let mut gcs = GroundStation::connect(&sim.address(), GroundConfig::default()).unwrap();
    gcs.wait_for_vehicle(Duration::from_secs(10), |_, _| {})
        .unwrap();
    let before = gcs.get_param("RTL_ALT", 2, 0.5).unwrap();
    assert_eq!(
        gcs.set_param("RTL_ALT", before + 700.0).unwrap(),
        before + 700.0
    );
    assert_eq!(gcs.get_param("RTL_ALT", 2, 0.5).unwrap(), before + 700.0);
    let e = gcs
        .get_param("WPNAV_SPEED", 2, 0.2)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("WPNAV_SPEED") && e.contains("did not answer after 2 tries"),
        "{e}"
    );
    drop(gcs);
    sim.finish();
}
