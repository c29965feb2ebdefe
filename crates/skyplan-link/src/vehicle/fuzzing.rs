//! Fuzzing and hostile-input tests only (not an API): the simulator's protocol ([`SimProtocol`])
//! fed one message at a time, with time passing between, without a socket or a clock.

use super::*;

/// A simulated vehicle at the FCND home, driven one message at a time.
pub struct SimHarness {
    sim: SimProtocol,
    now_s: f64,
}

impl Default for SimHarness {
    fn default() -> Self {
        Self::new()
    }
}

impl SimHarness {
    /// A vehicle on the ground at the FCND home, EKF ready after 1 simulated second, real time,
    /// no GCS failsafe.
    pub fn new() -> Self {
        let home = Lla {
            lat_deg: 37.79248,
            lon_deg: -122.39745,
            alt_m: 0.0,
        };
        let config = SimServerConfig {
            ekf_delay_s: 1.0,
            gcs_failsafe_s: None,
            ..SimServerConfig::at(home)
        };
        let earth = FlatEarth::new(home.lat_deg, home.lon_deg);
        // The FCND home is a valid geodetic point: its frame exists.
        let frame = LocalFrame::new(home).unwrap_or_else(|_| unreachable!("the FCND home"));
        Self {
            sim: SimProtocol::new(config, earth, frame, None),
            now_s: 0.0,
        }
    }

    /// One message; the replies, then `dt_s` seconds (at most 10) and what the vehicle sends
    /// unasked by then.
    pub fn handle(&mut self, message: MavMessage, dt_s: f64) -> Vec<MavMessage> {
        let mut out = self.sim.handle(self.now_s, message);
        self.now_s += dt_s.clamp(0.0, 10.0);
        out.extend(self.sim.advance(self.now_s));
        out.extend(self.sim.outbound(self.now_s));
        let _ = self.sim.take_notes();
        out
    }

    /// The vehicle's state now (for tests).
    pub fn state(&self) -> SimState {
        self.sim.state()
    }
}
