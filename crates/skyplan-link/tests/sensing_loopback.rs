//! The simulator's sensor and the ground station's watcher over a real loopback TCP socket: a
//! hidden box seen by OBSTACLE_DISTANCE, a route replaced in flight, a hidden box on the route
//! hit in the true world.

use skyplan_flight::executor::{ExecutorConfig, FlightState, MissionExecutor, Outcome, Target};
use skyplan_flight::sensing::{
    ObstacleReading, ReplanEvent, RouteDecision, RouteWatcher, SectorRange,
};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_link::ground::{FlightSummary, GroundConfig, GroundStation, Update};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::vehicle::{SimReport, SimServerConfig};
use skyplan_map::colliders::ObstacleBox;
use std::sync::{Arc, Mutex};
use std::time::Duration;

const HOME: Lla = Lla {
    lat_deg: 37.792480,
    lon_deg: -122.397450,
    alt_m: 0.0,
};

fn wp(n: f64, e: f64, h: f64) -> Target {
    Target {
        north_m: n,
        east_m: e,
        alt_m: 5.0,
        heading_rad: h.to_radians(),
    }
}

fn tower(north_m: f64, east_m: f64) -> ObstacleBox {
    ObstacleBox {
        north_m,
        east_m,
        up_m: 10.0,
        half_north_m: 2.0,
        half_east_m: 2.0,
        half_up_m: 10.0,
    }
}

/// Replaces the route once, with `detour`, at the first reading; keeps it afterwards.
struct Once {
    detour: Vec<Target>,
    seen_routes: Arc<Mutex<Vec<Vec<Target>>>>,
}

impl RouteWatcher for Once {
    fn on_reading(&mut self, reading: &ObstacleReading, route: &[Target]) -> RouteDecision {
        let mut seen = self.seen_routes.lock().unwrap();
        seen.push(route.to_vec());
        if seen.len() > 1 {
            return RouteDecision::Keep;
        }
        RouteDecision::Replace {
            targets: self.detour.clone(),
            event: ReplanEvent {
                time_s: reading.time_s,
                position_ned: reading.position_ned,
                reason: "test".into(),
                planner: "test".into(),
                latency_ms: 0.0,
                cpu_ms: None,
                expansions: 0,
                route_length_m: 25.0,
                learned_cells: 0,
            },
        }
    }
}

struct Run {
    ex: MissionExecutor,
    summary: FlightSummary,
    report: SimReport,
    readings: Vec<(FlightState, ObstacleReading)>,
}

fn fly(hidden: Vec<ObstacleBox>, route: &[Target], watcher: Option<Once>) -> Run {
    let config = SimServerConfig {
        speedup: 20.0,
        hidden,
        ..SimServerConfig::at(HOME)
    };
    let sim = InProcessSim::start(config, None).unwrap();
    let address = sim.address();
    let ground = GroundConfig {
        speedup: 20.0,
        timeout_s: Some(60.0),
        ..GroundConfig::default()
    };
    let mut gcs = GroundStation::connect(&address, ground).unwrap();
    gcs.wait_for_vehicle(Duration::from_secs(10), |_, _| {})
        .unwrap();
    if let Some(w) = watcher {
        gcs.set_watcher(Box::new(w));
    }
    let mut ex = MissionExecutor::new(route, ExecutorConfig::default()).unwrap();
    let frame = LocalFrame::new(HOME).unwrap();
    let mut readings = Vec::new();
    let mut state = FlightState::Manual;
    let summary = gcs
        .fly(&mut ex, &frame, |u| match u {
            Update::Progress(p) => state = p.state,
            Update::Reading(r) => readings.push((state, r)),
            _ => {}
        })
        .unwrap();
    let report = sim.finish().0.unwrap();
    Run {
        ex,
        summary,
        report,
        readings,
    }
}

#[test]
fn the_sensor_sees_a_hidden_box_and_the_watcher_swaps_the_route_in_flight() {
    // A hidden tower whose west face is 10 m east of home, off the route (north, then east).
    let route = [wp(0.0, 0.0, 0.0), wp(20.0, 0.0, 0.0), wp(20.0, 8.0, 90.0)];
    let detour = vec![wp(10.0, -5.0, 0.0), wp(20.0, -5.0, 0.0)];
    let seen = Arc::new(Mutex::new(Vec::new()));
    let run = fly(
        vec![tower(0.0, 12.0)],
        &route,
        Some(Once {
            detour: detour.clone(),
            seen_routes: Arc::clone(&seen),
        }),
    );
    assert_eq!(run.ex.outcome(), Some(&Outcome::Completed));
    // On the ground at home: east (sector 18) reads 10 m to the centimetre (the sector is
    // 0.37° off grid east: 10 / cos 0.37° = 10.0002 m), west (sector 54) is clear.
    let (_, first) = run
        .readings
        .iter()
        .find(|(s, _)| matches!(s, FlightState::Manual | FlightState::Arming))
        .expect("a reading on the ground");
    assert!(first.position_ned[0].abs() < 0.05 && first.position_ned[1].abs() < 0.05);
    let SectorRange::Obstacle(d) = first.ranges[18] else {
        panic!("{:?}", first.ranges[18]);
    };
    assert!((d - 10.0).abs() < 0.03, "{d}");
    assert_eq!(first.ranges[54], SectorRange::Clear);
    assert_eq!(first.ranges[0], SectorRange::Clear);
    // ≥ 10 Hz of vehicle time.
    let rate_hz = run.summary.readings as f64 / run.summary.time_s;
    assert!(rate_hz >= 9.0, "{rate_hz} Hz");
    // The watcher saw the original route still to fly (the take-off point is reached on
    // entering WAYPOINT), then the detour; it was flown.
    let seen = seen.lock().unwrap();
    assert_eq!(seen[0][..], route[1..]);
    assert_eq!(seen.last().unwrap().last(), detour.last());
    assert_eq!(run.summary.replans.len(), 1);
    let t = run.ex.last_telemetry().unwrap();
    assert!(
        (t.north_m - 20.0).abs() < 1.5 && (t.east_m + 5.0).abs() < 1.5,
        "{t:?}"
    );
    assert!(run.report.track.collision().is_none());
}

#[test]
fn a_hidden_box_on_the_route_is_a_collision_in_the_true_world() {
    let route = [wp(0.0, 0.0, 0.0), wp(20.0, 0.0, 0.0)];
    let run = fly(vec![tower(10.0, 0.0)], &route, None);
    let c = run.report.track.collision().expect("a collision");
    assert_eq!(c.box_index, 0);
    assert!((c.point_ned_m[0] - 8.0).abs() < 0.5, "{c:?}");
}
