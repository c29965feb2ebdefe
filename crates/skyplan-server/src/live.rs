//! A flight in the live view and its recording (`fly --view/--record`, `sim --view`): the
//! planned route, the vehicle from the ground station's progress reports (or the simulator's
//! state), the obstacle sensor's latest sweep with it, and every replanned route, as
//! [`ViewEvent`]s published to a [`ViewServer`] and recorded by a [`Recorder`].

use crate::{FlightEvent, Recorder, RouteEvent, SensedEvent, ViewEvent, ViewServer};
use skyplan_flight::executor::{FlightState, Target, Telemetry};
use skyplan_flight::sensing::{ObstacleReading, ReplanEvent};
use skyplan_link::ground::Progress;
use skyplan_link::vehicle::SimStatus;
use skyplan_plan::Plan;
use std::io::{Seek, Write};

/// Where a flight's events go: a live view, a recording, both or neither.
pub struct Live<W: Write + Seek> {
    view: Option<ViewServer>,
    record: Option<Recorder<W>>,
    /// The latest sensor reading not yet published.
    reading: Option<ObstacleReading>,
}

impl<W: Write + Seek> Default for Live<W> {
    fn default() -> Self {
        Self::new(None, None)
    }
}

impl<W: Write + Seek> Live<W> {
    /// Publishes to `view` and records to `record`.
    pub fn new(view: Option<ViewServer>, record: Option<Recorder<W>>) -> Self {
        Live {
            view,
            record,
            reading: None,
        }
    }

    fn send(&mut self, event: &ViewEvent, time_s: f64) {
        if let Some(view) = &self.view {
            view.publish(event);
        }
        if let Some(recorder) = &mut self.record
            && recorder.record(event, time_s).is_err()
        {
            // A failed write ends the recording; the flight goes on.
            self.record = None;
        }
    }

    /// The planned route.
    pub fn route(&mut self, plan: &Plan, reason: &str) {
        let event = ViewEvent::Route(RouteEvent {
            reason: reason.to_string(),
            planner: plan.planner.to_string(),
            waypoints: plan.points_nea(),
            trajectory: crate::events::TrajectoryEvent::of(plan),
        });
        self.send(&event, 0.0);
    }

    /// A sensor reading: kept, and published with the next progress report.
    pub fn reading(&mut self, r: ObstacleReading) {
        self.reading = Some(r);
    }

    /// A route replaced in flight.
    pub fn replanned(&mut self, time_s: f64, targets: &[Target], event: &ReplanEvent) {
        let route = ViewEvent::Route(RouteEvent {
            reason: format!("replan: {}", event.reason),
            planner: event.planner.clone(),
            waypoints: targets
                .iter()
                .map(|t| [t.north_m, t.east_m, t.alt_m])
                .collect(),
            trajectory: None,
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

    /// The vehicle, from a progress report (with the sensor's latest reading).
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
    pub fn last(&mut self, time_s: f64, state: FlightState, telemetry: Option<&Telemetry>) {
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

    /// Ends: a live view keeps serving for a moment so that open pages see the end of the
    /// flight; the recorder is returned to be finished, unless a write had failed.
    pub fn finish(self) -> Option<Recorder<W>> {
        if self.view.is_some() {
            std::thread::sleep(std::time::Duration::from_secs(2));
        }
        self.record
    }
}
