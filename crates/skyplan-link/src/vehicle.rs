//! The vehicle side: `skyplan sim`'s simulated multicopter behind a MAVLink server.
//!
//! It behaves like ArduCopter where it matters to a ground station: system 1, component 1,
//! `MAV_AUTOPILOT_ARDUPILOTMEGA` with ArduCopter's custom mode numbers; answers COMMAND_LONG
//! (ARM_DISARM, NAV_TAKEOFF, NAV_LAND, DO_SET_MODE, MISSION_START, SET_MESSAGE_INTERVAL), SET_MODE,
//! SET_POSITION_TARGET_LOCAL_NED and _GLOBAL_INT (position, optional yaw), the mission upload
//! (MISSION_COUNT → MISSION_REQUEST_INT → MISSION_ITEM_INT / MISSION_ITEM → MISSION_ACK; item 0
//! is the home, as on ArduPilot) and MISSION_CLEAR_ALL; the fence (`mission_type` FENCE: the
//! same upload, each item a fence vertex or circle, the whole checked as ArduPilot's fence
//! loader does — MAV_MISSION_UNSUPPORTED for another command, MAV_MISSION_ERROR for a polygon
//! whose vertices do not add up — then stored, not enforced, and read back with
//! MISSION_REQUEST_LIST → MISSION_COUNT → MISSION_REQUEST_INT → MISSION_ITEM_INT in
//! `MAV_FRAME_GLOBAL_INT`). Position targets may carry a velocity and
//! an acceleration (their `type_mask` bits clear), followed as feed-forward
//! ([`skyplan_flight::sim::SimVehicle::set_target`]); unlike ArduCopter, a stamped target
//! (`time_boot_ms`) is brought to the vehicle's time first ([`stamped`]).
//! Like ArduCopter, it sends only HEARTBEAT (1 Hz), command
//! and mission answers, MISSION_ITEM_REACHED and STATUSTEXT (the reason of every refusal)
//! unrequested: LOCAL_POSITION_NED, GLOBAL_POSITION_INT, ATTITUDE, EXTENDED_SYS_STATE,
//! MISSION_CURRENT and GPS_GLOBAL_ORIGIN stream only once asked for with SET_MESSAGE_INTERVAL or
//! REQUEST_DATA_STREAM. Its EKF needs [`SimServerConfig::ekf_delay_s`] after boot: the origin
//! (GPS_GLOBAL_ORIGIN) is set half-way, positions are sent and arming is allowed only after it.
//! Rates are in simulated time; with `speedup` K the simulation runs K× faster than the wall
//! clock, and heartbeats are also sent at least once a wall-clock second.
//!
//! Positions are ArduPilot's: LOCAL_POSITION_NED and the vehicle's dynamics are in the
//! true-north flat-earth frame about its EKF origin (the home, [`FlatEarth`]), and its latitude
//! and longitude come from that frame as ArduPilot's `Location::offset` computes them — not from
//! skyplan's UTM map frame, so a ground station that mixes the two is caught.
//!
//! Like ArduCopter's GCS failsafe, a flying vehicle in GUIDED lands when it has heard no ground
//! station heartbeat for [`SimServerConfig::gcs_failsafe_s`] wall-clock seconds.
//!
//! **The true world and the sensor.** The simulated world is the map's boxes plus
//! [`SimServerConfig::hidden`] ones the planner does not know; the flown track is checked
//! against both. Once its EKF has a position, the vehicle sends `OBSTACLE_DISTANCE`
//! unrequested, as a proximity sensor does, every 0.1 s of vehicle time: 72 sectors of 5°,
//! `MAV_FRAME_LOCAL_NED` (sector 0 centred on true north), ranges up to
//! [`SimServerConfig::sensor_range_m`], each a ray cast at the vehicle's altitude against the
//! true world ([`skyplan_flight::sensor`]; see [`crate::obstacle`] for the encoding).
//!
//! **Roofs.** Over a building, its roof is the ground: a goal on a roof is landed on (a few
//! centimetres above it), and the roof it stands on is left out of the closest approach.
//!
//! **Terrain.** With [`SimServerConfig::terrain`] the ground under the vehicle follows the DEM:
//! the vehicle's home stands on it (its relative altitudes are above that ground, as a real
//! autopilot's are above where it armed), a landing stops on the ground where it is, and flying
//! into the ground anywhere else is a [`GroundStrike`]. Positions told in the map's frame
//! ([`SimStatus`], the track's check) are above the map's home, so over terrain they differ
//! from the vehicle's own by the height of its home's ground above the map home's.

use crate::streams::{STREAMS, in_group};
use crate::{Address, Link, LinkError};
use mavlink::MessageData;
use mavlink::dialects::common::*;
use skyplan_flight::collision::{BoxWorld, Collision, TrackCheck};
use skyplan_flight::fence::FenceItem;
use skyplan_flight::flat_earth::FlatEarth;
use skyplan_flight::sim::{SimConfig, SimMissionItem, SimMode, SimState, SimTarget, SimVehicle};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_map::colliders::ObstacleBox;
use skyplan_map::terrain::Terrain;
use std::net::{SocketAddr, TcpListener};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

#[doc(hidden)]
pub mod fuzzing;
pub mod protocol;

pub use protocol::SimProtocol;

/// Simulated seconds after boot until the simulated EKF has a position, by default.
pub const DEFAULT_EKF_DELAY_S: f64 = 5.0;

/// The simulated vehicle's MAVLink system id.
pub const SYSTEM_ID: u8 = 1;
/// Its component id (the autopilot).
pub const COMPONENT_ID: u8 = 1;

/// How the simulator runs.
#[derive(Debug, Clone)]
pub struct SimServerConfig {
    /// Where the vehicle starts (home), also its EKF origin: the origin of LOCAL_POSITION_NED.
    pub home: Lla,
    /// The home of the map whose boxes the flown track is checked against (`None`: `home`).
    pub map_home: Option<Lla>,
    /// Simulated seconds after boot until the EKF has a position (GPS_GLOBAL_ORIGIN at half of
    /// it). ArduCopter SITL needs ~40 s at 1×.
    pub ekf_delay_s: f64,
    /// Vehicle limits.
    pub sim: SimConfig,
    /// Simulated seconds per wall-clock second (≥ 0.1).
    pub speedup: f64,
    /// Fault injection: after this much simulated time the vehicle goes silent and deaf.
    pub drop_link_after_s: Option<f64>,
    /// With `drop_link_after_s`: the link comes back after this many simulated seconds of
    /// silence (`None`: never).
    pub link_gap_s: Option<f64>,
    /// Land when flying in GUIDED without a ground station heartbeat for this many wall seconds.
    pub gcs_failsafe_s: Option<f64>,
    /// Physics step, simulated seconds.
    pub step_s: f64,
    /// Boxes in the simulated world that the planner's map does not have (the map's frame:
    /// metres about the map's home). The collision check and the sensor see them.
    pub hidden: Vec<ObstacleBox>,
    /// Range of the simulated obstacle sensor, metres (`OBSTACLE_DISTANCE`'s `max_distance`).
    pub sensor_range_m: f64,
    /// How the sensor's sweeps reach the ground station.
    pub proximity: Proximity,
    /// The map's terrain (`None`: flat ground at the map's home): the ground under the
    /// vehicle, which stops it and which it may strike; the vehicle's home stands on it, and
    /// `home.alt_m` should be the ground's height above mean sea level there.
    pub terrain: Option<Arc<Terrain>>,
}

/// How the simulated vehicle reports its proximity sensor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Proximity {
    /// `OBSTACLE_DISTANCE` (72 sectors of 5°, true north), unrequested, every sweep: as a
    /// companion computer's sensor does.
    #[default]
    ObstacleDistance,
    /// Eight `DISTANCE_SENSOR`s per sweep (the nearest obstacle in each 45° wedge about the nose),
    /// only once asked for with SET_MESSAGE_INTERVAL: as ArduCopter's proximity library does.
    DistanceSensor,
}

/// The simulated sensor's range by default, metres.
pub const DEFAULT_SENSOR_RANGE_M: f64 = 30.0;

/// Vehicle seconds between two `OBSTACLE_DISTANCE` sweeps (10 Hz).
pub const SENSOR_PERIOD_S: f64 = 0.1;

/// The simulator's state for a live view, reported every [`SimServer::run_with_state`] period.
#[derive(Debug, Clone, PartialEq)]
pub struct SimStatus {
    /// Simulated seconds since boot.
    pub time_s: f64,
    /// Position in the map's frame: metres north, east, down of the map's home.
    pub position_ned: [f64; 3],
    /// Heading, radians clockwise from the map's grid north.
    pub heading_rad: f64,
    /// Horizontal speed, m/s.
    pub ground_speed_m_s: f64,
    /// Flight mode.
    pub mode: SimMode,
    /// Motors armed.
    pub armed: bool,
    /// The points of the latest sweep where the sensor saw an obstacle (map frame, north/east).
    pub hits_ne: Vec<[f64; 2]>,
}

impl SimServerConfig {
    /// Defaults at a home: real time, no fault, 5 s GCS failsafe, 20 ms steps, EKF ready 5 s
    /// after boot.
    pub fn at(home: Lla) -> Self {
        Self {
            home,
            map_home: None,
            ekf_delay_s: DEFAULT_EKF_DELAY_S,
            sim: SimConfig::default(),
            speedup: 1.0,
            drop_link_after_s: None,
            link_gap_s: None,
            gcs_failsafe_s: Some(5.0),
            step_s: 0.02,
            hidden: Vec::new(),
            sensor_range_m: DEFAULT_SENSOR_RANGE_M,
            proximity: Proximity::default(),
            terrain: None,
        }
    }
}

/// What the simulator reports while it runs (the CLI prints these).
#[derive(Debug, Clone, PartialEq)]
pub enum SimNote {
    /// A ground station connected.
    Connected(String),
    /// The connection closed.
    Disconnected(String),
    /// Mode changed.
    Mode(SimMode),
    /// Armed (`true`) or disarmed.
    Armed(bool),
    /// A command was refused, with the reason sent as STATUSTEXT.
    Refused(String),
    /// Taking off to this altitude.
    Takeoff(f64),
    /// Touched down.
    Landed,
    /// A mission of this many items was uploaded.
    MissionUploaded(usize),
    /// A fence of this many items was uploaded (`mission_type` FENCE).
    FenceUploaded(usize),
    /// A mission item was reached.
    MissionItemReached(u16),
    /// The flown track hit an obstacle.
    Collision(Collision),
    /// The vehicle flew into the ground outside a landing.
    GroundStrike(GroundStrike),
    /// The GCS failsafe triggered a landing.
    Failsafe(String),
    /// The injected link fault: the vehicle stopped talking.
    LinkDropped,
    /// The injected link fault is over: the vehicle talks and listens again.
    LinkRestored,
}

/// The simulator's account at the end.
#[derive(Debug, Clone)]
pub struct SimReport {
    /// Simulated time, seconds.
    pub sim_time_s: f64,
    /// Wall-clock time, seconds.
    pub wall_time_s: f64,
    /// The vehicle at the end.
    pub final_state: SimState,
    /// The track's collision check (empty if no map was given).
    pub track: TrackCheck,
    /// Highest altitude above home, metres.
    pub max_alt_m: f64,
    /// Horizontal distance flown, metres.
    pub distance_m: f64,
    /// Obstacles of the map's world, footprints and boxes (obstacle numbers below this are
    /// the map's).
    pub map_boxes: usize,
    /// The source feature of each of the map's building footprints (the first obstacle
    /// numbers), empty on a map of boxes.
    pub map_features: Vec<usize>,
    /// Hidden boxes (obstacle numbers from `map_boxes` on), absent from the planner's map.
    pub hidden_boxes: usize,
    /// The first time the vehicle flew into the ground outside a landing (over terrain).
    pub ground_strike: Option<GroundStrike>,
}

/// Where and when the vehicle flew into the ground.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundStrike {
    /// Simulated seconds since boot.
    pub time_s: f64,
    /// Where, metres north, east, down of the map's home.
    pub position_ned_m: [f64; 3],
}

enum Listener {
    Tcp(TcpListener),
    Udp(Option<Link>),
}

/// A bound simulator, ready to [`run`](SimServer::run).
pub struct SimServer {
    listener: Listener,
    local: Option<SocketAddr>,
    config: SimServerConfig,
    /// The vehicle's own frame (ArduPilot's, about its EKF origin).
    earth: FlatEarth,
    /// The map's frame, for the collision check.
    map_frame: LocalFrame,
}

/// Requested stream periods (simulated seconds) and when each was last sent.
#[derive(Debug, Clone, Default)]
struct Streams {
    period_s: [Option<f64>; STREAMS.len()],
    last_s: [f64; STREAMS.len()],
    /// DISTANCE_SENSOR's period once asked for (sent only with [`Proximity::DistanceSensor`]),
    /// and when it was last sent.
    distance_sensor: Option<f64>,
    distance_sensor_last_s: f64,
}

impl Streams {
    /// SET_MESSAGE_INTERVAL: −1 stops, 0 is the default rate; `false` for an unknown message.
    fn set_interval(&mut self, id: u32, interval_us: f32) -> bool {
        if id == DISTANCE_SENSOR_DATA::ID {
            self.distance_sensor = (interval_us >= 0.0).then(|| {
                if interval_us == 0.0 {
                    0.2
                } else {
                    f64::from(interval_us) * 1e-6
                }
            });
            self.distance_sensor_last_s = f64::NEG_INFINITY;
            return true;
        }
        let Some(k) = STREAMS.iter().position(|m| m.id == id) else {
            return false;
        };
        self.period_s[k] = if interval_us < 0.0 {
            None
        } else if interval_us == 0.0 {
            Some(STREAMS[k].default_period_s)
        } else {
            Some(f64::from(interval_us) * 1e-6)
        };
        self.last_s[k] = f64::NEG_INFINITY;
        true
    }

    /// REQUEST_DATA_STREAM: a group of streams at a rate (0 or `start` false: off). Deprecated
    /// by MAVLink, still what older ground stations send and what ArduPilot honours.
    #[allow(deprecated)]
    fn request(&mut self, stream: MavDataStream, rate_hz: u16, start: bool) {
        let interval_us = if start && rate_hz > 0 {
            1e6 / f32::from(rate_hz)
        } else {
            -1.0
        };
        for s in STREAMS.iter().filter(|s| in_group(s, stream)) {
            self.set_interval(s.id, interval_us);
        }
    }

    /// The messages due at `now_s` (and marks them sent).
    fn due(&mut self, now_s: f64) -> Vec<u32> {
        let mut ids = Vec::new();
        for (k, stream) in STREAMS.iter().enumerate() {
            if let Some(p) = self.period_s[k]
                && now_s - self.last_s[k] >= p
            {
                self.last_s[k] = now_s;
                ids.push(stream.id);
            }
        }
        ids
    }
}

struct Upload {
    count: u16,
    /// MISSION (`items`) or FENCE (`fence`).
    mission_type: MavMissionType,
    items: Vec<SimMissionItem>,
    fence: Vec<FenceItem>,
    /// Wall seconds of the last request.
    last_request_s: f64,
    retries: u32,
}

fn heartbeat_of(s: &SimState) -> MavMessage {
    let mut base = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        | MavModeFlag::MAV_MODE_FLAG_STABILIZE_ENABLED;
    if matches!(s.mode, SimMode::Guided | SimMode::Auto) {
        base |= MavModeFlag::MAV_MODE_FLAG_GUIDED_ENABLED;
    }
    if s.armed {
        base |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
    }
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: s.mode.arducopter_custom_mode(),
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
        base_mode: base,
        system_status: if s.armed {
            MavState::MAV_STATE_ACTIVE
        } else {
            MavState::MAV_STATE_STANDBY
        },
        mavlink_version: 3,
    })
}

fn status_text(severity: MavSeverity, text: &str) -> MavMessage {
    let mut bytes = [0u8; 50];
    for (b, c) in bytes.iter_mut().zip(text.bytes()) {
        *b = c;
    }
    MavMessage::STATUSTEXT(STATUSTEXT_DATA {
        severity,
        text: bytes.into(),
        ..Default::default()
    })
}

impl SimServer {
    /// Binds a TCP listener (`tcpin:`; port 0 picks a free port) or a UDP socket (`udpin:`).
    pub fn bind(address: &Address, config: SimServerConfig) -> Result<Self, LinkError> {
        let map_home = config.map_home.unwrap_or(config.home);
        let map_frame = LocalFrame::new(map_home).map_err(|e| LinkError::Address {
            address: format!("lat {}, lon {}", map_home.lat_deg, map_home.lon_deg),
            message: format!("the map's home is not usable: {e}"),
        })?;
        let earth = FlatEarth::new(config.home.lat_deg, config.home.lon_deg);
        let (listener, local) = match address {
            Address::TcpIn(hp) => {
                let l = TcpListener::bind(hp.as_str()).map_err(|source| LinkError::Open {
                    address: address.to_string(),
                    source,
                })?;
                l.set_nonblocking(true).map_err(|source| LinkError::Open {
                    address: address.to_string(),
                    source,
                })?;
                let local = l.local_addr().ok();
                (Listener::Tcp(l), local)
            }
            Address::UdpIn(_) => {
                let link = Link::open(address, SYSTEM_ID, COMPONENT_ID)?;
                (Listener::Udp(Some(link)), None)
            }
            other => {
                return Err(LinkError::Address {
                    address: other.to_string(),
                    message: "the simulator listens: use tcp:HOST:PORT, tcpin: or udpin:".into(),
                });
            }
        };
        Ok(Self {
            listener,
            local,
            config,
            earth,
            map_frame,
        })
    }

    /// The bound TCP address (with the port chosen for port 0).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.local
    }

    /// Runs until `stop` is set. `world` (the map's boxes) enables the collision check of the
    /// flown track; with [`SimServerConfig::hidden`] boxes, the check and the sensor use both.
    pub fn run(
        self,
        world: Option<&BoxWorld>,
        stop: &AtomicBool,
        note: impl FnMut(SimNote),
    ) -> SimReport {
        self.run_with_state(world, stop, note, Duration::from_secs(3600), |_| {})
    }

    /// A stop flag for [`SimServer::run_with_state`]: set after `wall_s` wall seconds (by a
    /// thread of its own), or never.
    pub fn stop_after(wall_s: Option<f64>) -> std::sync::Arc<AtomicBool> {
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        // A time too long for a `Duration` (or NaN) is never.
        if let Some(wait) = wall_s.and_then(|s| Duration::try_from_secs_f64(s.max(0.0)).ok()) {
            let flag = std::sync::Arc::clone(&stop);
            std::thread::spawn(move || {
                std::thread::sleep(wait);
                flag.store(true, Ordering::Relaxed);
            });
        }
        stop
    }

    /// As [`SimServer::run`], and reports the vehicle's state to `state` every `period` of wall
    /// time (a live view: `skyplan sim --view`). The vehicle is a [`SimProtocol`] fed the wall
    /// clock and the messages received; this loop accepts connections and moves the messages.
    pub fn run_with_state(
        mut self,
        world: Option<&BoxWorld>,
        stop: &AtomicBool,
        mut note: impl FnMut(SimNote),
        period: Duration,
        mut state: impl FnMut(&SimStatus),
    ) -> SimReport {
        let mut sim = SimProtocol::new(self.config.clone(), self.earth, self.map_frame, world);
        let mut link: Option<Link> = match &mut self.listener {
            Listener::Udp(l) => l.take(),
            Listener::Tcp(_) => None,
        };
        let wall0 = Instant::now();
        let now_s = || wall0.elapsed().as_secs_f64();
        let mut last_status: Option<Instant> = None;
        while !stop.load(Ordering::Relaxed) {
            // A ground station connects (TCP: one at a time, again after it leaves).
            if link.is_none()
                && let Listener::Tcp(l) = &self.listener
                && let Ok((stream, peer)) = l.accept()
            {
                match Link::from_tcp_stream(stream, SYSTEM_ID, COMPONENT_ID) {
                    Ok(new) => {
                        note(SimNote::Connected(peer.to_string()));
                        sim.connected(now_s());
                        link = Some(new);
                    }
                    Err(e) => note(SimNote::Disconnected(e.to_string())),
                }
            }
            let sends = sim.advance(now_s());
            send_all(link.as_ref(), &sends);
            sim.take_notes().into_iter().for_each(&mut note);
            if last_status.is_none_or(|t| t.elapsed() >= period) {
                last_status = Some(Instant::now());
                state(&sim.status());
            }
            let Some(l) = link.as_mut() else {
                std::thread::sleep(Duration::from_millis(5));
                continue;
            };
            // Inbound, waiting a little for the first message.
            let mut wait = Duration::from_millis(4);
            while let Some(r) = l.recv_timeout(wait) {
                wait = Duration::ZERO;
                let replies = sim.handle(now_s(), r.message);
                send_all(Some(l), &replies);
            }
            sim.take_notes().into_iter().for_each(&mut note);
            if let Some(why) = l.closed() {
                note(SimNote::Disconnected(why.to_string()));
                link = None;
                sim.disconnected();
                continue;
            }
            send_all(Some(l), &sim.outbound(now_s()));
        }
        sim.finish().into_iter().for_each(&mut note);
        sim.report(now_s())
    }
}

/// Sends messages over the link, if any (a failed send shows up as a closed link).
fn send_all(link: Option<&Link>, messages: &[MavMessage]) {
    if let Some(l) = link {
        for m in messages {
            let _ = l.send(m);
        }
    }
}

fn request_int(seq: u16, mission_type: MavMissionType) -> MavMessage {
    MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
        seq,
        target_system: 255,
        target_component: 0,
        mission_type,
    })
}

impl Upload {
    fn new(count: u16, mission_type: MavMissionType, now_s: f64) -> Self {
        Self {
            count,
            mission_type,
            items: Vec::new(),
            fence: Vec::new(),
            last_request_s: now_s,
            retries: 0,
        }
    }

    /// Items received so far.
    fn received(&self) -> usize {
        match self.mission_type {
            MavMissionType::MAV_MISSION_TYPE_FENCE => self.fence.len(),
            _ => self.items.len(),
        }
    }
}

/// The vehicle side's frame, EKF and streams.
struct Side {
    earth: FlatEarth,
    home_alt_m: f64,
    ekf_delay_s: f64,
    streams: Streams,
    /// The last mission item reached (65535: none yet), which a requested MISSION_ITEM_REACHED
    /// stream repeats, as ArduPilot's does.
    last_reached: u16,
    /// The stored fence (`mission_type` FENCE), read back as uploaded. Stored only: like
    /// ArduCopter with `FENCE_ENABLE` 0, the vehicle does not act on it.
    fence: Vec<FenceItem>,
}

impl Side {
    /// The EKF has set its origin (half-way to a position, as ArduCopter's ~20 s of ~40 s).
    fn origin_set(&self, s: &SimState) -> bool {
        s.time_s >= 0.5 * self.ekf_delay_s
    }

    /// The EKF has a position: positions are sent and arming is allowed.
    fn position_ready(&self, s: &SimState) -> bool {
        s.time_s >= self.ekf_delay_s
    }

    /// Latitude and longitude of a point of the vehicle's local frame, as integers × 10⁷.
    fn lat_lon_e7(&self, north_m: f64, east_m: f64) -> (i32, i32) {
        let (lat, lon) = self.earth.lat_lon_from_ne(north_m, east_m);
        ((lat * 1e7).round() as i32, (lon * 1e7).round() as i32)
    }

    /// The streamed message `id` now, if the vehicle has it to send.
    fn message(&self, id: u32, s: &SimState, mission_len: usize) -> Option<MavMessage> {
        let time_boot_ms = (s.time_s * 1000.0) as u32;
        let [n, e, d] = s.position_ned_m;
        let [vn, ve, vd] = s.velocity_ned_m_s;
        let cm_s = |v: f64| (v * 100.0).round().clamp(-32768.0, 32767.0) as i16;
        Some(match id {
            ATTITUDE_DATA::ID => MavMessage::ATTITUDE(ATTITUDE_DATA {
                time_boot_ms,
                roll: 0.0,
                pitch: 0.0,
                yaw: s.yaw_rad as f32,
                rollspeed: 0.0,
                pitchspeed: 0.0,
                yawspeed: s.yaw_rate_rad_s as f32,
            }),
            LOCAL_POSITION_NED_DATA::ID if self.position_ready(s) => {
                MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms,
                    x: n as f32,
                    y: e as f32,
                    z: d as f32,
                    vx: vn as f32,
                    vy: ve as f32,
                    vz: vd as f32,
                })
            }
            GLOBAL_POSITION_INT_DATA::ID if self.position_ready(s) => {
                let (lat, lon) = self.lat_lon_e7(n, e);
                let hdg = (s.yaw_rad.to_degrees().rem_euclid(360.0) * 100.0).round() as u16 % 36000;
                MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
                    time_boot_ms,
                    lat,
                    lon,
                    alt: ((self.home_alt_m - d) * 1000.0).round() as i32,
                    relative_alt: (-d * 1000.0).round() as i32,
                    vx: cm_s(vn),
                    vy: cm_s(ve),
                    vz: cm_s(vd),
                    hdg,
                })
            }
            GPS_GLOBAL_ORIGIN_DATA::ID if self.origin_set(s) => {
                let (latitude, longitude) = self.lat_lon_e7(0.0, 0.0);
                MavMessage::GPS_GLOBAL_ORIGIN(GPS_GLOBAL_ORIGIN_DATA {
                    latitude,
                    longitude,
                    altitude: (self.home_alt_m * 1000.0).round() as i32,
                    ..Default::default()
                })
            }
            EXTENDED_SYS_STATE_DATA::ID => {
                MavMessage::EXTENDED_SYS_STATE(EXTENDED_SYS_STATE_DATA {
                    vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
                    landed_state: if s.on_ground {
                        MavLandedState::MAV_LANDED_STATE_ON_GROUND
                    } else {
                        MavLandedState::MAV_LANDED_STATE_IN_AIR
                    },
                })
            }
            MISSION_ITEM_REACHED_DATA::ID => {
                MavMessage::MISSION_ITEM_REACHED(MISSION_ITEM_REACHED_DATA {
                    seq: self.last_reached,
                })
            }
            // As ArduPilot: in every mode, once there is a mission.
            MISSION_CURRENT_DATA::ID if mission_len > 1 => {
                MavMessage::MISSION_CURRENT(MISSION_CURRENT_DATA {
                    seq: s.mission_current,
                    ..Default::default()
                })
            }
            _ => return None,
        })
    }
}

fn ack(command: MavCmd, result: MavResult) -> MavMessage {
    MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
        command,
        result,
        ..Default::default()
    })
}

/// A mission item in the vehicle's frame (the deprecated `_INT` frame is what ArduPilot sends).
/// `p` holds `param1`, `param2`, the latitude and longitude (degrees) and `z`.
#[allow(deprecated)]
fn item_to_sim(side: &Side, command: MavCmd, mav_frame: MavFrame, p: [f64; 5]) -> SimMissionItem {
    let [param1, param2, lat_deg, lon_deg, z] = p;
    let relative = matches!(
        mav_frame,
        MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
    );
    let alt_m = if relative { z } else { z - side.home_alt_m };
    match command {
        MavCmd::MAV_CMD_NAV_TAKEOFF => SimMissionItem::Takeoff { alt_m },
        MavCmd::MAV_CMD_NAV_LAND => SimMissionItem::Land,
        MavCmd::MAV_CMD_NAV_WAYPOINT if lat_deg.is_finite() && lon_deg.is_finite() => {
            let [north_m, east_m] = side.earth.ne_from_lat_lon(lat_deg, lon_deg);
            SimMissionItem::Waypoint {
                north_m,
                east_m,
                alt_m,
            }
        }
        MavCmd::MAV_CMD_CONDITION_YAW if param1.is_finite() => SimMissionItem::Yaw {
            yaw_rad: param1.to_radians(),
        },
        // ArduCopter: a speed of −1 (or 0) leaves the speed as it is.
        MavCmd::MAV_CMD_DO_CHANGE_SPEED if param2.is_finite() && param2 > 0.0 => {
            SimMissionItem::Speed { speed_m_s: param2 }
        }
        _ => SimMissionItem::Unsupported,
    }
}

/// The parameters the simulated vehicle has (PARAM_SET / PARAM_VALUE).
const SIM_PARAMS: [&str; 2] = ["RTL_ALT", "RTL_CONE_SLOPE"];

// SET_MODE and MISSION_ITEM are deprecated but still sent by ground stations: answer them.
#[allow(deprecated)]
fn handle_message(
    (v, side, upload): (&mut SimVehicle, &mut Side, &mut Option<Upload>),
    (now_s, last_gcs_s): (f64, &mut f64),
    message: MavMessage,
    note: &mut impl FnMut(SimNote),
) -> Vec<MavMessage> {
    let mut out = Vec::new();
    // Addressed to another system (vehicles may share a network): not ours to obey.
    if mavlink::Message::target_system_id(&message).is_some_and(|t| t != 0 && t != SYSTEM_ID) {
        return out;
    }
    match message {
        MavMessage::HEARTBEAT(h)
            if h.mavtype == MavType::MAV_TYPE_GCS
                || h.autopilot == MavAutopilot::MAV_AUTOPILOT_INVALID =>
        {
            *last_gcs_s = now_s;
        }
        MavMessage::COMMAND_LONG(c) => command_long(v, side, &c, &mut out, note),
        MavMessage::PARAM_SET(p) => {
            // As ArduPilot: the value now held is echoed in PARAM_VALUE; an unknown name or a
            // value out of range gets no answer.
            let name = p.param_id.to_str().unwrap_or("").trim_end_matches('\0');
            if let Some(value) = v.set_param(name, p.param_value) {
                out.push(MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
                    param_value: value,
                    param_count: SIM_PARAMS.len() as u16,
                    param_index: SIM_PARAMS.iter().position(|n| *n == name).unwrap_or(0) as u16,
                    param_id: p.param_id,
                    param_type: p.param_type,
                }));
            }
        }
        MavMessage::PARAM_REQUEST_READ(p) => {
            // As ArduPilot: the value held, by name; an unknown name gets no answer.
            let name = p.param_id.to_str().unwrap_or("").trim_end_matches('\0');
            if let Some(value) = v.param(name) {
                out.push(MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
                    param_value: value,
                    param_count: SIM_PARAMS.len() as u16,
                    param_index: SIM_PARAMS.iter().position(|n| *n == name).unwrap_or(0) as u16,
                    param_id: p.param_id,
                    param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
                }));
            }
        }
        MavMessage::SET_MODE(m) => {
            if let Some(mode) = SimMode::from_arducopter_custom_mode(m.custom_mode) {
                v.set_mode(mode);
            }
        }
        MavMessage::REQUEST_DATA_STREAM(r) => {
            side.streams
                .request(r.req_stream_id, r.req_message_rate, r.start_stop == 1);
        }
        MavMessage::SET_POSITION_TARGET_GLOBAL_INT(t) => position_target_global(v, side, &t),
        MavMessage::SET_POSITION_TARGET_LOCAL_NED(t) => {
            let mask = t.type_mask.bits();
            let position_ignored = mask & 0x7 != 0;
            let local = matches!(t.coordinate_frame, MavFrame::MAV_FRAME_LOCAL_NED);
            if !position_ignored && local {
                let target = sim_target(
                    mask,
                    [f64::from(t.x), f64::from(t.y), f64::from(t.z)],
                    [t.vx, t.vy, t.vz],
                    [t.afx, t.afy, t.afz],
                    t.yaw,
                );
                // Ignored outside GUIDED, as ArduPilot does.
                let _ = v.set_target(stamped(target, t.time_boot_ms, v.state().time_s));
            }
        }
        MavMessage::MISSION_COUNT(c) => {
            let kind = c.mission_type;
            let supported = matches!(
                kind,
                MavMissionType::MAV_MISSION_TYPE_MISSION | MavMissionType::MAV_MISSION_TYPE_FENCE
            );
            if !supported {
                out.push(mission_ack(MavMissionResult::MAV_MISSION_UNSUPPORTED, kind));
            } else if c.count == 0 {
                if kind == MavMissionType::MAV_MISSION_TYPE_FENCE {
                    side.fence.clear();
                } else {
                    v.set_mission(Vec::new());
                }
                out.push(mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, kind));
            } else {
                *upload = Some(Upload::new(c.count, kind, now_s));
                out.push(request_int(0, kind));
            }
        }
        MavMessage::MISSION_ITEM_INT(i)
            if i.mission_type == MavMissionType::MAV_MISSION_TYPE_FENCE =>
        {
            let item = FenceItem {
                seq: i.seq,
                command: i.command as u16,
                param1: i.param1,
                lat_e7: i.x,
                lon_e7: i.y,
            };
            accept_fence_item(side, (upload, now_s), item, &mut out, note);
        }
        MavMessage::MISSION_ITEM(i) if i.mission_type == MavMissionType::MAV_MISSION_TYPE_FENCE => {
            let item = FenceItem {
                seq: i.seq,
                command: i.command as u16,
                param1: i.param1,
                lat_e7: (f64::from(i.x) * 1e7).round() as i32,
                lon_e7: (f64::from(i.y) * 1e7).round() as i32,
            };
            accept_fence_item(side, (upload, now_s), item, &mut out, note);
        }
        MavMessage::MISSION_REQUEST_LIST(r)
            if r.mission_type == MavMissionType::MAV_MISSION_TYPE_FENCE =>
        {
            out.push(MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                count: side.fence.len() as u16,
                target_system: 255,
                target_component: 0,
                mission_type: r.mission_type,
                ..Default::default()
            }));
        }
        MavMessage::MISSION_REQUEST_INT(r)
            if r.mission_type == MavMissionType::MAV_MISSION_TYPE_FENCE =>
        {
            out.push(fence_item_out(side, r.seq));
        }
        MavMessage::MISSION_REQUEST(r)
            if r.mission_type == MavMissionType::MAV_MISSION_TYPE_FENCE =>
        {
            out.push(fence_item_out(side, r.seq));
        }
        MavMessage::MISSION_ITEM_INT(i) => {
            let p = [
                f64::from(i.param1),
                f64::from(i.param2),
                f64::from(i.x) * 1e-7,
                f64::from(i.y) * 1e-7,
                f64::from(i.z),
            ];
            let item = item_to_sim(side, i.command, i.frame, p);
            accept_item(v, (upload, now_s), i.seq, item, &mut out, note);
        }
        MavMessage::MISSION_ITEM(i) => {
            let p = [
                f64::from(i.param1),
                f64::from(i.param2),
                f64::from(i.x),
                f64::from(i.y),
                f64::from(i.z),
            ];
            let item = item_to_sim(side, i.command, i.frame, p);
            accept_item(v, (upload, now_s), i.seq, item, &mut out, note);
        }
        MavMessage::MISSION_CLEAR_ALL(c) => {
            match c.mission_type {
                MavMissionType::MAV_MISSION_TYPE_FENCE => side.fence.clear(),
                MavMissionType::MAV_MISSION_TYPE_MISSION => v.set_mission(Vec::new()),
                MavMissionType::MAV_MISSION_TYPE_ALL => {
                    side.fence.clear();
                    v.set_mission(Vec::new());
                }
                _ => {}
            }
            out.push(mission_ack(
                MavMissionResult::MAV_MISSION_ACCEPTED,
                c.mission_type,
            ));
        }
        _ => {}
    }
    out
}

/// A COMMAND_LONG: obeyed or refused (the reason as STATUSTEXT), always acknowledged.
fn command_long(
    v: &mut SimVehicle,
    side: &mut Side,
    c: &COMMAND_LONG_DATA,
    out: &mut Vec<MavMessage>,
    note: &mut impl FnMut(SimNote),
) {
    let mut refuse = |out: &mut Vec<MavMessage>, text: String| {
        out.push(status_text(MavSeverity::MAV_SEVERITY_WARNING, &text));
        note(SimNote::Refused(text));
    };
    if c.target_system != 0 && c.target_system != SYSTEM_ID {
        return;
    }
    let result = match c.command {
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM
            if c.param1 >= 0.5 && !side.position_ready(&v.state()) =>
        {
            refuse(out, "PreArm: Need Position Estimate".into());
            MavResult::MAV_RESULT_FAILED
        }
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => {
            let r = if c.param1 >= 0.5 { v.arm() } else { v.disarm() };
            match r {
                Ok(()) => MavResult::MAV_RESULT_ACCEPTED,
                Err(e) => {
                    refuse(out, e.0);
                    MavResult::MAV_RESULT_DENIED
                }
            }
        }
        MavCmd::MAV_CMD_NAV_TAKEOFF => match v.takeoff(f64::from(c.param7)) {
            Ok(()) => {
                note(SimNote::Takeoff(f64::from(c.param7)));
                MavResult::MAV_RESULT_ACCEPTED
            }
            Err(e) => {
                refuse(out, e.0);
                MavResult::MAV_RESULT_FAILED
            }
        },
        MavCmd::MAV_CMD_NAV_LAND => {
            v.land();
            MavResult::MAV_RESULT_ACCEPTED
        }
        MavCmd::MAV_CMD_DO_SET_MODE => {
            match SimMode::from_arducopter_custom_mode(c.param2 as u32) {
                Some(m) if (c.param1 as u32) & 1 == 1 => {
                    v.set_mode(m);
                    MavResult::MAV_RESULT_ACCEPTED
                }
                _ => {
                    refuse(out, format!("Mode change to {} not supported", c.param2));
                    MavResult::MAV_RESULT_UNSUPPORTED
                }
            }
        }
        MavCmd::MAV_CMD_MISSION_START => {
            if v.mission().len() <= 1 {
                refuse(out, "Mission: no items".into());
                MavResult::MAV_RESULT_DENIED
            } else {
                v.set_mode(SimMode::Auto);
                MavResult::MAV_RESULT_ACCEPTED
            }
        }
        MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => {
            if side.streams.set_interval(c.param1 as u32, c.param2) {
                MavResult::MAV_RESULT_ACCEPTED
            } else {
                MavResult::MAV_RESULT_UNSUPPORTED
            }
        }
        MavCmd::MAV_CMD_REQUEST_MESSAGE => MavResult::MAV_RESULT_ACCEPTED,
        _ => MavResult::MAV_RESULT_UNSUPPORTED,
    };
    out.push(ack(c.command, result));
}

/// A SET_POSITION_TARGET_GLOBAL_INT (relative or absolute altitude; yaw unless masked).
#[allow(deprecated)] // the non-INT global frames: still sent by ground stations.
fn position_target_global(
    v: &mut SimVehicle,
    side: &Side,
    t: &SET_POSITION_TARGET_GLOBAL_INT_DATA,
) {
    let mask = t.type_mask.bits();
    let relative = matches!(
        t.coordinate_frame,
        MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT | MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT
    );
    let absolute = matches!(
        t.coordinate_frame,
        MavFrame::MAV_FRAME_GLOBAL_INT | MavFrame::MAV_FRAME_GLOBAL
    );
    if mask & 0x7 == 0 && (relative || absolute) {
        let [north_m, east_m] = side
            .earth
            .ne_from_lat_lon(f64::from(t.lat_int) * 1e-7, f64::from(t.lon_int) * 1e-7);
        let alt_m = if relative {
            f64::from(t.alt)
        } else {
            f64::from(t.alt) - side.home_alt_m
        };
        // ArduCopter takes position and velocity from a GLOBAL_INT target and drops its
        // acceleration (`set_destination_posvel`); only LOCAL_NED keeps it: so does the simulator.
        let target = sim_target(
            mask | MASK_ACCELERATION,
            [north_m, east_m, -alt_m],
            [t.vx, t.vy, t.vz],
            [t.afx, t.afy, t.afz],
            t.yaw,
        );
        // Ignored outside GUIDED, as ArduPilot does.
        let _ = v.set_target(stamped(target, t.time_boot_ms, v.state().time_s));
    }
}

/// A position target's `type_mask` bits: velocity ignored (x, y, z)…
const MASK_VELOCITY: u16 = 0x38;
/// …acceleration ignored (x, y, z)…
const MASK_ACCELERATION: u16 = 0x1C0;
/// …the acceleration fields are a force…
const MASK_FORCE: u16 = 0x200;
/// …yaw ignored.
const MASK_YAW: u16 = 0x400;

/// A SET_POSITION_TARGET_* as the simulator's target: the position (NED, true north), the
/// velocity (m/s NED) when no velocity bit of `mask` is set, the acceleration (m/s² NED) when no
/// acceleration bit is set and it is not a force, the yaw unless masked.
pub fn sim_target(
    mask: u16,
    position_ned_m: [f64; 3],
    velocity: [f32; 3],
    accel: [f32; 3],
    yaw_rad: f32,
) -> SimTarget {
    let wide = |v: [f32; 3]| v.map(f64::from);
    SimTarget {
        position_ned_m,
        velocity_ned_m_s: (mask & MASK_VELOCITY == 0).then(|| wide(velocity)),
        accel_ned_m_s2: (mask & (MASK_ACCELERATION | MASK_FORCE) == 0).then(|| wide(accel)),
        yaw_rad: if mask & MASK_YAW != 0 {
            f64::NAN
        } else {
            f64::from(yaw_rad)
        },
    }
}

/// A target with velocity stamped `time_boot_ms` brought to the vehicle's time `now_s` (at
/// constant acceleration), making up the transport delay as MAVLink describes the stamp;
/// unchanged without a stamp (0), without a velocity, or with a stamp more than 1 s off (a
/// clock that is not the vehicle's). ArduCopter ignores the stamp.
pub fn stamped(target: SimTarget, time_boot_ms: u32, now_s: f64) -> SimTarget {
    let dt_s = now_s - f64::from(time_boot_ms) * 1e-3;
    if time_boot_ms == 0 || target.velocity_ned_m_s.is_none() || dt_s.abs() > 1.0 {
        target
    } else {
        target.advanced(dt_s)
    }
}

fn mission_ack(result: MavMissionResult, mission_type: MavMissionType) -> MavMessage {
    MavMessage::MISSION_ACK(MISSION_ACK_DATA {
        target_system: 255,
        target_component: 0,
        mavtype: result,
        mission_type,
        ..Default::default()
    })
}

/// The stored fence's item `seq` as MISSION_ITEM_INT, as ArduPilot reads it back
/// (`MAV_FRAME_GLOBAL_INT`), or MAV_MISSION_INVALID_SEQUENCE.
fn fence_item_out(side: &Side, seq: u16) -> MavMessage {
    match side.fence.get(usize::from(seq)) {
        Some(item) => crate::ground::fence_item_int(item, 255, 0),
        None => mission_ack(
            MavMissionResult::MAV_MISSION_INVALID_SEQUENCE,
            MavMissionType::MAV_MISSION_TYPE_FENCE,
        ),
    }
}

/// Why a whole fence cannot be stored, as ArduPilot's fence loader checks it: each polygon's
/// vertices in a row, as many as their `param1` says, at least 3; circles of positive radius.
fn fence_fault(items: &[FenceItem]) -> Option<String> {
    use skyplan_flight::fence::{
        CIRCLE_EXCLUSION, CIRCLE_INCLUSION, POLYGON_VERTEX_EXCLUSION, POLYGON_VERTEX_INCLUSION,
    };
    let mut k = 0;
    while let Some(item) = items.get(k) {
        match item.command {
            POLYGON_VERTEX_INCLUSION | POLYGON_VERTEX_EXCLUSION => {
                let n = item.param1;
                if !(n >= 3.0 && n.fract() == 0.0) {
                    return Some(format!("Fence: item {k}: bad vertex count {n}"));
                }
                let n = n as usize;
                let run = items[k..]
                    .iter()
                    .take(n)
                    .take_while(|i| i.command == item.command && i.param1 == item.param1)
                    .count();
                if run != n {
                    return Some(format!(
                        "Fence: item {k}: polygon of {n} has {run} vertices"
                    ));
                }
                k += n;
            }
            CIRCLE_INCLUSION | CIRCLE_EXCLUSION if item.param1 > 0.0 => k += 1,
            CIRCLE_INCLUSION | CIRCLE_EXCLUSION => {
                return Some(format!("Fence: item {k}: bad radius {}", item.param1));
            }
            other => return Some(format!("Fence: item {k}: command {other} unsupported")),
        }
    }
    None
}

/// A fence item of an upload in progress; the whole fence is checked and stored when the last
/// arrives. An unsupported command is refused at once with MAV_MISSION_UNSUPPORTED, a fence
/// that does not hold together with MAV_MISSION_ERROR (the reason in a STATUSTEXT), as
/// ArduPilot does.
fn accept_fence_item(
    side: &mut Side,
    (upload, now_s): (&mut Option<Upload>, f64),
    item: FenceItem,
    out: &mut Vec<MavMessage>,
    note: &mut impl FnMut(SimNote),
) {
    let fence = MavMissionType::MAV_MISSION_TYPE_FENCE;
    let Some(u) = upload.as_mut().filter(|u| u.mission_type == fence) else {
        out.push(mission_ack(MavMissionResult::MAV_MISSION_DENIED, fence));
        return;
    };
    let expected = u.fence.len() as u16;
    if item.seq != expected {
        out.push(request_int(expected, fence));
        return;
    }
    if !(5001..=5004).contains(&item.command) {
        *upload = None;
        out.push(status_text(
            MavSeverity::MAV_SEVERITY_WARNING,
            &format!("Fence: command {} unsupported", item.command),
        ));
        out.push(mission_ack(
            MavMissionResult::MAV_MISSION_UNSUPPORTED,
            fence,
        ));
        return;
    }
    u.fence.push(item);
    u.retries = 0;
    u.last_request_s = now_s;
    if u.fence.len() < usize::from(u.count) {
        out.push(request_int(expected + 1, fence));
        return;
    }
    let items = std::mem::take(&mut u.fence);
    *upload = None;
    if let Some(why) = fence_fault(&items) {
        out.push(status_text(MavSeverity::MAV_SEVERITY_WARNING, &why));
        note(SimNote::Refused(why));
        out.push(mission_ack(MavMissionResult::MAV_MISSION_ERROR, fence));
        return;
    }
    note(SimNote::FenceUploaded(items.len()));
    side.fence = items;
    out.push(mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, fence));
}

fn accept_item(
    v: &mut SimVehicle,
    (upload, now_s): (&mut Option<Upload>, f64),
    seq: u16,
    item: SimMissionItem,
    out: &mut Vec<MavMessage>,
    note: &mut impl FnMut(SimNote),
) {
    let mission = MavMissionType::MAV_MISSION_TYPE_MISSION;
    let Some(u) = upload.as_mut().filter(|u| u.mission_type == mission) else {
        out.push(mission_ack(MavMissionResult::MAV_MISSION_DENIED, mission));
        return;
    };
    let expected = u.items.len() as u16;
    if seq != expected {
        out.push(request_int(expected, mission));
        return;
    }
    // Item 0 is the home on ArduPilot: kept in the list, never flown.
    u.items.push(if seq == 0 {
        SimMissionItem::Unsupported
    } else {
        item
    });
    u.retries = 0;
    u.last_request_s = now_s;
    if u.items.len() as u16 == u.count {
        let items = std::mem::take(&mut u.items);
        note(SimNote::MissionUploaded(items.len()));
        v.set_mission(items);
        *upload = None;
        out.push(mission_ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission));
    } else {
        out.push(request_int(expected + 1, mission));
    }
}
