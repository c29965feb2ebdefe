//! The simulated vehicle's side of the protocol without I/O: a state machine fed the wall clock
//! (seconds since the simulator started) and the messages received, returning the messages to
//! send and the notes to tell. [`SimServer`](super::SimServer) only accepts connections and
//! moves the messages; the fuzz harness drives this as it is.

use super::{
    GroundStrike, Proximity, SENSOR_PERIOD_S, Side, SimNote, SimReport, SimServerConfig, SimStatus,
    Streams, Upload, handle_message, heartbeat_of, request_int,
};
use crate::obstacle::{distance_sensors, obstacle_distance};
use mavlink::dialects::common::*;
use skyplan_flight::collision::{BoxWorld, TrackCheck, true_world};
use skyplan_flight::flat_earth::FlatEarth;
use skyplan_flight::sensing::SectorRange;
use skyplan_flight::sensor::{RangeSensor, SECTORS};
use skyplan_flight::sim::{SimEvent, SimMode, SimState, SimVehicle};
use skyplan_frames::{Lla, LocalFrame};

/// How high above a roof a vehicle stands on it, metres (its skids: a touch of the roof is not
/// a collision).
const ROOF_STAND_M: f64 = 0.05;

/// The simulated multicopter behind MAVLink, without a socket or a clock.
pub struct SimProtocol {
    cfg: SimServerConfig,
    earth: FlatEarth,
    map_frame: LocalFrame,
    /// The true world: the map's boxes and the hidden ones (their indices follow the map's).
    truth: Option<BoxWorld>,
    map_boxes: usize,
    map_features: Vec<usize>,
    sensor: RangeSensor,
    /// Sector 0 is true north; the map's boxes are in its grid-north frame.
    convergence_rad: f64,
    speedup: f64,
    step_s: f64,
    vehicle: SimVehicle,
    side: Side,
    upload: Option<Upload>,
    track: TrackCheck,
    sweeps: Vec<(f64, Vec<SectorRange>)>,
    next_sweep_s: f64,
    status: SimStatus,
    last_hb_sim_s: f64,
    last_hb_wall_s: f64,
    last_gcs_s: f64,
    dropped: bool,
    restored: bool,
    collided: bool,
    failsafe_done: bool,
    max_alt_m: f64,
    distance_m: f64,
    last_mode: SimMode,
    last_armed: bool,
    notes: Vec<SimNote>,
    /// The vehicle's home ground above the map home's, metres (0 without terrain).
    home_up_m: f64,
    ground_strike: Option<GroundStrike>,
}

impl SimProtocol {
    /// A vehicle on the ground at `config.home` at wall time 0; `earth` is its own frame (about
    /// its EKF origin), `map_frame` the map's, `world` the map's boxes (the hidden ones are the
    /// config's).
    pub fn new(
        config: SimServerConfig,
        earth: FlatEarth,
        map_frame: LocalFrame,
        world: Option<&BoxWorld>,
    ) -> Self {
        let cfg = config;
        let sensor = RangeSensor {
            min_range_m: RangeSensor::default().min_range_m,
            max_range_m: cfg.sensor_range_m.clamp(0.5, 650.0),
        };
        let convergence_rad =
            crate::ground::grid_convergence_rad(&map_frame, cfg.home).unwrap_or(0.0);
        let vehicle = SimVehicle::new(cfg.sim);
        let side = Side {
            earth,
            home_alt_m: cfg.home.alt_m,
            ekf_delay_s: cfg.ekf_delay_s.max(0.0),
            streams: Streams::default(),
            last_reached: u16::MAX,
            fence: Vec::new(),
        };
        let last_mode = vehicle.state().mode;
        // Where the vehicle starts in the map's frame, and its ground's height there.
        let start_ne = map_frame
            .ned_from_lla(Lla {
                alt_m: 0.0,
                ..cfg.home
            })
            .map_or([0.0; 2], |n| [n.north_m, n.east_m]);
        let home_up_m = (cfg.terrain.as_ref())
            .and_then(|t| t.ground_m(start_ne[0], start_ne[1]).ok())
            .unwrap_or(0.0);
        Self {
            truth: true_world(world, &cfg.hidden),
            map_boxes: world.map_or(0, BoxWorld::len),
            map_features: world.map_or(Vec::new(), |w| {
                w.footprints().iter().map(|f| f.feature).collect()
            }),
            sensor,
            convergence_rad,
            speedup: cfg.speedup.max(0.1),
            step_s: cfg.step_s.clamp(0.001, 0.05),
            earth,
            map_frame,
            vehicle,
            side,
            upload: None,
            track: TrackCheck::default(),
            sweeps: Vec::new(),
            next_sweep_s: 0.0,
            status: SimStatus {
                time_s: 0.0,
                position_ned: [start_ne[0], start_ne[1], -home_up_m],
                heading_rad: 0.0,
                ground_speed_m_s: 0.0,
                mode: SimMode::Stabilize,
                armed: false,
                hits_ne: Vec::new(),
            },
            last_hb_sim_s: f64::NEG_INFINITY,
            last_hb_wall_s: -10.0,
            last_gcs_s: 0.0,
            dropped: false,
            restored: false,
            collided: false,
            failsafe_done: false,
            max_alt_m: 0.0,
            distance_m: 0.0,
            last_mode,
            last_armed: false,
            notes: Vec::new(),
            home_up_m,
            ground_strike: None,
            cfg,
        }
    }

    /// A ground station connected at `now_s` (its silence counts from now).
    pub fn connected(&mut self, now_s: f64) {
        self.last_gcs_s = now_s;
    }

    /// The ground station went away: an upload in progress is dropped.
    pub fn disconnected(&mut self) {
        self.upload = None;
    }

    /// The notes since the last call, in order.
    pub fn take_notes(&mut self) -> Vec<SimNote> {
        std::mem::take(&mut self.notes)
    }

    /// The vehicle's state now.
    pub fn state(&self) -> SimState {
        self.vehicle.state()
    }

    /// The state for a live view now.
    pub fn status(&mut self) -> SimStatus {
        let s = self.vehicle.state();
        self.status.time_s = s.time_s;
        self.status.heading_rad = s.yaw_rad - self.convergence_rad;
        self.status.ground_speed_m_s = s.velocity_ned_m_s[0].hypot(s.velocity_ned_m_s[1]);
        self.status.mode = s.mode;
        self.status.armed = s.armed;
        self.status.clone()
    }

    /// Runs the physics up to the wall clock `now_s` (times the speed-up), then the mode and
    /// arming notes, the injected link fault and the GCS failsafe: the messages the physics
    /// sends (MISSION_ITEM_REACHED; none while the link is dropped).
    pub fn advance(&mut self, now_s: f64) -> Vec<MavMessage> {
        let mut out = Vec::new();
        let target_s = now_s * self.speedup;
        while self.vehicle.state().time_s + self.step_s <= target_s {
            self.physics_step(&mut out);
        }
        let s = self.vehicle.state();
        self.changes(&s);
        self.link_fault(&s);
        // GCS failsafe.
        if let Some(fs) = self.cfg.gcs_failsafe_s
            && !self.failsafe_done
            && s.armed
            && !s.on_ground
            && s.mode == SimMode::Guided
            && now_s - self.last_gcs_s > fs
        {
            self.failsafe_done = true;
            self.vehicle.land();
            self.notes.push(SimNote::Failsafe(format!(
                "no ground station heartbeat for {fs:.1} s: LAND"
            )));
        }
        out
    }

    /// One physics step: events, distance, the sensor's sweep when due, the track's check.
    fn physics_step(&mut self, out: &mut Vec<MavMessage>) {
        let before = self.vehicle.state();
        // The ground under the last position told (one step behind: 20 ms): the DEM's, or a
        // roof the vehicle is over.
        let [n, e, _] = self.status.position_ned;
        let terrain_up_m = (self.cfg.terrain.as_ref())
            .and_then(|t| t.ground_m(n, e).ok())
            .unwrap_or(0.0);
        let roof = (self.truth.as_ref()).and_then(|w| w.roof_under(self.status.position_ned));
        let roof_up_m = roof.map_or(f64::NEG_INFINITY, |(_, top_m)| top_m + ROOF_STAND_M);
        self.vehicle
            .set_ground_up_m(terrain_up_m.max(roof_up_m) - self.home_up_m);
        let on_roof = roof.filter(|_| roof_up_m > terrain_up_m).map(|(i, _)| i);
        let mut struck = false;
        for e in self.vehicle.step(self.step_s) {
            match e {
                SimEvent::MissionItemReached(seq) => {
                    self.notes.push(SimNote::MissionItemReached(seq));
                    self.side.last_reached = seq;
                    if !self.dropped {
                        out.push(MavMessage::MISSION_ITEM_REACHED(
                            MISSION_ITEM_REACHED_DATA { seq },
                        ));
                    }
                }
                SimEvent::Landed => self.notes.push(SimNote::Landed),
                SimEvent::AutoDisarmed => {}
                SimEvent::GroundStrike => struck = true,
            }
        }
        let s = self.vehicle.state();
        let down_m = s.position_ned_m[2] - self.home_up_m;
        self.max_alt_m = self.max_alt_m.max(-down_m);
        self.distance_m += (s.position_ned_m[0] - before.position_ned_m[0])
            .hypot(s.position_ned_m[1] - before.position_ned_m[1]);
        let (lat_deg, lon_deg) = self
            .earth
            .lat_lon_from_ne(s.position_ned_m[0], s.position_ned_m[1]);
        let map_ned = self.map_frame.ned_from_lla(Lla {
            lat_deg,
            lon_deg,
            alt_m: 0.0,
        });
        if let Ok(ned) = &map_ned {
            self.status.position_ned = [ned.north_m, ned.east_m, down_m];
        }
        if struck && self.ground_strike.is_none() {
            let strike = GroundStrike {
                time_s: s.time_s,
                position_ned_m: self.status.position_ned,
            };
            self.ground_strike = Some(strike);
            self.notes.push(SimNote::GroundStrike(strike));
        }
        if s.time_s >= self.next_sweep_s {
            self.next_sweep_s = s.time_s + SENSOR_PERIOD_S - 0.5 * self.step_s;
            self.sweep(s.time_s, map_ned.is_ok());
        }
        if let Some(w) = &self.truth {
            if map_ned.is_ok() {
                // Landing on a roof, or standing on it, is not coming close to it.
                let roof = on_roof.filter(|_| s.on_ground || self.vehicle.landing());
                self.track
                    .add_on(w, s.time_s, self.status.position_ned, roof);
            }
            if !self.collided
                && let Some(c) = self.track.collision()
            {
                self.collided = true;
                self.notes.push(SimNote::Collision(c));
            }
        }
    }

    /// The proximity sensor's sweep at `time_s` against the true world, kept until sent (at most
    /// 5 s of them when no one listens); `located`: the vehicle has a position in the map.
    fn sweep(&mut self, time_s: f64, located: bool) {
        let at = self.status.position_ned;
        let sweep = match (&self.truth, located) {
            (Some(w), true) => self.sensor.scan(w, at, -self.convergence_rad),
            _ => vec![SectorRange::Clear; SECTORS],
        };
        self.status.hits_ne = sweep
            .iter()
            .enumerate()
            .filter_map(|(i, r)| match r {
                SectorRange::Obstacle(d) => {
                    let b = self.sensor.increment_rad() * i as f64 - self.convergence_rad;
                    Some([at[0] + d * b.cos(), at[1] + d * b.sin()])
                }
                _ => None,
            })
            .collect();
        if self.sweeps.len() >= 50 {
            self.sweeps.remove(0);
        }
        self.sweeps.push((time_s, sweep));
    }

    /// Notes of a mode or arming change.
    fn changes(&mut self, s: &SimState) {
        if s.mode != self.last_mode {
            self.notes.push(SimNote::Mode(s.mode));
            self.last_mode = s.mode;
        }
        if s.armed != self.last_armed {
            self.notes.push(SimNote::Armed(s.armed));
            self.last_armed = s.armed;
        }
    }

    /// The injected fault: silent and deaf after `drop_link_after_s`, back after `link_gap_s`.
    fn link_fault(&mut self, s: &SimState) {
        if !self.dropped
            && !self.restored
            && let Some(after) = self.cfg.drop_link_after_s
            && s.time_s >= after
        {
            self.dropped = true;
            self.notes.push(SimNote::LinkDropped);
        }
        if self.dropped
            && !self.restored
            && let (Some(after), Some(gap)) = (self.cfg.drop_link_after_s, self.cfg.link_gap_s)
            && s.time_s >= after + gap
        {
            self.dropped = false;
            self.restored = true;
            self.notes.push(SimNote::LinkRestored);
        }
    }

    /// A message received at `now_s`: the replies (none while the link is dropped).
    pub fn handle(&mut self, now_s: f64, message: MavMessage) -> Vec<MavMessage> {
        if self.dropped {
            return Vec::new();
        }
        let notes = &mut self.notes;
        handle_message(
            (&mut self.vehicle, &mut self.side, &mut self.upload),
            (now_s, &mut self.last_gcs_s),
            message,
            &mut |n| notes.push(n),
        )
    }

    /// What the vehicle sends unasked at `now_s` (none while the link is dropped): upload
    /// re-requests, the heartbeat (each simulated and each wall second), the requested streams
    /// due and the sensor's sweeps once the EKF has a position.
    pub fn outbound(&mut self, now_s: f64) -> Vec<MavMessage> {
        let mut out = Vec::new();
        if self.dropped {
            return out;
        }
        if let Some(u) = &mut self.upload
            && now_s - u.last_request_s > 0.5
        {
            if u.retries >= 5 {
                out.push(MavMessage::MISSION_ACK(MISSION_ACK_DATA {
                    target_system: 0,
                    target_component: 0,
                    mavtype: MavMissionResult::MAV_MISSION_OPERATION_CANCELLED,
                    mission_type: u.mission_type,
                    ..Default::default()
                }));
                self.upload = None;
            } else {
                u.retries += 1;
                u.last_request_s = now_s;
                out.push(request_int(u.received() as u16, u.mission_type));
            }
        }
        let s = self.vehicle.state();
        if s.time_s - self.last_hb_sim_s >= 1.0 || now_s - self.last_hb_wall_s >= 1.0 {
            self.last_hb_sim_s = s.time_s;
            self.last_hb_wall_s = now_s;
            out.push(heartbeat_of(&s));
        }
        for id in self.side.streams.due(s.time_s) {
            out.extend(self.side.message(id, &s, self.vehicle.mission().len()));
        }
        match self.cfg.proximity {
            // Every sweep: ≥ 10 Hz of vehicle time at any speed-up.
            Proximity::ObstacleDistance => {
                for (time_s, sweep) in self.sweeps.drain(..) {
                    if self.side.position_ready(&s) {
                        let time_usec = (time_s * 1e6) as u64;
                        out.push(obstacle_distance(&sweep, &self.sensor, time_usec));
                    }
                }
            }
            // The latest sweep, at the period asked for, as ArduCopter's eight sectors.
            Proximity::DistanceSensor => {
                let latest = self.sweeps.drain(..).next_back();
                let ready = self.side.position_ready(&s);
                let streams = &mut self.side.streams;
                if let (Some((time_s, sweep)), Some(period_s)) = (latest, streams.distance_sensor)
                    && s.time_s - streams.distance_sensor_last_s >= period_s
                    && ready
                {
                    streams.distance_sensor_last_s = s.time_s;
                    // The sweep is on true north, as the vehicle's own yaw.
                    let time_boot_ms = (time_s * 1000.0) as u32;
                    out.extend(distance_sensors(
                        &sweep,
                        &self.sensor,
                        s.yaw_rad,
                        time_boot_ms,
                    ));
                }
            }
        }
        out
    }

    /// The last notes (a mode or arming change made in the last turn: the ground station may
    /// stop the simulator as soon as it sees it in a heartbeat).
    pub fn finish(&mut self) -> Vec<SimNote> {
        let s = self.vehicle.state();
        self.changes(&s);
        self.take_notes()
    }

    /// The simulator's account at wall time `now_s`.
    pub fn report(self, now_s: f64) -> SimReport {
        SimReport {
            sim_time_s: self.vehicle.state().time_s,
            wall_time_s: now_s,
            final_state: self.vehicle.state(),
            track: self.track,
            max_alt_m: self.max_alt_m,
            distance_m: self.distance_m,
            map_boxes: self.map_boxes,
            map_features: self.map_features,
            hidden_boxes: self.cfg.hidden.len(),
            ground_strike: self.ground_strike,
        }
    }
}
