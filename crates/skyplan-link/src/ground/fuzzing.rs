//! Fuzzing and hostile-input tests only (not an API): the ground station's flight loop
//! ([`FlightLoop`] over a [`GroundProtocol`]) fed one received message at a time — what the
//! station learns, which vehicle it listens to, the position converted to the map's frame, the
//! executor fed, its commands built — without a socket or a clock.

use super::*;
use crate::Received;
use skyplan_flight::executor::{ExecutorConfig, MissionExecutor};

/// A ground station flying a short GUIDED route, driven one message at a time.
pub struct GroundHarness {
    protocol: GroundProtocol,
    flight: FlightLoop,
    executor: MissionExecutor,
    now_s: f64,
    sent: usize,
}

impl GroundHarness {
    /// A station at the FCND home with its executor ready.
    pub fn new() -> Result<Self, String> {
        let home = Lla {
            lat_deg: 37.79248,
            lon_deg: -122.39745,
            alt_m: 0.0,
        };
        let frame = LocalFrame::new(home).map_err(|e| e.to_string())?;
        let targets = [
            Target {
                north_m: 0.0,
                east_m: 0.0,
                alt_m: 5.0,
                heading_rad: 0.0,
            },
            Target {
                north_m: 30.0,
                east_m: 20.0,
                alt_m: 5.0,
                heading_rad: 0.5,
            },
        ];
        let executor =
            MissionExecutor::new(&targets, ExecutorConfig::default()).map_err(|e| e.to_string())?;
        let convergence_rad = grid_convergence_rad(&frame, home).map_err(|e| e.to_string())?;
        let flight = FlightLoop::with_convergence(
            &frame,
            GroundConfig::default(),
            convergence_rad,
            None,
            0.0,
        );
        Ok(Self {
            protocol: GroundProtocol::new(),
            flight,
            executor,
            now_s: 0.0,
            sent: 0,
        })
    }

    /// One message from `system_id`/`component_id` at the station's clock, then `dt_s` wall
    /// seconds (at most 10) pass with a turn of the loop; the messages the station would send.
    pub fn handle(
        &mut self,
        system_id: u8,
        component_id: u8,
        message: MavMessage,
        dt_s: f64,
    ) -> Vec<MavMessage> {
        let r = Received {
            header: mavlink::MavHeader {
                system_id: u32::from(system_id),
                component_id,
                sequence: 0,
            },
            message,
        };
        let (p, ex) = (&mut self.protocol, &mut self.executor);
        let mut out = self.flight.step(p, ex, self.now_s, Some(&r), (None, false));
        self.now_s += dt_s.clamp(0.0, 10.0);
        out.extend(self.flight.step(p, ex, self.now_s, None, (None, false)));
        let _ = self.flight.take_updates();
        self.sent += out.len();
        out
    }

    /// The executor's last telemetry, in the map's frame (for tests).
    pub fn last_telemetry(&self) -> Option<Telemetry> {
        self.executor.last_telemetry().cloned()
    }

    /// The executor's state now (for tests).
    pub fn state(&self) -> FlightState {
        self.executor.state()
    }

    /// Messages the station has built so far.
    pub fn sent(&self) -> usize {
        self.sent
    }
}
