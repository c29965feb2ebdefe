//! The ground side: `skyplan fly` connects to a vehicle and drives the mission state machine.
//!
//! The protocol is [`protocol`]'s state machines, fed messages and wall seconds, returning the
//! messages to send; [`GroundStation`] holds the link and the clock and runs them in short loops.
//!
//! Vehicle messages become `Event`s of the executor (HEARTBEAT → armed and mode,
//! GLOBAL_POSITION_INT + ATTITUDE + EXTENDED_SYS_STATE → telemetry, COMMAND_ACK → acks,
//! STATUSTEXT → reasons, MISSION_ITEM_REACHED / MISSION_CURRENT → mission progress), its
//! `Command`s become COMMAND_LONG (DO_SET_MODE GUIDED, COMPONENT_ARM_DISARM, NAV_TAKEOFF,
//! NAV_LAND) and SET_POSITION_TARGET_GLOBAL_INT (`MAV_FRAME_GLOBAL_RELATIVE_ALT_INT`, `type_mask`
//! 0x9F8: position + yaw; a reference's setpoint, `Command::Track`, with `type_mask` 0x0800:
//! position, velocity, acceleration and yaw, stamped with the vehicle's time it holds at).
//! Heartbeats go out at 1 Hz from their own thread; a vehicle silent for
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
//! goes to it with the targets still to fly: `RouteDecision::Replace` swaps the route without
//! landing, `RouteDecision::Hold` holds the position, then lands, and the flight fails
//! ([`skyplan_flight::executor::Failure::NoRoute`]). An uploaded mission (AUTO) cannot be
//! replanned: [`GroundStation::fly`] refuses a watcher with it.

use crate::{Address, Link, LinkError};
use mavlink::dialects::common::*;
use skyplan_flight::executor::{
    FailsafeAction, FlightExecutor, FlightState, Note, Target, Telemetry, TrackingReport,
    VehicleMode,
};
use skyplan_flight::fence::FenceItem;
use skyplan_flight::sensing::{HomeRouter, ObstacleReading, ReplanEvent, RouteWatcher};
use skyplan_flight::upload::{ItemCommand, MissionItem, MissionPlan, UploadConfig};
use skyplan_frames::{Lla, LocalFrame, Ned};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

#[doc(hidden)]
pub mod fuzzing;
pub mod protocol;

pub use protocol::{
    DISTANCE_SENSOR_RATE_HZ, FenceDownload, FlightLoop, GroundProtocol, UploadDriver, VehicleWait,
    WaitStep, mission_result_name,
};

/// Wall seconds to wait for GPS_GLOBAL_ORIGIN once the vehicle has a position.
pub const ORIGIN_GRACE_S: f64 = 2.0;

/// Our MAVLink system id (a ground station).
pub const SYSTEM_ID: u8 = 255;
/// Our component id (MAV_COMP_ID_MISSIONPLANNER).
pub const COMPONENT_ID: u8 = 190;

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
    /// The fence upload or its read-back failed, or what was read back differs.
    #[error("fence {0}")]
    Fence(String),
    /// The vehicle did not confirm a parameter.
    #[error("parameter {name}: {why}")]
    Param {
        /// The parameter.
        name: String,
        /// What happened.
        why: String,
    },
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
    /// How the reference was followed, for a flight by a reference (its executor's
    /// [`FlightExecutor::tracking`]); times in the vehicle's clock when it stamps its positions.
    pub tracking: Option<TrackingReport>,
}

/// A connection to one vehicle: the link and the clock around the station's protocol
/// ([`protocol`]), which decides everything.
pub struct GroundStation {
    link: Link,
    config: GroundConfig,
    protocol: GroundProtocol,
    /// The station's clock: wall seconds since it connected.
    epoch: Instant,
    interrupt: Option<Arc<AtomicBool>>,
    watcher: Option<Box<dyn RouteWatcher + Send>>,
    home_router: Option<Box<dyn HomeRouter + Send>>,
}

impl GroundStation {
    /// Connects and starts sending heartbeats at 1 Hz (from their own thread, so planning or
    /// waiting never starves them).
    pub fn connect(address: &Address, config: GroundConfig) -> Result<Self, GroundError> {
        let link = Link::open(address, SYSTEM_ID, COMPONENT_ID)?;
        link.start_heartbeat(crate::messages::gcs_heartbeat(), Duration::from_secs(1));
        Ok(Self {
            link,
            config,
            protocol: GroundProtocol::new(),
            epoch: Instant::now(),
            interrupt: None,
            watcher: None,
            home_router: None,
        })
    }

    /// Over terrain: the vehicle's home (where it armed) stands `up_m` above the map's home,
    /// and every altitude the station takes or gives is above the map's home from then on
    /// ([`GroundProtocol::set_home_up_m`]).
    pub fn set_home_up_m(&mut self, up_m: f64) {
        self.protocol.set_home_up_m(up_m);
    }

    /// Hands every reading taken while the vehicle flies its waypoints to `watcher`, which may
    /// replace the route or hold (see the module documentation). GUIDED flights only:
    /// [`GroundStation::fly`] refuses it with an uploaded mission.
    pub fn set_watcher(&mut self, watcher: Box<dyn RouteWatcher + Send>) {
        self.watcher = Some(watcher);
    }

    /// Plans the way home when the flight stops with [`FailsafeAction::Return`] (an interrupt
    /// with `on_interrupt` return, or the failsafe after a lost link): without a router the
    /// vehicle lands where it is.
    pub fn set_home_router(&mut self, router: Box<dyn HomeRouter + Send>) {
        self.home_router = Some(router);
    }

    /// A flag that, once set (by a Ctrl-C handler), aborts the flight: the executor lands.
    pub fn set_interrupt(&mut self, flag: Arc<AtomicBool>) {
        self.interrupt = Some(flag);
    }

    /// The vehicle's mode from its last heartbeat.
    pub fn mode(&self) -> VehicleMode {
        self.protocol.mode()
    }

    /// Wall seconds on the station's clock.
    fn now_s(&self) -> f64 {
        self.epoch.elapsed().as_secs_f64()
    }

    /// Sends messages in order; the first failure stops.
    fn send_all(&self, messages: &[MavMessage]) -> Result<(), LinkError> {
        messages.iter().try_for_each(|m| self.link.send(m))
    }

    /// Uploads a mission (see [`skyplan_flight::upload`] and [`UploadDriver`]); silences are
    /// retried as `config` says. Call after [`GroundStation::wait_for_vehicle`].
    pub fn upload_mission(
        &mut self,
        plan: &MissionPlan,
        config: UploadConfig,
    ) -> Result<UploadReport, GroundError> {
        let (mut driver, sends) = UploadDriver::start(&self.protocol, plan, config, self.now_s())?;
        self.send_all(&sends)?;
        loop {
            if let Some(done) = driver.done(self.now_s()) {
                return done;
            }
            if let Some(why) = self.link.closed() {
                return Err(GroundError::Upload(format!("the connection closed: {why}")));
            }
            let r = self.link.recv_timeout(Duration::from_millis(10));
            let now_s = self.now_s();
            let sends = driver.step(&mut self.protocol, now_s, r.as_ref());
            self.send_all(&sends)?;
        }
    }

    /// Uploads a fence (`mission_type` FENCE, [`UploadDriver::start_fence`]), then reads it
    /// back ([`FenceDownload`]) and checks it item by item
    /// ([`skyplan_flight::fence::verify_fence`]). Call after
    /// [`GroundStation::wait_for_vehicle`]; an error ([`GroundError::Fence`]) says which step
    /// failed and how.
    pub fn upload_fence(
        &mut self,
        fence: &[FenceItem],
        config: UploadConfig,
    ) -> Result<UploadReport, GroundError> {
        let (mut driver, sends) =
            UploadDriver::start_fence(&self.protocol, fence, config, self.now_s())?;
        self.send_all(&sends)?;
        let report = loop {
            if let Some(done) = driver.done(self.now_s()) {
                break done?;
            }
            if let Some(why) = self.link.closed() {
                return Err(GroundError::Fence(format!(
                    "upload: the connection closed: {why}"
                )));
            }
            let r = self.link.recv_timeout(Duration::from_millis(10));
            let now_s = self.now_s();
            let sends = driver.step(&mut self.protocol, now_s, r.as_ref());
            self.send_all(&sends)?;
        };
        let read = self.read_fence(config)?;
        skyplan_flight::fence::verify_fence(fence, &read).map_err(|e| {
            GroundError::Fence(format!("read-back differs from what was sent: {e}"))
        })?;
        Ok(report)
    }

    /// Reads the vehicle's fence back ([`FenceDownload`]).
    pub fn read_fence(&mut self, config: UploadConfig) -> Result<Vec<FenceItem>, GroundError> {
        let (mut down, sends) = FenceDownload::start(&self.protocol, config, self.now_s());
        self.send_all(&sends)?;
        loop {
            if let Some(done) = down.done() {
                // The closing MISSION_ACK went out with the last step.
                return done;
            }
            if let Some(why) = self.link.closed() {
                return Err(GroundError::Fence(format!(
                    "read-back: the connection closed: {why}"
                )));
            }
            let r = self.link.recv_timeout(Duration::from_millis(10));
            let now_s = self.now_s();
            let sends = down.step(&mut self.protocol, now_s, r.as_ref());
            self.send_all(&sends)?;
        }
    }

    /// Sets the vehicle's parameter `name` to `value` (PARAM_SET) and returns the value it then
    /// holds, from its PARAM_VALUE; sent up to 3 times, 1 s apart. Call after
    /// [`GroundStation::wait_for_vehicle`]. A vehicle without the parameter (or that refuses the
    /// value) does not answer: an error saying so.
    pub fn set_param(&mut self, name: &str, value: f32) -> Result<f32, GroundError> {
        let message = self.protocol.param_set(name, value);
        self.param_exchange(name, &message, 3, 1.0)
            .map_err(|e| match e {
                GroundError::Param { name, why } if why.is_empty() => GroundError::Param {
                    name,
                    why: "the vehicle did not confirm it after 3 tries (no such parameter, or a value it refuses)".into(),
                },
                e => e,
            })
    }

    /// Reads the vehicle's parameter `name` (PARAM_REQUEST_READ → PARAM_VALUE), asked up to
    /// `tries` times, `wait_s` wall seconds apart. A vehicle without the parameter does not
    /// answer (ArduPilot's way): an error saying so.
    pub fn get_param(&mut self, name: &str, tries: usize, wait_s: f64) -> Result<f32, GroundError> {
        let message = self.protocol.param_request_read(name);
        self.param_exchange(name, &message, tries, wait_s)
            .map_err(|e| match e {
                GroundError::Param { name, why } if why.is_empty() => GroundError::Param {
                    name,
                    why: format!(
                        "the vehicle did not answer after {tries} tries (no such parameter)"
                    ),
                },
                e => e,
            })
    }

    /// Sends `message` until a PARAM_VALUE of `name` comes back (its value), absorbing what
    /// else arrives; an empty `why` when no answer came.
    fn param_exchange(
        &mut self,
        name: &str,
        message: &MavMessage,
        tries: usize,
        wait_s: f64,
    ) -> Result<f32, GroundError> {
        for _ in 0..tries {
            self.link.send(message)?;
            let sent_s = self.now_s();
            while self.now_s() - sent_s < wait_s {
                if let Some(why) = self.link.closed() {
                    return Err(GroundError::Param {
                        name: name.into(),
                        why: format!("the connection closed: {why}"),
                    });
                }
                let Some(r) = self.link.recv_timeout(Duration::from_millis(20)) else {
                    continue;
                };
                if let Some(held) = self.protocol.param_value(&r, name) {
                    return Ok(held);
                }
                let now_s = self.now_s();
                let _ = self.protocol.absorb(now_s, &r);
            }
        }
        Err(GroundError::Param {
            name: name.into(),
            why: String::new(),
        })
    }

    /// Waits, like a ground station, for the vehicle's heartbeat, its EKF origin and its
    /// position, asking it to stream what the flight needs ([`VehicleWait`]); `on_wait` hears
    /// what is awaited (at each change and every `progress_period_s`) with the wall seconds
    /// waited. `timeout` is wall time. An EKF origin that does not come within
    /// [`ORIGIN_GRACE_S`] of the position is not waited for.
    pub fn wait_for_vehicle(
        &mut self,
        timeout: Duration,
        mut on_wait: impl FnMut(Waiting, f64),
    ) -> Result<VehicleInfo, GroundError> {
        let timeout_s = timeout.as_secs_f64();
        let mut wait = VehicleWait::new(self.now_s(), timeout_s, self.config.progress_period_s);
        loop {
            let r = self.link.recv_timeout(Duration::from_millis(20));
            let now_s = self.now_s();
            let step = wait.step(&mut self.protocol, now_s, r.as_ref(), self.link.closed());
            // A failed request shows up as a vehicle that streams nothing.
            let _ = self.send_all(&step.send);
            if let Some((waiting, waited_s)) = step.show {
                on_wait(waiting, waited_s);
            }
            if let Some(done) = step.done {
                return done;
            }
        }
    }

    /// Flies the mission: `frame` is the mission's frame (the map's home). Returns when the
    /// executor has an outcome, or when an aborted flight does not land in time
    /// ([`FlightLoop`]).
    pub fn fly<E: FlightExecutor>(
        &mut self,
        ex: &mut E,
        frame: &LocalFrame,
        mut on_update: impl FnMut(Update),
    ) -> Result<FlightSummary, GroundError> {
        // Catch up with what arrived while planning, so that the offset and the first
        // telemetry are fresh.
        while let Some(r) = self.link.recv_timeout(Duration::ZERO) {
            let now_s = self.now_s();
            let _ = self.protocol.absorb(now_s, &r);
        }
        let watcher = self.watcher.take();
        let now_s = self.now_s();
        let mut flight =
            FlightLoop::start(&mut self.protocol, ex, frame, self.config, watcher, now_s)?;
        if let Some(router) = self.home_router.take() {
            flight = flight.with_home_router(router);
        }
        // A reference's setpoints go out at ≥ 10 Hz of vehicle time, also at a speed-up.
        let wait = match ex.tracking() {
            Some(_) => Duration::from_millis(1),
            None => Duration::from_millis(5),
        };
        while !flight.finished(ex) {
            let r = self.link.recv_timeout(wait);
            let interrupted = (self.interrupt.as_ref()).is_some_and(|f| f.load(Ordering::Relaxed));
            let now_s = self.now_s();
            let closed = self.link.closed();
            let sends = flight.step(
                &mut self.protocol,
                ex,
                now_s,
                r.as_ref(),
                (closed, interrupted),
            );
            // A failed send shows up as a lost link; nothing else to do here.
            let _ = self.send_all(&sends);
            for u in flight.take_updates() {
                on_update(u);
            }
        }
        let mut summary = flight.summary(&self.protocol, self.now_s());
        summary.tracking = ex.tracking();
        Ok(summary)
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
/// its absolute heading in `param1`, at the default rate, the shortest way; a DO_CHANGE_SPEED its
/// ground speed in `param2`; a NAV_WAYPOINT its acceptance radius in `param2`).
#[allow(deprecated)] // MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: what ArduPilot and PX4 expect here.
pub fn mission_item_int(item: &MissionItem, target_system: u8, target_component: u8) -> MavMessage {
    let (command, frame, params) = match item.command {
        ItemCommand::Waypoint => (
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            [0.0, item.acceptance_radius_m, 0.0, item.yaw_deg],
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
        // Ground speed (type 1), the speed, throttle unchanged (−1).
        ItemCommand::ChangeSpeed => (
            MavCmd::MAV_CMD_DO_CHANGE_SPEED,
            MavFrame::MAV_FRAME_MISSION,
            [1.0, item.speed_m_s, -1.0, 0.0],
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

/// A fence item as MISSION_ITEM_INT: `mission_type` FENCE, `MAV_FRAME_GLOBAL_INT`, the command
/// (5001–5004), `param1` (a vertex count or a radius), latitude and longitude × 10⁷.
#[allow(deprecated)] // MAV_FRAME_GLOBAL_INT: what ArduPilot was seen taking for fence items.
pub fn fence_item_int(item: &FenceItem, target_system: u8, target_component: u8) -> MavMessage {
    use skyplan_flight::fence::{
        CIRCLE_EXCLUSION, CIRCLE_INCLUSION, POLYGON_VERTEX_EXCLUSION, POLYGON_VERTEX_INCLUSION,
    };
    let command = match item.command {
        POLYGON_VERTEX_INCLUSION => MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
        POLYGON_VERTEX_EXCLUSION => MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
        CIRCLE_INCLUSION => MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
        CIRCLE_EXCLUSION => MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION,
        // `fence_items` makes no other command.
        _ => MavCmd::MAV_CMD_NAV_FENCE_RETURN_POINT,
    };
    MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
        param1: item.param1,
        x: item.lat_e7,
        y: item.lon_e7,
        seq: item.seq,
        command,
        target_system,
        target_component,
        frame: MavFrame::MAV_FRAME_GLOBAL_INT,
        autocontinue: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
        ..Default::default()
    })
}

/// `type_mask` of a position + yaw target: ignore velocity, acceleration and yaw rate.
pub const POSITION_AND_YAW: u16 = 0x9F8;

/// `type_mask` of a reference's setpoint: position, velocity, acceleration (not force) and yaw;
/// only the yaw rate ignored.
pub const POSITION_VELOCITY_ACCELERATION_AND_YAW: u16 = 0x0800;

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
