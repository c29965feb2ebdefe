//! `fly --view ADDR` and `fly --record FILE.mcap`: the live view (skyplan-server's page) and the
//! MCAP recording of a flight — the planned route, then the vehicle at 5 updates per second.

use crate::exit::{Classify, Kind, Result, bad_input, runtime};
use crate::files::{Target, output_target};
use skyplan_link::ground::Progress;
use skyplan_plan::{Plan, World};
use skyplan_server::{FlightEvent, Recorder, RouteEvent, ViewEvent, ViewServer};
use std::path::{Path, PathBuf};

/// Where a flight's events go.
#[derive(Default)]
pub struct Live {
    view: Option<ViewServer>,
    record: Option<(PathBuf, PathBuf, Recorder<std::fs::File>)>,
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

    /// The vehicle, from a progress report.
    pub fn progress(&mut self, p: &Progress) {
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
