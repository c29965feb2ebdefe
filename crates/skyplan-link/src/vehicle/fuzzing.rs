//! Fuzzing and hostile-input tests only (not an API): the simulator's command handling
//! (`handle_message`) and its telemetry streams, without a socket.

use super::*;

/// A simulated vehicle at the FCND home, driven one message at a time.
pub struct SimHarness {
    vehicle: SimVehicle,
    side: Side,
    upload: Option<Upload>,
    last_gcs: Instant,
}

impl Default for SimHarness {
    fn default() -> Self {
        Self::new()
    }
}

impl SimHarness {
    /// A vehicle on the ground at the FCND home, EKF ready after 1 simulated second.
    pub fn new() -> Self {
        let home = Lla {
            lat_deg: 37.79248,
            lon_deg: -122.39745,
            alt_m: 0.0,
        };
        Self {
            vehicle: SimVehicle::new(SimConfig::default()),
            side: Side {
                earth: FlatEarth::new(home.lat_deg, home.lon_deg),
                home_alt_m: home.alt_m,
                ekf_delay_s: 1.0,
                streams: Streams::default(),
                last_reached: u16::MAX,
            },
            upload: None,
            last_gcs: Instant::now(),
        }
    }

    /// One message; the replies, then `dt_s` simulated seconds (at most 10) and the streamed
    /// messages due.
    pub fn handle(&mut self, message: MavMessage, dt_s: f64) -> Vec<MavMessage> {
        let mut out = handle_message(
            &mut self.vehicle,
            &mut self.side,
            &mut self.upload,
            &mut self.last_gcs,
            message,
            &mut |_| {},
        );
        let mut left = dt_s.clamp(0.0, 10.0);
        while left > 0.0 {
            let step = left.min(0.02);
            for e in self.vehicle.step(step) {
                if let skyplan_flight::sim::SimEvent::MissionItemReached(seq) = e {
                    self.side.last_reached = seq;
                }
            }
            left -= step;
        }
        let s = self.vehicle.state();
        out.push(heartbeat_of(&s));
        for id in self.side.streams.due(s.time_s) {
            out.extend(self.side.message(id, &s, self.vehicle.mission().len()));
        }
        out
    }

    /// The vehicle's state now (for tests).
    pub fn state(&self) -> SimState {
        self.vehicle.state()
    }
}
