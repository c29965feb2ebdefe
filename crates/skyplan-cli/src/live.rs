//! `fly --view ADDR` and `fly --record FILE.mcap`: the live view (skyplan-server's page) and the
//! MCAP recording of a flight — the planned route, then the vehicle at 5 updates per second,
//! the obstacle sensor's latest sweep with it, and every replanned route. `sim --view ADDR`
//! publishes the simulator's state the same way ([`Live::sim_status`]).

use crate::exit::{Classify, Kind, Result, bad_input, runtime};
use crate::files::{Target, output_target};
use skyplan_flight::executor::Target as Waypoint;
use skyplan_flight::sensing::{ObstacleReading, ReplanEvent};
use skyplan_link::ground::Progress;
use skyplan_link::vehicle::SimStatus;
use skyplan_plan::{Plan, World};
use skyplan_server::{FlightEvent, Recorder, RouteEvent, SensedEvent, ViewEvent, ViewServer};
use std::path::{Path, PathBuf};

/// Where a flight's events go.
#[derive(Default)]
pub struct Live {
    view: Option<ViewServer>,
    record: Option<(PathBuf, PathBuf, Recorder<std::fs::File>)>,
    /// The latest sensor reading not yet published.
    reading: Option<ObstacleReading>,
}

impl Live {
    /// Starts the view server and opens the recording (a temporary file beside the target,
    /// renamed when the flight ends), before anything flies.
    pub fn start(world: &World, view: Option<&str>, record: Option<&Path>) -> Result<Self> {
        let mut live = Live::default();
        if let Some(addr) = view {
            let server = ViewServer::start(world.clone(), addr)
                .map_err(|e| bad_input(format!("--view {addr}: {e}")))?;
            println!("view       http://{}/ (the live view)", server.addr());
            live.view = Some(server);
        }
        if let Some(path) = record {
            let Target::File(target) = output_target("--record", path)? else {
                return Err(bad_input(
                    "--record: a recording needs a file, not standard output",
                ));
            };
            let tmp = target.with_extension(format!("mcap.{}.tmp", std::process::id()));
            let file = std::fs::File::create(&tmp)
                .map_err(|e| runtime(format!("--record {}: {e}", tmp.display())))?;
            let recorder =
                Recorder::new(file, world).map_err(|e| runtime(format!("--record: {e}")))?;
            live.record = Some((target, tmp, recorder));
        }
        Ok(live)
    }

    fn send(&mut self, event: &ViewEvent, time_s: f64) {
        if let Some(view) = &self.view {
            view.publish(event);
        }
        if let Some((_, _, recorder)) = &mut self.record
            && recorder.record(event, time_s).is_err()
        {
            // A failed write ends the recording; the flight goes on (reported at the end).
            self.record = None;
        }
    }

    /// The planned route.
    pub fn route(&mut self, plan: &Plan, reason: &str) {
        let event = ViewEvent::Route(RouteEvent {
            reason: reason.to_string(),
            planner: plan.planner.to_string(),
            waypoints: plan.points_nea(),
        });
        self.send(&event, 0.0);
    }

    /// A sensor reading: kept, and published with the next progress report (5 Hz).
    pub fn reading(&mut self, r: ObstacleReading) {
        self.reading = Some(r);
    }

    /// A route replaced in flight.
    pub fn replanned(&mut self, time_s: f64, targets: &[Waypoint], event: &ReplanEvent) {
        let route = ViewEvent::Route(RouteEvent {
            reason: format!("replan: {}", event.reason),
            planner: event.planner.clone(),
            waypoints: targets
                .iter()
                .map(|t| [t.north_m, t.east_m, t.alt_m])
                .collect(),
        });
        self.send(&route, time_s);
    }

    /// The simulator's state (`sim --view`): the vehicle and what its sensor sees.
    pub fn sim_status(&mut self, s: &SimStatus) {
        let flight = ViewEvent::Flight(FlightEvent {
            time_s: s.time_s,
            north_m: s.position_ned[0],
            east_m: s.position_ned[1],
            alt_m: 0.0 - s.position_ned[2], // never -0.0
            heading_deg: s.heading_rad.to_degrees(),
            speed_m_s: s.ground_speed_m_s,
            state: s.mode.to_string(),
            waypoint_index: None,
            armed: s.armed,
        });
        self.send(&flight, s.time_s);
        let sensed = ViewEvent::Sensed(SensedEvent {
            time_s: s.time_s,
            vehicle_ne: [s.position_ned[0], s.position_ned[1]],
            alt_m: 0.0 - s.position_ned[2], // never -0.0
            hits_ne: s.hits_ne.clone(),
        });
        self.send(&sensed, s.time_s);
    }

    /// The vehicle, from a progress report.
    pub fn progress(&mut self, p: &Progress) {
        if let Some(r) = self.reading.take() {
            let sensed = ViewEvent::Sensed(SensedEvent {
                time_s: r.time_s,
                vehicle_ne: [r.position_ned[0], r.position_ned[1]],
                alt_m: -r.position_ned[2],
                hits_ne: r.hits_ne().collect(),
            });
            self.send(&sensed, r.time_s);
        }
        let Some(t) = p.telemetry else {
            return;
        };
        let event = ViewEvent::Flight(FlightEvent {
            time_s: p.time_s,
            north_m: t.north_m,
            east_m: t.east_m,
            alt_m: t.alt_m(),
            heading_deg: t.yaw_rad.to_degrees(),
            speed_m_s: t.ground_speed_m_s(),
            state: p.state.name().to_string(),
            waypoint_index: (p.reached < p.waypoints).then_some(p.reached),
            armed: t.armed,
        });
        self.send(&event, p.time_s);
    }

    /// The vehicle at the end of the flight (the last state, often MANUAL after the disarm, can
    /// fall between two progress reports).
    pub fn last(
        &mut self,
        time_s: f64,
        state: skyplan_flight::executor::FlightState,
        telemetry: Option<&skyplan_flight::executor::Telemetry>,
    ) {
        let p = Progress {
            time_s,
            state,
            reached: 0,
            waypoints: 0,
            distance_left_m: 0.0,
            telemetry: telemetry.copied(),
            readings: 0,
            replans: 0,
        };
        self.progress(&p);
    }

    /// Closes the recording (renamed into place) and says where it is; a live view keeps
    /// serving for a moment so that open pages see the end of the flight.
    pub fn finish(self) -> Result<()> {
        if self.view.is_some() {
            std::thread::sleep(std::time::Duration::from_secs(2));
        }
        if let Some((target, tmp, recorder)) = self.record {
            recorder
                .finish()
                .map_err(|e| runtime(format!("--record: {e}")))?;
            std::fs::rename(&tmp, &target).or_exit(Kind::Runtime)?;
            println!("wrote      flight recording {} (MCAP)", target.display());
        }
        Ok(())
    }
}
