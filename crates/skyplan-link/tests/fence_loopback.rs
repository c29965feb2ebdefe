//! The fence (`mission_type` FENCE) uploaded to the simulated vehicle and read back: every
//! message of both exchanges carries `mission_type` 1, what the vehicle stores is what was sent,
//! and a fence the vehicle cannot store is refused with a clear error.

use skyplan_flight::fence::{
    CIRCLE_EXCLUSION, FenceItem, FenceShape, POLYGON_VERTEX_EXCLUSION, fence_items,
};
use skyplan_flight::upload::UploadConfig;
use skyplan_frames::Lla;
use skyplan_link::Received;
use skyplan_link::ground::{
    FenceDownload, GroundConfig, GroundError, GroundProtocol, GroundStation, UploadDriver,
};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::mavlink::MavHeader;
use skyplan_link::mavlink::dialects::common::*;
use skyplan_link::vehicle::fuzzing::SimHarness;
use skyplan_link::vehicle::{SimNote, SimServerConfig};
use std::time::Duration;

const HOME: Lla = Lla {
    lat_deg: 37.792480,
    lon_deg: -122.397450,
    alt_m: 0.0,
};

fn shapes() -> Vec<FenceShape> {
    vec![
        FenceShape::Polygon {
            inclusion: true,
            vertices_lat_lon_deg: vec![
                [37.7900, -122.4000],
                [37.7950, -122.4000],
                [37.7950, -122.3950],
                [37.7900, -122.3950],
            ],
        },
        FenceShape::Circle {
            inclusion: false,
            centre_lat_lon_deg: [37.79301234, -122.39712345],
            radius_m: 35.5,
        },
        FenceShape::Polygon {
            inclusion: false,
            vertices_lat_lon_deg: vec![
                [37.7910, -122.3990],
                [37.7915, -122.3990],
                [37.7915, -122.3985],
            ],
        },
    ]
}

/// The mission type a MISSION_* message carries, if it is one.
fn mission_type(m: &MavMessage) -> Option<MavMissionType> {
    Some(match m {
        MavMessage::MISSION_COUNT(d) => d.mission_type,
        MavMessage::MISSION_REQUEST_INT(d) => d.mission_type,
        MavMessage::MISSION_ITEM_INT(d) => d.mission_type,
        MavMessage::MISSION_ACK(d) => d.mission_type,
        MavMessage::MISSION_REQUEST_LIST(d) => d.mission_type,
        _ => return None,
    })
}

fn from_vehicle(message: MavMessage) -> Received {
    Received {
        header: MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: 0,
        },
        message,
    }
}

/// The ground's upload and read-back drivers against the simulator's protocol, message by
/// message, without a socket: every MISSION_* message either way is of type FENCE, and the
/// exchange is COUNT → (REQUEST_INT → ITEM_INT)×n → ACK, then REQUEST_LIST → COUNT →
/// (REQUEST_INT → ITEM_INT)×n → ACK.
#[test]
fn every_message_of_both_exchanges_is_of_type_fence() {
    let items = fence_items(&shapes()).unwrap();
    let mut sim = SimHarness::new();
    let mut p = GroundProtocol::new();
    let mut names = Vec::new();
    let check = |m: &MavMessage, names: &mut Vec<String>| {
        if let Some(t) = mission_type(m) {
            assert_eq!(t, MavMissionType::MAV_MISSION_TYPE_FENCE, "{m:?}");
            names.push(skyplan_link::message_name(m).to_string());
        }
    };
    let (mut up, mut outbox) =
        UploadDriver::start_fence(&p, &items, UploadConfig::default(), 0.0).unwrap();
    let mut t = 0.0;
    while up.done(t).is_none() && t < 30.0 {
        t += 0.01;
        let mut replies = Vec::new();
        for m in outbox.drain(..) {
            check(&m, &mut names);
            replies.extend(sim.handle(m, 0.0));
        }
        outbox.extend(up.step(&mut p, t, None));
        for r in replies {
            if mission_type(&r).is_some() {
                check(&r, &mut names);
                outbox.extend(up.step(&mut p, t, Some(&from_vehicle(r))));
            }
        }
    }
    let report = up.done(t).unwrap().unwrap();
    assert_eq!((report.items, report.resends), (items.len(), 0));
    let n = items.len();
    let mut want = vec!["MISSION_COUNT".to_string()];
    for _ in 0..n {
        want.extend([
            "MISSION_REQUEST_INT".to_string(),
            "MISSION_ITEM_INT".to_string(),
        ]);
    }
    want.push("MISSION_ACK".into());
    assert_eq!(names, want);

    names.clear();
    let (mut down, mut outbox) = FenceDownload::start(&p, UploadConfig::default(), t);
    while down.done().is_none() && t < 60.0 {
        t += 0.01;
        let mut replies = Vec::new();
        for m in outbox.drain(..) {
            check(&m, &mut names);
            replies.extend(sim.handle(m, 0.0));
        }
        for r in replies {
            if mission_type(&r).is_some() {
                check(&r, &mut names);
                outbox.extend(down.step(&mut p, t, Some(&from_vehicle(r))));
            }
        }
    }
    let read = down.done().unwrap().unwrap();
    for m in outbox.drain(..) {
        check(&m, &mut names); // the closing ACK
    }
    assert_eq!(read, items);
    let mut want = vec![
        "MISSION_REQUEST_LIST".to_string(),
        "MISSION_COUNT".to_string(),
    ];
    for _ in 0..n {
        want.extend([
            "MISSION_REQUEST_INT".to_string(),
            "MISSION_ITEM_INT".to_string(),
        ]);
    }
    want.push("MISSION_ACK".into());
    assert_eq!(names, want);
}

fn station() -> (InProcessSim, GroundStation) {
    let config = SimServerConfig {
        speedup: 10.0,
        ekf_delay_s: 1.0,
        ..SimServerConfig::at(HOME)
    };
    let sim = InProcessSim::start(config, None).unwrap();
    let ground = GroundConfig {
        speedup: 10.0,
        ..GroundConfig::default()
    };
    let mut gcs = GroundStation::connect(&sim.address(), ground).unwrap();
    gcs.wait_for_vehicle(Duration::from_secs(10), |_, _| {})
        .unwrap();
    (sim, gcs)
}

#[test]
fn the_simulator_stores_the_fence_it_is_sent_and_a_new_one_replaces_it() {
    let (sim, mut gcs) = station();
    let items = fence_items(&shapes()).unwrap();
    let report = gcs.upload_fence(&items, UploadConfig::default()).unwrap();
    assert_eq!(report.items, 8);
    // Read again, separately: the stored fence, exactly.
    assert_eq!(gcs.read_fence(UploadConfig::default()).unwrap(), items);
    let one = fence_items(&shapes()[1..2]).unwrap();
    gcs.upload_fence(&one, UploadConfig::default()).unwrap();
    assert_eq!(gcs.read_fence(UploadConfig::default()).unwrap(), one);
    let (_, notes) = sim.finish();
    assert!(notes.contains(&SimNote::FenceUploaded(8)), "{notes:?}");
    assert!(notes.contains(&SimNote::FenceUploaded(1)), "{notes:?}");
    // A fence is not a mission: none was uploaded.
    assert!(
        !notes
            .iter()
            .any(|n| matches!(n, SimNote::MissionUploaded(_)))
    );
}

#[test]
fn a_fence_the_vehicle_cannot_store_is_refused_with_its_answer() {
    let (_sim, mut gcs) = station();
    // A polygon whose vertices say 4 but are 3, then a circle: MAV_MISSION_ERROR.
    let mut items = fence_items(&shapes()[2..3]).unwrap();
    for i in &mut items {
        i.param1 = 4.0;
    }
    items.push(FenceItem {
        seq: 3,
        command: CIRCLE_EXCLUSION,
        param1: 10.0,
        lat_e7: 377_930_000,
        lon_e7: -1_223_970_000,
    });
    let e = gcs
        .upload_fence(&items, UploadConfig::default())
        .unwrap_err();
    assert!(matches!(e, GroundError::Fence(_)));
    assert_eq!(
        e.to_string(),
        "fence upload: the vehicle rejected the fence: ERROR"
    );
    // An unsupported command (the return point, 5000): MAV_MISSION_UNSUPPORTED at once.
    let bad = [FenceItem {
        seq: 0,
        command: 5000,
        param1: 0.0,
        lat_e7: 377_930_000,
        lon_e7: -1_223_970_000,
    }];
    let e = gcs.upload_fence(&bad, UploadConfig::default()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "fence upload: the vehicle rejected the fence: UNSUPPORTED"
    );
    assert_eq!(POLYGON_VERTEX_EXCLUSION, 5002);
}
