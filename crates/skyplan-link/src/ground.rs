//! The ground side: `skyplan fly` connects to a vehicle and drives the mission state machine.
//!
//! Vehicle messages become [`Event`]s of the executor (HEARTBEAT → armed and mode,
//! GLOBAL_POSITION_INT + ATTITUDE + EXTENDED_SYS_STATE → telemetry, COMMAND_ACK → acks,
//! STATUSTEXT → reasons, MISSION_ITEM_REACHED / MISSION_CURRENT → mission progress), its
//! [`Command`]s become COMMAND_LONG (DO_SET_MODE GUIDED, COMPONENT_ARM_DISARM, NAV_TAKEOFF,
//! NAV_LAND) and SET_POSITION_TARGET_GLOBAL_INT (`MAV_FRAME_GLOBAL_RELATIVE_ALT_INT`, `type_mask`
//! 0x9F8: position + yaw). Heartbeats go out at 1 Hz from their own thread; a vehicle silent for
//! [`GroundConfig::link_timeout_s`] is a lost link. Autopilots stream nothing by default
//! (ArduCopter's rates are 0): every message needed is requested with SET_MESSAGE_INTERVAL, and
//! with REQUEST_DATA_STREAM as well when that brings nothing.
//!
//! **One frame chain.** Every position sent to or read from the vehicle goes through latitude
//! and longitude with the map's own [`LocalFrame`]: targets are `lla_from_ned` of the plan's
//! points, telemetry is `ned_from_lla` of GLOBAL_POSITION_INT. The vehicle's LOCAL_POSITION_NED
//! (a true-north flat-earth frame about its EKF origin, not the map's UTM grid) is never mixed
//! in; it only tells that the EKF has a position. Headings are turned between true north and the
//! map's grid north by the grid convergence at the vehicle.
//!
//! **Sensing and replanning.** `OBSTACLE_DISTANCE` from the vehicle's system (the autopilot or a
//! companion computer) is decoded into an [`ObstacleReading`] at the vehicle's position then
//! ([`crate::obstacle`]) and reported as [`Update::Reading`]. With a [`RouteWatcher`]
//! ([`GroundStation::set_watcher`]), each reading taken while the executor flies its waypoints
//! goes to it with the targets still to fly: [`RouteDecision::Replace`] swaps the route without
//! landing, [`RouteDecision::Hold`] holds the position, then lands, and the flight fails
//! ([`skyplan_flight::executor::Failure::NoRoute`]). An uploaded mission (AUTO) cannot be
//! replanned: [`GroundStation::fly`] refuses a watcher with it.

use crate::obstacle::reading_from_obstacle_distance;
use crate::{Address, Link, LinkError, Received};
use mavlink::dialects::common::*;
use skyplan_flight::executor::wrap_angle_rad;
use skyplan_flight::executor::{
    Command, CommandKind, Event, FailsafeAction, FlightExecutor, FlightState, Note, Output, Target,
    Telemetry, VehicleMode,
};
use skyplan_flight::sensing::{ObstacleReading, ReplanEvent, RouteDecision, RouteWatcher};
use skyplan_flight::upload::{
    ItemCommand, MissionItem, MissionPlan, MissionUpload, UploadConfig, UploadEvent, UploadSend,
    UploadStatus,
};
use skyplan_frames::{Lla, LocalFrame, Ned};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

#[doc(hidden)]
pub mod fuzzing;

/// The messages the flight needs and their rates, Hz: GLOBAL_POSITION_INT, LOCAL_POSITION_NED,
/// ATTITUDE, EXTENDED_SYS_STATE, MISSION_CURRENT, MISSION_ITEM_REACHED, GPS_GLOBAL_ORIGIN.
pub const STREAM_RATES_HZ: [(u32, f64); 7] = [
    (33, 10.0),
    (32, 2.0),
    (30, 10.0),
    (245, 2.0),
    (42, 2.0),
    (46, 2.0),
    (49, 1.0),
];

/// Wall seconds to wait for GPS_GLOBAL_ORIGIN once the vehicle has a position.
pub const ORIGIN_GRACE_S: f64 = 2.0;

/// Our MAVLink system id (a ground station).
pub const SYSTEM_ID: u8 = 255;
/// Our component id (MAV_COMP_ID_MISSIONPLANNER).
pub const COMPONENT_ID: u8 = 190;

/// ArduCopter's GUIDED custom mode.
const ARDUCOPTER_GUIDED: u32 = 4;
/// ArduCopter's AUTO, LOITER and RTL custom modes.
const ARDUCOPTER_AUTO: u32 = 3;
const ARDUCOPTER_LOITER: u32 = 5;
const ARDUCOPTER_RTL: u32 = 6;
/// PX4's OFFBOARD main mode, in `custom_mode` bits 16–23.
const PX4_OFFBOARD: u32 = 6 << 16;

/// Timing of the ground station.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundConfig {
    /// Vehicle seconds per wall-clock second (the simulator's `--speedup`; 1 for real vehicles).
    pub speedup: f64,
    /// A vehicle silent this long (wall seconds) has lost the link.
    pub link_timeout_s: f64,
    /// Overall wall-clock budget of the flight: past it, the executor is told to land.
    pub timeout_s: Option<f64>,
    /// After an abort, wall seconds to wait for the landing beyond the executor's own landing
    /// budget (a return to launch from far away takes that much longer) before giving up.
    pub abort_grace_s: f64,
    /// What the interrupt flag ([`GroundStation::set_interrupt`]) commands: land (default) or
    /// hold ([`FailsafeAction::Hold`]; a return to launch works too).
    pub on_interrupt: FailsafeAction,
    /// Wall seconds between [`Update::Progress`] reports.
    pub progress_period_s: f64,
}

impl Default for GroundConfig {
    fn default() -> Self {
        Self {
            speedup: 1.0,
            link_timeout_s: 5.0,
            timeout_s: None,
            abort_grace_s: 120.0,
            on_interrupt: FailsafeAction::Land,
            progress_period_s: 0.2,
        }
    }
}

/// Ground-side errors before the flight starts.
#[derive(Debug, thiserror::Error)]
pub enum GroundError {
    /// The link failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The vehicle did not show up.
    #[error("no vehicle: {0}")]
    NoVehicle(String),
    /// The vehicle's position is not usable in the map's frame.
    #[error("vehicle position: {0}")]
    Position(String),
    /// The mission upload failed.
    #[error("mission upload failed: {0}")]
    Upload(String),
    /// A route watcher was given for a flight that cannot change its route.
    #[error("replanning in flight: {0}")]
    Replan(String),
}

/// How a mission upload went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UploadReport {
    /// Items sent (the vehicle acknowledged them all).
    pub items: usize,
    /// Item requests answered (re-requests included).
    pub requests: u32,
    /// Messages resent after the vehicle went quiet.
    pub resends: u32,
    /// Wall time from MISSION_COUNT to MISSION_ACK, seconds.
    pub wall_time_s: f64,
}

/// Which autopilot the vehicle runs (decides the mode numbers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Autopilot {
    /// ArduPilot (and skyplan's simulator).
    ArduPilot,
    /// PX4.
    Px4,
    /// Anything else (treated as ArduPilot).
    Other,
}

/// What the ground station knows of the vehicle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleInfo {
    /// Its system id.
    pub system_id: u8,
    /// Its component id.
    pub component_id: u8,
    /// Its autopilot.
    pub autopilot: Autopilot,
    /// Its global position (altitude: relative to home).
    pub position: Lla,
    /// Its EKF origin (GPS_GLOBAL_ORIGIN; altitude above mean sea level), if it sent one.
    pub ekf_origin: Option<Lla>,
}

/// What [`GroundStation::wait_for_vehicle`] is waiting for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Waiting {
    /// A HEARTBEAT from an autopilot.
    Heartbeat,
    /// The EKF origin (GPS_GLOBAL_ORIGIN): set once the autopilot has a GPS fix.
    EkfOrigin,
    /// A position: GLOBAL_POSITION_INT and LOCAL_POSITION_NED (the EKF uses GPS).
    Position,
}

impl std::fmt::Display for Waiting {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Waiting::Heartbeat => "heartbeat",
            Waiting::EkfOrigin => "EKF origin (GPS_GLOBAL_ORIGIN)",
            Waiting::Position => "position (GLOBAL_POSITION_INT, LOCAL_POSITION_NED)",
        })
    }
}

/// One row of the flight log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogRow {
    /// Vehicle time since the flight started, seconds (wall time × speedup).
    pub time_s: f64,
    /// The executor's state.
    pub state: FlightState,
    /// The vehicle's own latitude, degrees (GLOBAL_POSITION_INT, as received).
    pub lat_deg: f64,
    /// The vehicle's own longitude, degrees.
    pub lon_deg: f64,
    /// Position in the mission frame: metres north, east of home, altitude above home.
    pub north_m: f64,
    /// See `north_m`.
    pub east_m: f64,
    /// See `north_m`.
    pub alt_m: f64,
    /// Heading, radians.
    pub yaw_rad: f64,
    /// Ground speed, m/s.
    pub speed_m_s: f64,
    /// The waypoint being flown to, with its index.
    pub target: Option<(usize, Target)>,
}

/// What happens during the flight, for the caller to print.
#[derive(Debug, Clone, PartialEq)]
pub enum Update {
    /// Executor notes (transitions, reached waypoints, refusals) at this vehicle time.
    Notes(f64, Vec<Note>),
    /// A STATUSTEXT from the vehicle.
    StatusText(String),
    /// The connection closed (the link-loss timeout follows).
    LinkClosed(String),
    /// The flight's wall-clock budget ran out: landing.
    TimedOut(f64),
    /// The operator interrupted (Ctrl-C): the action commanded.
    Interrupted(FailsafeAction),
    /// The vehicle changed mode.
    Mode(VehicleMode),
    /// Where the flight stands, every [`GroundConfig::progress_period_s`] (for a progress bar).
    Progress(Progress),
    /// An `OBSTACLE_DISTANCE` decoded in the map's frame (every one: up to the sensor's rate
    /// times the speed-up; keep the latest for displays).
    Reading(ObstacleReading),
    /// Something was not used, and why: an `OBSTACLE_DISTANCE` that cannot be decoded (once
    /// per kind of error), or a watcher's route the executor refused.
    Warning(String),
}

/// Where the flight stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Vehicle time, seconds.
    pub time_s: f64,
    /// The executor's state.
    pub state: FlightState,
    /// Waypoints reached.
    pub reached: usize,
    /// Waypoints in all.
    pub waypoints: usize,
    /// Horizontal distance still to fly along the route, metres.
    pub distance_left_m: f64,
    /// The vehicle's latest telemetry in the map's frame (for live views and recordings).
    pub telemetry: Option<Telemetry>,
    /// `OBSTACLE_DISTANCE` readings decoded so far.
    pub readings: usize,
    /// Routes replaced in flight so far.
    pub replans: usize,
}

/// The flight's account.
#[derive(Debug, Clone)]
pub struct FlightSummary {
    /// The log, one row per telemetry update.
    pub log: Vec<LogRow>,
    /// Vehicle time of the flight, seconds.
    pub time_s: f64,
    /// Wall time of the flight, seconds.
    pub wall_time_s: f64,
    /// Position targets sent.
    pub position_targets_sent: usize,
    /// Heartbeats received from the vehicle.
    pub heartbeats_received: usize,
    /// Every route replaced in flight, in order.
    pub replans: Vec<ReplanEvent>,
    /// `OBSTACLE_DISTANCE` readings decoded.
    pub readings: usize,
    /// Where the latest reading saw obstacles (map frame, north/east metres).
    pub last_hits_ne: Vec<[f64; 2]>,
}

/// A connection to one vehicle.
pub struct GroundStation {
    link: Link,
    config: GroundConfig,
    vehicle: Option<(u8, u8)>,
    autopilot: Autopilot,
    last_heartbeat: Option<Instant>,
    heartbeats: usize,
    armed: bool,
    custom_mode: u32,
    global: Option<GLOBAL_POSITION_INT_DATA>,
    local: Option<LOCAL_POSITION_NED_DATA>,
    origin: Option<GPS_GLOBAL_ORIGIN_DATA>,
    /// An ATTITUDE arrived: the stream requests work.
    streaming: bool,
    yaw_rad: f64,
    on_ground: Option<bool>,
    last_arm_request: CommandKind,
    last_mode_request: CommandKind,
    interrupt: Option<Arc<AtomicBool>>,
    watcher: Option<Box<dyn RouteWatcher + Send>>,
}

impl GroundStation {
    /// Connects and starts sending heartbeats at 1 Hz (from their own thread, so planning or
    /// waiting never starves them).
    pub fn connect(address: &Address, config: GroundConfig) -> Result<Self, GroundError> {
        let link = Link::open(address, SYSTEM_ID, COMPONENT_ID)?;
        link.start_heartbeat(crate::messages::gcs_heartbeat(), Duration::from_secs(1));
        Ok(Self::over(link, config))
    }

    /// A station over an open link, knowing nothing yet.
    fn over(link: Link, config: GroundConfig) -> Self {
        Self {
            link,
            config,
            vehicle: None,
            autopilot: Autopilot::Other,
            last_heartbeat: None,
            heartbeats: 0,
            armed: false,
            custom_mode: 0,
            global: None,
            local: None,
            origin: None,
            streaming: false,
            yaw_rad: 0.0,
            on_ground: None,
            last_arm_request: CommandKind::Arm,
            last_mode_request: CommandKind::TakeControl,
            interrupt: None,
            watcher: None,
        }
    }

    /// Hands every reading taken while the vehicle flies its waypoints to `watcher`, which may
    /// replace the route or hold (see the module documentation). GUIDED flights only:
    /// [`GroundStation::fly`] refuses it with an uploaded mission.
    pub fn set_watcher(&mut self, watcher: Box<dyn RouteWatcher + Send>) {
        self.watcher = Some(watcher);
    }

    /// A flag that, once set (by a Ctrl-C handler), aborts the flight: the executor lands.
    pub fn set_interrupt(&mut self, flag: Arc<AtomicBool>) {
        self.interrupt = Some(flag);
    }

    /// The vehicle's mode from its last heartbeat.
    pub fn mode(&self) -> VehicleMode {
        match self.autopilot {
            Autopilot::Px4 => {
                let main = (self.custom_mode >> 16) & 0xff;
                let sub = (self.custom_mode >> 24) & 0xff;
                match (main, sub) {
                    (6, _) => VehicleMode::Guided,
                    (4, 4) => VehicleMode::Auto,
                    (4, 3) => VehicleMode::Hold,
                    (4, 5) => VehicleMode::ReturnToLaunch,
                    (4, 6) => VehicleMode::Land,
                    _ => VehicleMode::Other(self.custom_mode),
                }
            }
            _ => match self.custom_mode {
                ARDUCOPTER_GUIDED => VehicleMode::Guided,
                ARDUCOPTER_AUTO => VehicleMode::Auto,
                9 => VehicleMode::Land,
                ARDUCOPTER_LOITER | 17 => VehicleMode::Hold,
                ARDUCOPTER_RTL | 21 => VehicleMode::ReturnToLaunch,
                m => VehicleMode::Other(m),
            },
        }
    }

    /// Uploads a mission (see [`skyplan_flight::upload`]): MISSION_COUNT, each requested item
    /// as MISSION_ITEM_INT (MISSION_REQUEST_INT and MISSION_REQUEST are answered alike), until
    /// the vehicle's MISSION_ACK; silences are retried as `config` says. Call after
    /// [`GroundStation::wait_for_vehicle`].
    pub fn upload_mission(
        &mut self,
        plan: &MissionPlan,
        config: UploadConfig,
    ) -> Result<UploadReport, GroundError> {
        let Ok(count) = u16::try_from(plan.items.len()) else {
            return Err(GroundError::Upload(format!(
                "{} items do not fit in a mission",
                plan.items.len()
            )));
        };
        let mut up = MissionUpload::new(count, config);
        let start = Instant::now();
        let sends = up.start(0.0);
        self.send_upload(plan, &sends)?;
        loop {
            match up.status() {
                UploadStatus::Done => {
                    return Ok(UploadReport {
                        items: plan.items.len(),
                        requests: up.requests(),
                        resends: up.resends(),
                        wall_time_s: start.elapsed().as_secs_f64(),
                    });
                }
                UploadStatus::Failed(why) => return Err(GroundError::Upload(why.clone())),
                UploadStatus::InProgress => {}
            }
            if let Some(why) = self.link.closed() {
                return Err(GroundError::Upload(format!("the connection closed: {why}")));
            }
            let event = match self.link.recv_timeout(Duration::from_millis(10)) {
                Some(r) => {
                    let from_vehicle = self
                        .vehicle
                        .is_none_or(|(sys, _)| u32::from(sys) == r.header.system_id);
                    let to_us = |target: u8| target == 0 || target == SYSTEM_ID;
                    let _ = self.absorb(&r);
                    match &r.message {
                        MavMessage::MISSION_REQUEST_INT(q)
                            if from_vehicle && to_us(q.target_system) =>
                        {
                            UploadEvent::Request { seq: q.seq }
                        }
                        #[allow(deprecated)]
                        MavMessage::MISSION_REQUEST(q)
                            if from_vehicle && to_us(q.target_system) =>
                        {
                            UploadEvent::Request { seq: q.seq }
                        }
                        MavMessage::MISSION_ACK(a) if from_vehicle && to_us(a.target_system) => {
                            UploadEvent::Ack(match a.mavtype {
                                MavMissionResult::MAV_MISSION_ACCEPTED => Ok(()),
                                other => Err(format!("{other:?}")
                                    .trim_start_matches("MAV_MISSION_")
                                    .to_string()),
                            })
                        }
                        _ => UploadEvent::Tick,
                    }
                }
                None => UploadEvent::Tick,
            };
            let sends = up.handle(start.elapsed().as_secs_f64(), event);
            self.send_upload(plan, &sends)?;
        }
    }

    fn send_upload(&self, plan: &MissionPlan, sends: &[UploadSend]) -> Result<(), GroundError> {
        let (sys, comp) = self.vehicle.unwrap_or((1, 1));
        for s in sends {
            let message = match *s {
                UploadSend::Count(count) => MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                    count,
                    target_system: sys,
                    target_component: comp,
                    ..Default::default()
                }),
                UploadSend::Item(seq) => {
                    let Some(item) = plan.items.get(usize::from(seq)) else {
                        continue;
                    };
                    mission_item_int(item, sys, comp)
                }
            };
            self.link.send(&message)?;
        }
        Ok(())
    }

    /// Waits, like a ground station, for the vehicle's heartbeat, its EKF origin and its
    /// position, asking it to stream what the flight needs; `on_wait` hears what is awaited (at
    /// each change and every `progress_period_s`) with the wall seconds waited. `timeout` is wall
    /// time. An EKF origin that does not come within [`ORIGIN_GRACE_S`] of the position is not
    /// waited for (not every autopilot sends GPS_GLOBAL_ORIGIN).
    pub fn wait_for_vehicle(
        &mut self,
        timeout: Duration,
        mut on_wait: impl FnMut(Waiting, f64),
    ) -> Result<VehicleInfo, GroundError> {
        let start = Instant::now();
        let mut asked = None::<Instant>;
        let mut first_ask = None::<Instant>;
        let mut fallback = false;
        let mut position_since = None::<Instant>;
        let mut shown: Option<(Waiting, Instant)> = None;
        loop {
            if let Some(r) = self.link.recv_timeout(Duration::from_millis(20)) {
                let _ = self.absorb(&r);
            }
            if let Some(why) = self.link.closed() {
                return Err(GroundError::NoVehicle(format!(
                    "the connection closed: {why}"
                )));
            }
            if self.vehicle.is_some() && asked.is_none_or(|t| t.elapsed() > Duration::from_secs(1))
            {
                let first = *first_ask.get_or_insert_with(Instant::now);
                // Nothing streams 3 s after SET_MESSAGE_INTERVAL: ask the old way too.
                fallback |= !self.streaming && first.elapsed() > Duration::from_secs(3);
                self.request_streams(fallback);
                asked = Some(Instant::now());
            }
            let position = self.global.as_ref().filter(|g| g.lat != 0 || g.lon != 0);
            let position_ready = position.is_some() && self.local.is_some();
            if position_ready {
                position_since.get_or_insert_with(Instant::now);
            }
            let origin_waited =
                position_since.is_some_and(|t| t.elapsed().as_secs_f64() > ORIGIN_GRACE_S);
            if let (Some((sys, comp)), Some(g), true) = (self.vehicle, position, position_ready)
                && (self.origin.is_some() || origin_waited)
            {
                return Ok(VehicleInfo {
                    system_id: sys,
                    component_id: comp,
                    autopilot: self.autopilot,
                    position: Lla {
                        lat_deg: f64::from(g.lat) * 1e-7,
                        lon_deg: f64::from(g.lon) * 1e-7,
                        alt_m: f64::from(g.relative_alt) * 1e-3,
                    },
                    ekf_origin: self.origin.as_ref().map(|o| Lla {
                        lat_deg: f64::from(o.latitude) * 1e-7,
                        lon_deg: f64::from(o.longitude) * 1e-7,
                        alt_m: f64::from(o.altitude) * 1e-3,
                    }),
                });
            }
            let waiting = if self.vehicle.is_none() {
                Waiting::Heartbeat
            } else if self.origin.is_none() && (position_ready || self.local.is_none()) {
                Waiting::EkfOrigin
            } else {
                Waiting::Position
            };
            if shown.is_none_or(|(w, t)| {
                w != waiting || t.elapsed().as_secs_f64() >= self.config.progress_period_s
            }) {
                shown = Some((waiting, Instant::now()));
                on_wait(waiting, start.elapsed().as_secs_f64());
            }
            if start.elapsed() > timeout {
                return Err(GroundError::NoVehicle(self.missing(timeout)));
            }
        }
    }

    /// What never came, for the error of [`GroundStation::wait_for_vehicle`].
    fn missing(&self, timeout: Duration) -> String {
        let within = format!("within {:.1} s", timeout.as_secs_f64());
        if self.vehicle.is_none() {
            return format!("no heartbeat from an autopilot {within}");
        }
        let mut never = Vec::new();
        if self.origin.is_none() {
            never.push("no EKF origin (GPS_GLOBAL_ORIGIN)");
        }
        match &self.global {
            None => never.push("no GLOBAL_POSITION_INT"),
            Some(g) if g.lat == 0 && g.lon == 0 => never.push("GLOBAL_POSITION_INT without a fix"),
            Some(_) => {}
        }
        if self.local.is_none() {
            never.push("no LOCAL_POSITION_NED");
        }
        let hint = if !self.streaming {
            "the vehicle streams nothing we asked for (SET_MESSAGE_INTERVAL, REQUEST_DATA_STREAM)"
        } else if self.origin.is_none() {
            "no GPS fix yet?"
        } else {
            "the EKF has its origin but is not using GPS yet (ArduCopter SITL needs ~40 s after boot at 1×: raise --wait-s)"
        };
        format!("a heartbeat, but {} {within}: {hint}", never.join(", "))
    }

    /// Asks the vehicle to stream what the flight needs (SET_MESSAGE_INTERVAL; with `fallback`,
    /// REQUEST_DATA_STREAM of every stream too, for autopilots without the former).
    fn request_streams(&self, fallback: bool) {
        for (id, hz) in STREAM_RATES_HZ {
            let _ = self.send_command(
                MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
                [id as f32, (1e6 / hz) as f32, 0.0, 0.0, 0.0, 0.0, 0.0],
            );
        }
        if fallback {
            let (sys, comp) = self.vehicle.unwrap_or((1, 1));
            #[allow(deprecated)] // superseded by SET_MESSAGE_INTERVAL, still honoured by ArduPilot
            let request = MavMessage::REQUEST_DATA_STREAM(REQUEST_DATA_STREAM_DATA {
                req_message_rate: 10,
                target_system: sys,
                target_component: comp,
                req_stream_id: MavDataStream::MAV_DATA_STREAM_ALL,
                start_stop: 1,
            });
            let _ = self.link.send(&request);
        }
    }

    fn send_command(&self, command: MavCmd, p: [f32; 7]) -> Result<(), LinkError> {
        let vehicle = self.vehicle.unwrap_or((1, 1));
        self.link
            .send(&crate::messages::command_long(vehicle, command, p))
    }

    /// The message comes from our vehicle (or any, before one has been heard).
    fn is_from_vehicle(&self, r: &Received) -> bool {
        self.vehicle
            .is_none_or(|(sys, _)| u32::from(sys) == r.header.system_id)
    }

    /// Updates what we know from one message; returns an executor event for acks and texts.
    fn absorb(&mut self, r: &Received) -> Option<Event> {
        let from_vehicle = self.is_from_vehicle(r);
        // Telemetry arrives: the stream requests work.
        self.streaming |= from_vehicle
            && matches!(
                r.message,
                MavMessage::GLOBAL_POSITION_INT(_) | MavMessage::ATTITUDE(_)
            );
        match &r.message {
            MavMessage::HEARTBEAT(h) => {
                if h.mavtype == MavType::MAV_TYPE_GCS
                    || h.autopilot == MavAutopilot::MAV_AUTOPILOT_INVALID
                {
                    return None;
                }
                if self.vehicle.is_none() {
                    self.vehicle = Some((r.header.system_id as u8, r.header.component_id));
                    self.autopilot = match h.autopilot {
                        MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA => Autopilot::ArduPilot,
                        MavAutopilot::MAV_AUTOPILOT_PX4 => Autopilot::Px4,
                        _ => Autopilot::Other,
                    };
                } else if !from_vehicle {
                    return None;
                }
                self.last_heartbeat = Some(Instant::now());
                self.heartbeats += 1;
                self.armed = h
                    .base_mode
                    .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                self.custom_mode = h.custom_mode;
                Some(Event::Mode(self.mode()))
            }
            _ if !from_vehicle => None,
            MavMessage::GLOBAL_POSITION_INT(g) => {
                self.global = Some(g.clone());
                None
            }
            MavMessage::LOCAL_POSITION_NED(l) => {
                self.local = Some(l.clone());
                None
            }
            MavMessage::ATTITUDE(a) => {
                self.yaw_rad = f64::from(a.yaw);
                None
            }
            MavMessage::GPS_GLOBAL_ORIGIN(o) => {
                self.origin = Some(o.clone());
                None
            }
            MavMessage::EXTENDED_SYS_STATE(s) => {
                self.on_ground = match s.landed_state {
                    MavLandedState::MAV_LANDED_STATE_ON_GROUND => Some(true),
                    MavLandedState::MAV_LANDED_STATE_UNDEFINED => None,
                    _ => Some(false),
                };
                None
            }
            MavMessage::COMMAND_ACK(a) => {
                let command = match a.command {
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => self.last_arm_request,
                    MavCmd::MAV_CMD_DO_SET_MODE => self.last_mode_request,
                    MavCmd::MAV_CMD_MISSION_START => CommandKind::StartMission,
                    MavCmd::MAV_CMD_NAV_TAKEOFF => CommandKind::Takeoff,
                    MavCmd::MAV_CMD_NAV_LAND => CommandKind::Land,
                    _ => return None,
                };
                let accepted = match a.result {
                    MavResult::MAV_RESULT_ACCEPTED | MavResult::MAV_RESULT_IN_PROGRESS => Ok(()),
                    other => Err(format!("{other:?}")
                        .trim_start_matches("MAV_RESULT_")
                        .to_string()),
                };
                Some(Event::Ack { command, accepted })
            }
            MavMessage::MISSION_ITEM_REACHED(m) => Some(Event::MissionItemReached(m.seq)),
            MavMessage::MISSION_CURRENT(m) => Some(Event::MissionCurrent(m.seq)),
            MavMessage::STATUSTEXT(t) => {
                let text = t
                    .text
                    .to_str()
                    .unwrap_or("")
                    .trim_end_matches('\0')
                    .to_string();
                Some(Event::StatusText(text))
            }
            _ => None,
        }
    }

    fn guided(&self) -> bool {
        match self.autopilot {
            Autopilot::Px4 => self.custom_mode & 0x00ff_0000 == PX4_OFFBOARD,
            _ => self.custom_mode == ARDUCOPTER_GUIDED,
        }
    }

    /// Flies the mission: `frame` is the mission's frame (the map's home). Returns when the
    /// executor has an outcome, or when an aborted flight does not land in time.
    pub fn fly<E: FlightExecutor>(
        &mut self,
        ex: &mut E,
        frame: &LocalFrame,
        mut on_update: impl FnMut(Update),
    ) -> Result<FlightSummary, GroundError> {
        // Catch up with what arrived while planning, so that the offset and the first
        // telemetry are fresh.
        while let Some(r) = self.link.recv_timeout(Duration::ZERO) {
            let _ = self.absorb(&r);
        }
        if self.watcher.is_some() && !ex.replans() {
            return Err(GroundError::Replan(
                "an uploaded mission (AUTO, --upload) cannot change its route in flight; fly it in GUIDED (without --upload) to replan from sensor readings".into(),
            ));
        }
        let Some(g) = self.global.clone() else {
            return Err(GroundError::NoVehicle(
                "call wait_for_vehicle first: no position yet".into(),
            ));
        };
        // True bearing of the map's grid north at the vehicle (UTM convergence; 0.37° at the
        // FCND home): headings are turned by it between the vehicle and the plan.
        let convergence_rad = grid_convergence_rad(frame, global_lla(&g))?;
        let speedup = self.config.speedup.max(0.1);
        let start = Instant::now();
        let now = |start: Instant| start.elapsed().as_secs_f64() * speedup;
        let mut log = Vec::new();
        let mut last_tick = Instant::now();
        let mut aborted_at: Option<Instant> = None;
        let mut closed_reported = false;
        let mut sent_targets = 0usize;
        let mut last_global_ms = None;
        let mut last_request = Instant::now();
        let mut last_mode = None;
        let mut link_lost = false;
        let mut last_progress: Option<Instant> = None;
        let mut replans: Vec<ReplanEvent> = Vec::new();
        let mut readings = 0usize;
        let mut last_hits_ne: Vec<[f64; 2]> = Vec::new();
        let mut warned: Vec<String> = Vec::new();
        // The silence clock starts now: planning may have taken a while.
        self.last_heartbeat = Some(Instant::now());
        while ex.outcome().is_none() {
            let mut events = Vec::new();
            let mut reading = None;
            if let Some(r) = self.link.recv_timeout(Duration::from_millis(5)) {
                if let MavMessage::OBSTACLE_DISTANCE(o) = &r.message
                    && self
                        .vehicle
                        .is_some_and(|(sys, _)| u32::from(sys) == r.header.system_id)
                    && let Some(t) = ex.last_telemetry()
                {
                    let at = [t.north_m, t.east_m, t.down_m];
                    match reading_from_obstacle_distance(
                        o,
                        now(start),
                        at,
                        self.yaw_rad,
                        convergence_rad,
                    ) {
                        Ok(x) => {
                            readings += 1;
                            last_hits_ne = x.hits_ne().collect();
                            on_update(Update::Reading(x.clone()));
                            reading = Some(x);
                        }
                        Err(e) => {
                            let text = e.to_string();
                            if !warned.contains(&text) {
                                warned.push(text.clone());
                                on_update(Update::Warning(format!("{text}: reading ignored")));
                            }
                        }
                    }
                }
                let heard_before = self.last_heartbeat;
                let event = self.absorb(&r);
                if link_lost && self.last_heartbeat != heard_before {
                    // The vehicle speaks again: the executor commands the failsafe.
                    link_lost = false;
                    let silent_s = heard_before.map_or(0.0, |t| t.elapsed().as_secs_f64());
                    events.push(Event::LinkRegained { silent_s });
                }
                if let Some(e) = event {
                    if let Event::StatusText(t) = &e {
                        on_update(Update::StatusText(t.clone()));
                    }
                    if let Event::Mode(m) = e
                        && last_mode != Some(m)
                    {
                        last_mode = Some(m);
                        on_update(Update::Mode(m));
                    }
                    events.push(e);
                }
                if let MavMessage::GLOBAL_POSITION_INT(g) = &r.message
                    && self.is_from_vehicle(&r)
                    && last_global_ms != Some(g.time_boot_ms)
                    && (g.lat != 0 || g.lon != 0)
                    && let Ok(ned) = frame.ned_from_lla(global_lla(g))
                {
                    last_global_ms = Some(g.time_boot_ms);
                    let (c, s) = (convergence_rad.cos(), convergence_rad.sin());
                    let [vn, ve] = [f64::from(g.vx) * 0.01, f64::from(g.vy) * 0.01];
                    events.push(Event::Telemetry(Telemetry {
                        north_m: ned.north_m,
                        east_m: ned.east_m,
                        down_m: -f64::from(g.relative_alt) * 1e-3,
                        velocity_ned_m_s: [
                            vn * c + ve * s,
                            ve * c - vn * s,
                            f64::from(g.vz) * 0.01,
                        ],
                        yaw_rad: wrap_angle_rad(self.yaw_rad - convergence_rad),
                        armed: self.armed,
                        guided: self.guided(),
                        on_ground: self.on_ground,
                    }));
                }
            }
            // Ask again now and then: a request lost on the way would cost the mission progress.
            if last_request.elapsed() > Duration::from_secs(10) {
                last_request = Instant::now();
                self.request_streams(false);
            }
            if !closed_reported && let Some(why) = self.link.closed() {
                closed_reported = true;
                on_update(Update::LinkClosed(why.to_string()));
            }
            if last_tick.elapsed() >= Duration::from_millis(50) {
                last_tick = Instant::now();
                events.push(Event::Tick);
            }
            let silent_s = self
                .last_heartbeat
                .map_or(f64::INFINITY, |t| t.elapsed().as_secs_f64());
            if silent_s > self.config.link_timeout_s {
                link_lost = true;
                events.push(Event::LinkLost { silent_s });
            }
            if let Some(limit) = self.config.timeout_s
                && aborted_at.is_none()
                && start.elapsed().as_secs_f64() > limit
            {
                aborted_at = Some(Instant::now());
                on_update(Update::TimedOut(limit));
                events.push(Event::Abort(format!("--timeout-s {limit} exceeded")));
            }
            if aborted_at.is_none()
                && self
                    .interrupt
                    .as_ref()
                    .is_some_and(|f| f.load(Ordering::Relaxed))
            {
                aborted_at = Some(Instant::now());
                let action = self.config.on_interrupt;
                on_update(Update::Interrupted(action));
                events.push(Event::Stop {
                    reason: "interrupted by Ctrl-C".into(),
                    action,
                });
            }
            if last_progress
                .is_none_or(|t| t.elapsed().as_secs_f64() >= self.config.progress_period_s)
            {
                last_progress = Some(Instant::now());
                on_update(Update::Progress(Progress {
                    time_s: now(start),
                    state: ex.state(),
                    reached: ex.reached().len(),
                    waypoints: ex.targets().len(),
                    distance_left_m: ex.distance_left_m(),
                    telemetry: ex.last_telemetry().cloned(),
                    readings,
                    replans: replans.len(),
                }));
            }
            if let Some(t) = aborted_at
                && t.elapsed().as_secs_f64()
                    > self.config.abort_grace_s + ex.landing_budget_s() / self.config.speedup
            {
                break;
            }
            for e in events {
                let t = now(start);
                let is_telemetry = matches!(e, Event::Telemetry(_));
                let out = ex.handle(t, e);
                sent_targets += self.dispatch(out, t, frame, convergence_rad, &mut on_update);
                if is_telemetry && let Some(tel) = ex.last_telemetry() {
                    let (lat_deg, lon_deg) =
                        self.global.as_ref().map_or((f64::NAN, f64::NAN), |g| {
                            (f64::from(g.lat) * 1e-7, f64::from(g.lon) * 1e-7)
                        });
                    log.push(LogRow {
                        time_s: t,
                        lat_deg,
                        lon_deg,
                        state: ex.state(),
                        north_m: tel.north_m,
                        east_m: tel.east_m,
                        alt_m: tel.alt_m(),
                        yaw_rad: tel.yaw_rad,
                        speed_m_s: tel.ground_speed_m_s(),
                        target: ex.current_target(),
                    });
                }
            }
            // The watcher sees the reading with the route still to fly.
            if let Some(reading) = reading
                && ex.accepts_route_change()
                && let Some(watcher) = self.watcher.as_mut()
            {
                let t = now(start);
                let out = match watcher.on_reading(&reading, ex.remaining_targets()) {
                    RouteDecision::Keep => None,
                    RouteDecision::Replace { targets, event } => {
                        match ex.replace_route(t, &targets, event.clone()) {
                            Ok(out) => {
                                replans.push(event);
                                Some(out)
                            }
                            Err(e) => {
                                on_update(Update::Warning(format!("replanned route refused: {e}")));
                                None
                            }
                        }
                    }
                    RouteDecision::Hold { reason } => Some(ex.hold_no_route(t, reason)),
                };
                if let Some(out) = out {
                    sent_targets += self.dispatch(out, t, frame, convergence_rad, &mut on_update);
                }
            }
        }
        Ok(FlightSummary {
            log,
            time_s: now(start),
            wall_time_s: start.elapsed().as_secs_f64(),
            position_targets_sent: sent_targets,
            heartbeats_received: self.heartbeats,
            replans,
            readings,
            last_hits_ne,
        })
    }

    /// Sends an executor output's commands and reports its notes; the position targets sent.
    fn dispatch(
        &mut self,
        out: Output,
        t: f64,
        frame: &LocalFrame,
        convergence_rad: f64,
        on_update: &mut impl FnMut(Update),
    ) -> usize {
        let mut gotos = 0;
        for c in &out.commands {
            if matches!(c, Command::GoTo { .. }) {
                gotos += 1;
            }
            // A failed send shows up as a lost link; nothing else to do here.
            let _ = self.send(*c, frame, convergence_rad);
        }
        if !out.notes.is_empty() {
            on_update(Update::Notes(t, out.notes));
        }
        gotos
    }

    fn send(
        &mut self,
        c: Command,
        frame: &LocalFrame,
        convergence_rad: f64,
    ) -> Result<(), LinkError> {
        match c {
            Command::TakeControl | Command::Hold | Command::ReturnToLaunch => {
                // PX4: main mode in param2, sub mode in param3 (AUTO = 4: LOITER 3, RTL 5).
                let (kind, mode, sub) = match (c, self.autopilot) {
                    (Command::TakeControl, Autopilot::Px4) => (CommandKind::TakeControl, 6.0, 0.0),
                    (Command::TakeControl, _) => {
                        (CommandKind::TakeControl, ARDUCOPTER_GUIDED as f32, 0.0)
                    }
                    (Command::Hold, Autopilot::Px4) => (CommandKind::Hold, 4.0, 3.0),
                    (Command::Hold, _) => (CommandKind::Hold, ARDUCOPTER_LOITER as f32, 0.0),
                    (_, Autopilot::Px4) => (CommandKind::ReturnToLaunch, 4.0, 5.0),
                    _ => (CommandKind::ReturnToLaunch, ARDUCOPTER_RTL as f32, 0.0),
                };
                self.last_mode_request = kind;
                self.send_command(
                    MavCmd::MAV_CMD_DO_SET_MODE,
                    [1.0, mode, sub, 0.0, 0.0, 0.0, 0.0],
                )
            }
            Command::StartMission => {
                // AUTO first (ArduCopter starts a mission on the ground only with MISSION_START).
                let (mode, sub) = match self.autopilot {
                    Autopilot::Px4 => (4.0, 4.0),
                    _ => (ARDUCOPTER_AUTO as f32, 0.0),
                };
                self.last_mode_request = CommandKind::StartMission;
                self.send_command(
                    MavCmd::MAV_CMD_DO_SET_MODE,
                    [1.0, mode, sub, 0.0, 0.0, 0.0, 0.0],
                )?;
                self.send_command(
                    MavCmd::MAV_CMD_MISSION_START,
                    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                )
            }
            Command::Arm | Command::Disarm => {
                let arm = matches!(c, Command::Arm);
                self.last_arm_request = if arm {
                    CommandKind::Arm
                } else {
                    CommandKind::Disarm
                };
                self.send_command(
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                    [if arm { 1.0 } else { 0.0 }, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                )
            }
            Command::Takeoff { alt_m } => self.send_command(
                MavCmd::MAV_CMD_NAV_TAKEOFF,
                [0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, alt_m as f32],
            ),
            Command::Land => self.send_command(
                MavCmd::MAV_CMD_NAV_LAND,
                [0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0],
            ),
            Command::GoTo {
                north_m,
                east_m,
                down_m,
                yaw_rad,
            } => {
                let (sys, comp) = self.vehicle.unwrap_or((1, 1));
                let lla = frame
                    .lla_from_ned(Ned {
                        north_m,
                        east_m,
                        down_m: 0.0,
                    })
                    .map_err(|e| LinkError::Send {
                        message: "SET_POSITION_TARGET_GLOBAL_INT",
                        detail: format!("the target has no latitude/longitude: {e}"),
                    })?;
                #[allow(deprecated)] // GLOBAL_RELATIVE_ALT_INT: what ArduPilot and PX4 expect here.
                let coordinate_frame = MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT;
                self.link.send(&MavMessage::SET_POSITION_TARGET_GLOBAL_INT(
                    SET_POSITION_TARGET_GLOBAL_INT_DATA {
                        time_boot_ms: 0,
                        lat_int: (lla.lat_deg * 1e7).round() as i32,
                        lon_int: (lla.lon_deg * 1e7).round() as i32,
                        alt: (-down_m) as f32,
                        vx: 0.0,
                        vy: 0.0,
                        vz: 0.0,
                        afx: 0.0,
                        afy: 0.0,
                        afz: 0.0,
                        yaw: wrap_angle_rad(yaw_rad + convergence_rad) as f32,
                        yaw_rate: 0.0,
                        type_mask: PositionTargetTypemask::from_bits_truncate(POSITION_AND_YAW),
                        target_system: sys,
                        target_component: comp,
                        coordinate_frame,
                    },
                ))
            }
        }
    }
}

/// The latitude and longitude of a GLOBAL_POSITION_INT (altitude 0: positions are horizontal).
fn global_lla(g: &GLOBAL_POSITION_INT_DATA) -> Lla {
    Lla {
        lat_deg: f64::from(g.lat) * 1e-7,
        lon_deg: f64::from(g.lon) * 1e-7,
        alt_m: 0.0,
    }
}

/// The true bearing of the map frame's north axis at `at`, radians clockwise from true north
/// (the grid convergence of its UTM projection there).
pub fn grid_convergence_rad(frame: &LocalFrame, at: Lla) -> Result<f64, GroundError> {
    let bad = |e: skyplan_frames::FrameError| GroundError::Position(e.to_string());
    let ned = frame.ned_from_lla(at).map_err(bad)?;
    let ahead = frame
        .lla_from_ned(Ned {
            north_m: ned.north_m + 100.0,
            ..ned
        })
        .map_err(bad)?;
    // WGS84 radii of curvature there: north (meridian) and east (prime vertical).
    const A_M: f64 = 6_378_137.0;
    const E2: f64 = 6.694_379_990_14e-3;
    let lat = ((at.lat_deg + ahead.lat_deg) / 2.0).to_radians();
    let w = 1.0 - E2 * lat.sin().powi(2);
    let (m_north, m_east) = (A_M * (1.0 - E2) / w.powf(1.5), A_M / w.sqrt() * lat.cos());
    let (dn, de) = (
        (ahead.lat_deg - at.lat_deg).to_radians() * m_north,
        (ahead.lon_deg - at.lon_deg).to_radians() * m_east,
    );
    Ok(de.atan2(dn))
}

/// An item as MISSION_ITEM_INT (relative-altitude frame, auto-continue; a CONDITION_YAW carries
/// its absolute heading in `param1`, at the default rate, the shortest way).
#[allow(deprecated)] // MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: what ArduPilot and PX4 expect here.
pub fn mission_item_int(item: &MissionItem, target_system: u8, target_component: u8) -> MavMessage {
    let (command, frame, params) = match item.command {
        ItemCommand::Waypoint => (
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            [0.0, 0.0, 0.0, item.yaw_deg],
        ),
        ItemCommand::Takeoff => (
            MavCmd::MAV_CMD_NAV_TAKEOFF,
            MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            [0.0, 0.0, 0.0, item.yaw_deg],
        ),
        ItemCommand::Land => (
            MavCmd::MAV_CMD_NAV_LAND,
            MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            [0.0, 0.0, 0.0, item.yaw_deg],
        ),
        ItemCommand::ConditionYaw => (
            MavCmd::MAV_CMD_CONDITION_YAW,
            MavFrame::MAV_FRAME_MISSION,
            [item.yaw_deg, 0.0, 0.0, 0.0],
        ),
    };
    MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
        param1: params[0],
        param2: params[1],
        param3: params[2],
        param4: params[3],
        x: item.lat_e7,
        y: item.lon_e7,
        z: item.alt_m,
        seq: item.seq,
        command,
        target_system,
        target_component,
        frame,
        current: 0,
        autocontinue: 1,
        ..Default::default()
    })
}

/// `type_mask` of a position + yaw target: ignore velocity, acceleration and yaw rate.
pub const POSITION_AND_YAW: u16 = 0x9F8;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_convergence_matches_the_utm_formula() {
        // UTM convergence (Snyder, "Map Projections — A Working Manual", eq. 8-15 without
        // higher terms): γ = Δλ sin φ [1 + Δλ² cos² φ (1 + 3η² + 2η⁴) / 3], η² = e'² cos² φ,
        // Δλ from the zone's central meridian; grid north is east of true north east of it.
        let frame = LocalFrame::new(Lla {
            lat_deg: 37.792480,
            lon_deg: -122.397450,
            alt_m: 0.0,
        })
        .unwrap();
        for (lat_deg, lon_deg) in [(37.792480, -122.397450), (37.80, -122.45), (37.70, -122.90)] {
            let phi = f64::to_radians(lat_deg);
            let dl = f64::to_radians(lon_deg + 123.0); // zone 10: central meridian 123° W
            let eta2 = 6.739_496_742e-3 * phi.cos().powi(2);
            let gamma = dl
                * phi.sin()
                * (1.0
                    + dl.powi(2) * phi.cos().powi(2) * (1.0 + 3.0 * eta2 + 2.0 * eta2 * eta2)
                        / 3.0);
            let got = grid_convergence_rad(
                &frame,
                Lla {
                    lat_deg,
                    lon_deg,
                    alt_m: 0.0,
                },
            )
            .unwrap();
            assert!(
                (got - gamma).to_degrees().abs() < 2e-4,
                "{lat_deg} {lon_deg}: {} vs {}",
                got.to_degrees(),
                gamma.to_degrees()
            );
        }
        // At the FCND home: 0.37°, as FLIGHT-NOTES measured.
        let home = grid_convergence_rad(&frame, frame.home())
            .unwrap()
            .to_degrees();
        assert!((home - 0.369).abs() < 0.001, "{home}");
    }
}
