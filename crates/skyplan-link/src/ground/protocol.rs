//! The ground station's protocol without I/O: state machines fed received messages and the wall
//! clock (seconds since the station's epoch) that return the messages to send. [`GroundStation`]
//! (super) only moves bytes and reads the clock around them; the fuzz harness drives them as they
//! are.
//!
//! - [`GroundProtocol`]: what the station knows of the vehicle (absorbing every message) and the
//!   messages of executor commands and stream requests.
//! - [`VehicleWait`]: waiting for the vehicle's heartbeat, EKF origin and position.
//! - [`UploadDriver`]: a mission or fence upload ([`MissionUpload`]) in MAVLink messages.
//! - [`FenceDownload`]: the fence read back ([`MissionDownload`]) in MAVLink messages.
//! - [`FlightLoop`]: the flight loop's decisions: executor events from messages and time, commands
//!   out, lost link, timeout, interrupt, progress, the route watcher.
//!
//! [`GroundStation`]: super::GroundStation

use super::{
    Autopilot, FlightSummary, GroundConfig, GroundError, LogRow, ORIGIN_GRACE_S, POSITION_AND_YAW,
    POSITION_VELOCITY_ACCELERATION_AND_YAW, Progress, SYSTEM_ID, Update, UploadReport, VehicleInfo,
    Waiting, fence_item_int, global_lla, grid_convergence_rad, mission_item_int,
};
use crate::Received;
use crate::obstacle::{reading_from_distance_sensor, reading_from_obstacle_distance};
use crate::streams::STREAMS;
use mavlink::dialects::common::*;
use skyplan_flight::executor::{
    Command, CommandKind, Event, FailsafeAction, FlightExecutor, Output, Telemetry, VehicleMode,
    wrap_angle_rad,
};
use skyplan_flight::fence::{
    DownloadEvent, DownloadSend, DownloadStatus, FenceItem, MissionDownload,
};
use skyplan_flight::flat_earth::FlatEarth;
use skyplan_flight::modes::{arducopter, px4};
use skyplan_flight::reference::Setpoint;
use skyplan_flight::sensing::{
    HomeRouter, ObstacleReading, ReplanEvent, RouteDecision, RouteWatcher,
};
use skyplan_flight::upload::{
    MissionPlan, MissionUpload, UploadConfig, UploadEvent, UploadSend, UploadStatus,
};
use skyplan_frames::{Lla, LocalFrame, Ned};

/// Our clock running this much further than the vehicle's between two of its positions, in
/// wall-clock seconds (ours runs at `--speedup` times the wall clock), is told as a warning: a
/// simulator that stalled, a link that held messages back.
pub const STALL_WARN_WALL_S: f64 = 1.0;

/// What the ground station knows of the vehicle, from every message absorbed.
#[derive(Debug, Clone)]
pub struct GroundProtocol {
    vehicle: Option<(u8, u8)>,
    autopilot: Autopilot,
    /// Wall seconds of the last heartbeat heard.
    last_heartbeat_s: Option<f64>,
    heartbeats: usize,
    armed: bool,
    custom_mode: u32,
    global: Option<GLOBAL_POSITION_INT_DATA>,
    local: Option<LOCAL_POSITION_NED_DATA>,
    origin: Option<GPS_GLOBAL_ORIGIN_DATA>,
    /// Telemetry arrived: the stream requests work.
    streaming: bool,
    yaw_rad: f64,
    on_ground: Option<bool>,
    last_arm_request: CommandKind,
    last_mode_request: CommandKind,
    /// How high the vehicle's home stands above the map's home, metres (0 on flat ground):
    /// the station's altitudes are above the map's home, the vehicle's above its own.
    home_up_m: f64,
}

impl Default for GroundProtocol {
    fn default() -> Self {
        Self::new()
    }
}

/// The rate the ground station asks for the autopilot's DISTANCE_SENSOR messages at, Hz
/// (ArduPilot sends one per proximity sector at this rate).
pub const DISTANCE_SENSOR_RATE_HZ: f64 = 5.0;

impl GroundProtocol {
    /// A station that knows nothing yet.
    pub fn new() -> Self {
        Self {
            vehicle: None,
            autopilot: Autopilot::Other,
            last_heartbeat_s: None,
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
            home_up_m: 0.0,
        }
    }

    /// Over terrain: the vehicle's home (where it armed) stands `up_m` above the map's home.
    /// From then on every altitude the station takes or gives (telemetry, targets, take-off)
    /// is above the map's home, converted to and from the vehicle's relative altitudes.
    ///
    /// ```
    /// use skyplan_link::ground::protocol::GroundProtocol;
    /// let mut p = GroundProtocol::new();
    /// p.set_home_up_m(12.5);
    /// assert_eq!(p.vehicle_alt_m(42.5), 30.0);
    /// ```
    pub fn set_home_up_m(&mut self, up_m: f64) {
        if up_m.is_finite() {
            self.home_up_m = up_m;
        }
    }

    /// The vehicle's relative altitude (above where it armed) of a point `alt_m` above the
    /// map's home.
    pub fn vehicle_alt_m(&self, alt_m: f64) -> f64 {
        alt_m - self.home_up_m
    }

    /// The vehicle's mode from its last heartbeat.
    pub fn mode(&self) -> VehicleMode {
        match self.autopilot {
            Autopilot::Px4 => px4::vehicle_mode(self.custom_mode),
            _ => arducopter::vehicle_mode(self.custom_mode),
        }
    }

    /// The vehicle is in the mode that obeys position targets.
    pub fn guided(&self) -> bool {
        match self.autopilot {
            Autopilot::Px4 => px4::main_mode(self.custom_mode) == px4::MAIN_OFFBOARD,
            _ => self.custom_mode == arducopter::GUIDED,
        }
    }

    /// Heartbeats heard from the vehicle.
    pub fn heartbeats(&self) -> usize {
        self.heartbeats
    }

    /// The vehicle's (system, component), once heard; (1, 1) before.
    fn target(&self) -> (u8, u8) {
        self.vehicle.unwrap_or((1, 1))
    }

    /// PARAM_SET of `name` (at most 16 bytes) to `value` on the vehicle, as a REAL32 (ArduPilot
    /// and PX4 both take a parameter's value as a float in PARAM_SET).
    pub fn param_set(&self, name: &str, value: f32) -> MavMessage {
        let (target_system, target_component) = self.target();
        MavMessage::PARAM_SET(PARAM_SET_DATA {
            param_value: value,
            target_system,
            target_component,
            param_id: name.into(),
            param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
        })
    }

    /// PARAM_REQUEST_READ of `name` (by name: `param_index` −1); the vehicle answers with
    /// PARAM_VALUE, or not at all when it has no such parameter.
    pub fn param_request_read(&self, name: &str) -> MavMessage {
        let (target_system, target_component) = self.target();
        MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
            param_index: -1,
            target_system,
            target_component,
            param_id: name.into(),
        })
    }

    /// The value of parameter `name` that a PARAM_VALUE from the vehicle carries, if `r` is one.
    pub fn param_value(&self, r: &Received, name: &str) -> Option<f32> {
        match &r.message {
            MavMessage::PARAM_VALUE(p)
                if self.is_from_vehicle(r)
                    && p.param_id
                        .to_str()
                        .is_ok_and(|id| id.trim_end_matches('\0') == name) =>
            {
                Some(p.param_value)
            }
            _ => None,
        }
    }

    /// The message comes from our vehicle (or any, before one has been heard).
    pub fn is_from_vehicle(&self, r: &Received) -> bool {
        self.vehicle
            .is_none_or(|(sys, _)| u32::from(sys) == r.header.system_id)
    }

    /// Updates what we know from one message received at `now_s`; returns an executor event for
    /// heartbeats (the mode), acks, mission progress and texts.
    pub fn absorb(&mut self, now_s: f64, r: &Received) -> Option<Event> {
        let from_vehicle = self.is_from_vehicle(r);
        self.streaming |= from_vehicle
            && matches!(
                r.message,
                MavMessage::GLOBAL_POSITION_INT(_) | MavMessage::ATTITUDE(_)
            );
        match &r.message {
            MavMessage::HEARTBEAT(h) => self.heartbeat(now_s, r, h),
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
            MavMessage::COMMAND_ACK(a) => self.ack(a),
            MavMessage::MISSION_ITEM_REACHED(m) => Some(Event::MissionItemReached(m.seq)),
            MavMessage::MISSION_CURRENT(m) => Some(Event::MissionCurrent(m.seq)),
            MavMessage::STATUSTEXT(t) => {
                let text = t.text.to_str().unwrap_or("").trim_end_matches('\0');
                Some(Event::StatusText(text.to_string()))
            }
            _ => None,
        }
    }

    /// A HEARTBEAT: the first autopilot's picks the vehicle; ours tells its mode and arming.
    fn heartbeat(&mut self, now_s: f64, r: &Received, h: &HEARTBEAT_DATA) -> Option<Event> {
        if h.mavtype == MavType::MAV_TYPE_GCS || h.autopilot == MavAutopilot::MAV_AUTOPILOT_INVALID
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
        } else if !self.is_from_vehicle(r) {
            return None;
        }
        self.last_heartbeat_s = Some(now_s);
        self.heartbeats += 1;
        self.armed = h
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        self.custom_mode = h.custom_mode;
        Some(Event::Mode(self.mode()))
    }

    /// A COMMAND_ACK of a command the executor sent.
    fn ack(&self, a: &COMMAND_ACK_DATA) -> Option<Event> {
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

    /// A COMMAND_LONG to the vehicle.
    fn command_long(&self, command: MavCmd, p: [f32; 7]) -> MavMessage {
        crate::messages::command_long(self.target(), command, p)
    }

    /// DO_SET_MODE to a mode: ArduCopter's number in param2; PX4's main mode in param2, its sub
    /// mode in param3.
    fn set_mode(&self, (arducopter_mode, px4_main, px4_sub): (u32, u32, u32)) -> MavMessage {
        let (mode, sub) = match self.autopilot {
            Autopilot::Px4 => (px4_main, px4_sub),
            _ => (arducopter_mode, 0),
        };
        self.command_long(
            MavCmd::MAV_CMD_DO_SET_MODE,
            [1.0, mode as f32, sub as f32, 0.0, 0.0, 0.0, 0.0],
        )
    }

    /// The messages of an executor command; `frame` is the mission's, `convergence_rad` the true
    /// bearing of its grid north at the vehicle. An error when a target has no latitude/longitude.
    pub fn command(
        &mut self,
        c: Command,
        frame: &LocalFrame,
        convergence_rad: f64,
    ) -> Result<Vec<MavMessage>, String> {
        let nan = f32::NAN;
        Ok(match c {
            Command::TakeControl => {
                self.last_mode_request = CommandKind::TakeControl;
                vec![self.set_mode((arducopter::GUIDED, px4::MAIN_OFFBOARD, 0))]
            }
            Command::Hold => {
                self.last_mode_request = CommandKind::Hold;
                vec![self.set_mode((arducopter::LOITER, px4::MAIN_AUTO, px4::SUB_AUTO_LOITER))]
            }
            Command::ReturnToLaunch => {
                self.last_mode_request = CommandKind::ReturnToLaunch;
                vec![self.set_mode((arducopter::RTL, px4::MAIN_AUTO, px4::SUB_AUTO_RTL))]
            }
            Command::StartMission => {
                // AUTO first (ArduCopter starts a mission on the ground only with MISSION_START).
                self.last_mode_request = CommandKind::StartMission;
                vec![
                    self.set_mode((arducopter::AUTO, px4::MAIN_AUTO, px4::SUB_AUTO_MISSION)),
                    self.command_long(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]),
                ]
            }
            Command::Arm | Command::Disarm => {
                let arm = matches!(c, Command::Arm);
                self.last_arm_request = if arm {
                    CommandKind::Arm
                } else {
                    CommandKind::Disarm
                };
                let p1 = if arm { 1.0 } else { 0.0 };
                vec![self.command_long(
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                    [p1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                )]
            }
            Command::Takeoff { alt_m } => vec![self.command_long(
                MavCmd::MAV_CMD_NAV_TAKEOFF,
                [
                    0.0,
                    0.0,
                    0.0,
                    nan,
                    0.0,
                    0.0,
                    self.vehicle_alt_m(alt_m) as f32,
                ],
            )],
            Command::Land => vec![self.command_long(
                MavCmd::MAV_CMD_NAV_LAND,
                [0.0, 0.0, 0.0, nan, 0.0, 0.0, 0.0],
            )],
            Command::GoTo {
                north_m,
                east_m,
                down_m,
                yaw_rad,
            } => vec![self.position_target(
                frame,
                [north_m, east_m, down_m],
                wrap_angle_rad(yaw_rad + convergence_rad),
            )?],
            Command::Track { setpoint, .. } => {
                vec![self.track_target(frame, &setpoint, convergence_rad, 0)?]
            }
        })
    }

    /// SET_POSITION_TARGET_GLOBAL_INT of a reference's setpoint in the mission's frame:
    /// position (altitude relative to home), velocity and acceleration (turned from the map's
    /// grid north to true north by `convergence_rad`) and yaw, `type_mask`
    /// [`POSITION_VELOCITY_ACCELERATION_AND_YAW`] (only the yaw rate ignored). `time_boot_ms` is
    /// the vehicle's time at which the setpoint holds (0: unknown), for the vehicle to make up
    /// the transport delay as MAVLink describes the field.
    ///
    /// ArduPilot, though, keeps the acceleration of such a target only from
    /// SET_POSITION_TARGET_LOCAL_NED (its GLOBAL_INT handler takes position and velocity,
    /// `set_destination_posvel`, seen against ArduCopter SITL: the guided target's acceleration
    /// logged 0 throughout): once the vehicle's EKF origin (GPS_GLOBAL_ORIGIN) and position are
    /// known, an ArduPilot vehicle gets the same target in its own frame instead
    /// ([`GroundProtocol::in_vehicle_frame`]).
    pub fn track_target(
        &self,
        frame: &LocalFrame,
        setpoint: &Setpoint,
        convergence_rad: f64,
        time_boot_ms: u32,
    ) -> Result<MavMessage, String> {
        let yaw_rad = wrap_angle_rad(setpoint.yaw_rad + convergence_rad);
        let mut m = self.position_target(frame, setpoint.point_ned, yaw_rad)?;
        let (c, s) = (convergence_rad.cos(), convergence_rad.sin());
        let true_north =
            |[n, e, d]: [f64; 3]| [(n * c - e * s) as f32, (n * s + e * c) as f32, d as f32];
        if let MavMessage::SET_POSITION_TARGET_GLOBAL_INT(t) = &mut m {
            [t.vx, t.vy, t.vz] = true_north(setpoint.vel_ned_m_s);
            [t.afx, t.afy, t.afz] = true_north(setpoint.accel_ned_m_s2);
            t.type_mask =
                PositionTargetTypemask::from_bits_truncate(POSITION_VELOCITY_ACCELERATION_AND_YAW);
            t.time_boot_ms = time_boot_ms;
            if self.autopilot != Autopilot::Px4 {
                let [n, e, d] = setpoint.point_ned;
                let lla = frame
                    .lla_from_ned(Ned {
                        north_m: n,
                        east_m: e,
                        down_m: 0.0,
                    })
                    .map_err(|e| format!("the target has no latitude/longitude: {e}"))?;
                let alt_m = self.vehicle_alt_m(-d);
                if let Some(local) = self.in_vehicle_frame(t, [lla.lat_deg, lla.lon_deg], alt_m) {
                    return Ok(local);
                }
            }
        }
        Ok(m)
    }

    /// A GLOBAL_INT target (at `lat_lon_deg`, `alt_m` above home) as SET_POSITION_TARGET_LOCAL_NED
    /// in ArduPilot's frame: north and east of the EKF origin by ArduPilot's own flat-earth
    /// formulas ([`FlatEarth`]), down from the origin's altitude (home's altitude above mean sea
    /// level is GLOBAL_POSITION_INT's `alt − relative_alt`); velocity, acceleration, yaw, mask and
    /// stamp unchanged (already true north). `None` until the origin and a position are known.
    pub fn in_vehicle_frame(
        &self,
        t: &SET_POSITION_TARGET_GLOBAL_INT_DATA,
        [lat_deg, lon_deg]: [f64; 2],
        alt_m: f64,
    ) -> Option<MavMessage> {
        let origin = self.origin.as_ref()?;
        let global = self.global.as_ref()?;
        let earth = FlatEarth::new(
            f64::from(origin.latitude) * 1e-7,
            f64::from(origin.longitude) * 1e-7,
        );
        let [x, y] = earth.ne_from_lat_lon(lat_deg, lon_deg);
        let home_amsl_m = f64::from(global.alt - global.relative_alt) * 1e-3;
        let origin_amsl_m = f64::from(origin.altitude) * 1e-3;
        let z = -(alt_m + home_amsl_m - origin_amsl_m);
        Some(MavMessage::SET_POSITION_TARGET_LOCAL_NED(
            SET_POSITION_TARGET_LOCAL_NED_DATA {
                time_boot_ms: t.time_boot_ms,
                x: x as f32,
                y: y as f32,
                z: z as f32,
                vx: t.vx,
                vy: t.vy,
                vz: t.vz,
                afx: t.afx,
                afy: t.afy,
                afz: t.afz,
                yaw: t.yaw,
                yaw_rate: t.yaw_rate,
                type_mask: t.type_mask,
                target_system: t.target_system,
                target_component: t.target_component,
                coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
            },
        ))
    }

    /// SET_POSITION_TARGET_GLOBAL_INT of a point of the mission's frame (position and yaw,
    /// altitude relative to home); `yaw_rad` from true north.
    fn position_target(
        &self,
        frame: &LocalFrame,
        [north_m, east_m, down_m]: [f64; 3],
        yaw_rad: f64,
    ) -> Result<MavMessage, String> {
        let (sys, comp) = self.target();
        let lla = frame
            .lla_from_ned(Ned {
                north_m,
                east_m,
                down_m: 0.0,
            })
            .map_err(|e| format!("the target has no latitude/longitude: {e}"))?;
        #[allow(deprecated)] // GLOBAL_RELATIVE_ALT_INT: what ArduPilot and PX4 expect here.
        let coordinate_frame = MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT;
        Ok(MavMessage::SET_POSITION_TARGET_GLOBAL_INT(
            SET_POSITION_TARGET_GLOBAL_INT_DATA {
                lat_int: (lla.lat_deg * 1e7).round() as i32,
                lon_int: (lla.lon_deg * 1e7).round() as i32,
                alt: self.vehicle_alt_m(-down_m) as f32,
                yaw: yaw_rad as f32,
                type_mask: PositionTargetTypemask::from_bits_truncate(POSITION_AND_YAW),
                target_system: sys,
                target_component: comp,
                coordinate_frame,
                ..Default::default()
            },
        ))
    }

    /// Asks the vehicle to stream what the flight needs (SET_MESSAGE_INTERVAL, and the
    /// autopilot's proximity readings, DISTANCE_SENSOR, at [`DISTANCE_SENSOR_RATE_HZ`]; with `fallback`,
    /// REQUEST_DATA_STREAM of every stream too, for autopilots without the former).
    pub fn stream_requests(&self, fallback: bool) -> Vec<MavMessage> {
        let mut out: Vec<MavMessage> = STREAMS
            .iter()
            .map(|s| {
                let interval_us = (1e6 / s.ground_rate_hz) as f32;
                self.command_long(
                    MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
                    [s.id as f32, interval_us, 0.0, 0.0, 0.0, 0.0, 0.0],
                )
            })
            .collect();
        // The autopilot's own proximity readings (ArduPilot streams them only when asked).
        out.push(self.command_long(
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            [
                <DISTANCE_SENSOR_DATA as mavlink::MessageData>::ID as f32,
                (1e6 / DISTANCE_SENSOR_RATE_HZ) as f32,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
        ));
        if fallback {
            let (sys, comp) = self.target();
            #[allow(deprecated)] // superseded by SET_MESSAGE_INTERVAL, still honoured by ArduPilot
            out.push(MavMessage::REQUEST_DATA_STREAM(REQUEST_DATA_STREAM_DATA {
                req_message_rate: 10,
                target_system: sys,
                target_component: comp,
                req_stream_id: MavDataStream::MAV_DATA_STREAM_ALL,
                start_stop: 1,
            }));
        }
        out
    }

    /// A GLOBAL_POSITION_INT as executor telemetry in the mission's frame (headings and
    /// velocities turned by `convergence_rad`); `None` without a fix or a usable position.
    pub fn telemetry(
        &self,
        g: &GLOBAL_POSITION_INT_DATA,
        frame: &LocalFrame,
        convergence_rad: f64,
    ) -> Option<Telemetry> {
        if g.lat == 0 && g.lon == 0 {
            return None;
        }
        let ned = frame.ned_from_lla(global_lla(g)).ok()?;
        let (c, s) = (convergence_rad.cos(), convergence_rad.sin());
        let [vn, ve] = [f64::from(g.vx) * 0.01, f64::from(g.vy) * 0.01];
        Some(Telemetry {
            north_m: ned.north_m,
            east_m: ned.east_m,
            down_m: -(f64::from(g.relative_alt) * 1e-3 + self.home_up_m),
            velocity_ned_m_s: [vn * c + ve * s, ve * c - vn * s, f64::from(g.vz) * 0.01],
            yaw_rad: wrap_angle_rad(self.yaw_rad - convergence_rad),
            armed: self.armed,
            guided: self.guided(),
            on_ground: self.on_ground,
            sample_time_s: None,
        })
    }

    /// The vehicle as known, once it has a heartbeat and a position fix.
    fn vehicle_info(&self) -> Option<VehicleInfo> {
        let (system_id, component_id) = self.vehicle?;
        let g = self.global.as_ref().filter(|g| g.lat != 0 || g.lon != 0)?;
        Some(VehicleInfo {
            system_id,
            component_id,
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
        })
    }

    /// What never came within `timeout_s`, for the error of a failed wait.
    fn missing(&self, timeout_s: f64) -> String {
        let within = format!("within {timeout_s:.1} s");
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
}

/// One step of [`VehicleWait`]: what to send, what to show, and the end of the wait.
#[derive(Debug)]
pub struct WaitStep {
    /// Messages to send (stream requests).
    pub send: Vec<MavMessage>,
    /// What is awaited and the wall seconds waited, when worth showing (at each change and every
    /// `progress_period_s`).
    pub show: Option<(Waiting, f64)>,
    /// The vehicle, or why the wait failed; `None` while waiting.
    pub done: Option<Result<VehicleInfo, GroundError>>,
}

/// Waiting, like a ground station, for the vehicle's heartbeat, its EKF origin and its position,
/// asking it to stream what the flight needs. An EKF origin that does not come within
/// [`ORIGIN_GRACE_S`] of the position is not waited for (not every autopilot sends it).
#[derive(Debug, Clone)]
pub struct VehicleWait {
    start_s: f64,
    timeout_s: f64,
    progress_period_s: f64,
    asked_s: Option<f64>,
    first_ask_s: Option<f64>,
    fallback: bool,
    position_since_s: Option<f64>,
    shown: Option<(Waiting, f64)>,
}

impl VehicleWait {
    /// A wait starting at `now_s`, for at most `timeout_s` wall seconds.
    pub fn new(now_s: f64, timeout_s: f64, progress_period_s: f64) -> Self {
        Self {
            start_s: now_s,
            timeout_s,
            progress_period_s,
            asked_s: None,
            first_ask_s: None,
            fallback: false,
            position_since_s: None,
            shown: None,
        }
    }

    /// One step at `now_s`, after `received` (if a message came) was absorbed by `p`; `closed`
    /// when the connection has closed.
    pub fn step(
        &mut self,
        p: &mut GroundProtocol,
        now_s: f64,
        received: Option<&Received>,
        closed: Option<&str>,
    ) -> WaitStep {
        if let Some(r) = received {
            let _ = p.absorb(now_s, r);
        }
        let mut step = WaitStep {
            send: Vec::new(),
            show: None,
            done: None,
        };
        if let Some(why) = closed {
            step.done = Some(Err(GroundError::NoVehicle(format!(
                "the connection closed: {why}"
            ))));
            return step;
        }
        if p.vehicle.is_some() && self.asked_s.is_none_or(|t| now_s - t > 1.0) {
            let first = *self.first_ask_s.get_or_insert(now_s);
            // Nothing streams 3 s after SET_MESSAGE_INTERVAL: ask the old way too.
            self.fallback |= !p.streaming && now_s - first > 3.0;
            step.send = p.stream_requests(self.fallback);
            self.asked_s = Some(now_s);
        }
        let fix = p.global.as_ref().is_some_and(|g| g.lat != 0 || g.lon != 0);
        let position_ready = fix && p.local.is_some();
        if position_ready {
            self.position_since_s.get_or_insert(now_s);
        }
        let origin_waited = self
            .position_since_s
            .is_some_and(|t| now_s - t > ORIGIN_GRACE_S);
        if position_ready
            && (p.origin.is_some() || origin_waited)
            && let Some(info) = p.vehicle_info()
        {
            step.done = Some(Ok(info));
            return step;
        }
        let waiting = if p.vehicle.is_none() {
            Waiting::Heartbeat
        } else if p.origin.is_none() && (position_ready || p.local.is_none()) {
            Waiting::EkfOrigin
        } else {
            Waiting::Position
        };
        if self
            .shown
            .is_none_or(|(w, t)| w != waiting || now_s - t >= self.progress_period_s)
        {
            self.shown = Some((waiting, now_s));
            step.show = Some((waiting, now_s - self.start_s));
        }
        if now_s - self.start_s > self.timeout_s {
            step.done = Some(Err(GroundError::NoVehicle(p.missing(self.timeout_s))));
        }
        step
    }
}

/// A mission upload in MAVLink messages: MISSION_COUNT, each requested item as MISSION_ITEM_INT
/// (MISSION_REQUEST_INT and MISSION_REQUEST answered alike), until the vehicle's MISSION_ACK.
#[derive(Debug)]
pub struct UploadDriver<'a> {
    payload: Payload<'a>,
    up: MissionUpload,
    start_s: f64,
}

/// What an [`UploadDriver`] uploads.
#[derive(Debug, Clone, Copy)]
enum Payload<'a> {
    /// A mission (`mission_type` MISSION).
    Mission(&'a MissionPlan),
    /// A fence (`mission_type` FENCE).
    Fence(&'a [FenceItem]),
}

impl Payload<'_> {
    fn len(&self) -> usize {
        match self {
            Payload::Mission(p) => p.items.len(),
            Payload::Fence(f) => f.len(),
        }
    }

    fn mission_type(&self) -> MavMissionType {
        match self {
            Payload::Mission(_) => MavMissionType::MAV_MISSION_TYPE_MISSION,
            Payload::Fence(_) => MavMissionType::MAV_MISSION_TYPE_FENCE,
        }
    }
}

/// The name of a MISSION_ACK's result without its `MAV_MISSION_` prefix (`UNSUPPORTED`).
pub fn mission_result_name(result: MavMissionResult) -> String {
    format!("{result:?}")
        .trim_start_matches("MAV_MISSION_")
        .to_string()
}

impl<'a> UploadDriver<'a> {
    /// Starts uploading `plan` at `now_s`: the driver and the first messages.
    pub fn start(
        p: &GroundProtocol,
        plan: &'a MissionPlan,
        config: UploadConfig,
        now_s: f64,
    ) -> Result<(Self, Vec<MavMessage>), GroundError> {
        Self::start_payload(p, Payload::Mission(plan), config, now_s)
    }

    /// Starts uploading a fence at `now_s`: every message of the exchange carries
    /// `mission_type` FENCE, and only the vehicle's messages of that type are heeded.
    pub fn start_fence(
        p: &GroundProtocol,
        fence: &'a [FenceItem],
        config: UploadConfig,
        now_s: f64,
    ) -> Result<(Self, Vec<MavMessage>), GroundError> {
        Self::start_payload(p, Payload::Fence(fence), config, now_s)
    }

    fn start_payload(
        p: &GroundProtocol,
        payload: Payload<'a>,
        config: UploadConfig,
        now_s: f64,
    ) -> Result<(Self, Vec<MavMessage>), GroundError> {
        let Ok(count) = u16::try_from(payload.len()) else {
            return Err(GroundError::Upload(format!(
                "{} items do not fit in a mission",
                payload.len()
            )));
        };
        let mut up = MissionUpload::new(count, config);
        let sends = up.start(0.0);
        let driver = Self {
            payload,
            up,
            start_s: now_s,
        };
        let out = driver.messages(p, &sends);
        Ok((driver, out))
    }

    /// One step at `now_s` with the message received, if any: the messages to send.
    pub fn step(
        &mut self,
        p: &mut GroundProtocol,
        now_s: f64,
        received: Option<&Received>,
    ) -> Vec<MavMessage> {
        let kind = self.payload.mission_type();
        let event = received.map_or(UploadEvent::Tick, |r| {
            let to_us = |target: u8| target == 0 || target == SYSTEM_ID;
            let from_vehicle = p.is_from_vehicle(r);
            let _ = p.absorb(now_s, r);
            match &r.message {
                MavMessage::MISSION_REQUEST_INT(q)
                    if from_vehicle && to_us(q.target_system) && q.mission_type == kind =>
                {
                    UploadEvent::Request { seq: q.seq }
                }
                #[allow(deprecated)]
                MavMessage::MISSION_REQUEST(q)
                    if from_vehicle && to_us(q.target_system) && q.mission_type == kind =>
                {
                    UploadEvent::Request { seq: q.seq }
                }
                MavMessage::MISSION_ACK(a)
                    if from_vehicle && to_us(a.target_system) && a.mission_type == kind =>
                {
                    UploadEvent::Ack(match a.mavtype {
                        MavMissionResult::MAV_MISSION_ACCEPTED => Ok(()),
                        other => Err(mission_result_name(other)),
                    })
                }
                _ => UploadEvent::Tick,
            }
        });
        let sends = self.up.handle(now_s - self.start_s, event);
        self.messages(p, &sends)
    }

    /// `None` while in progress; then the report at `now_s` or why it failed.
    pub fn done(&self, now_s: f64) -> Option<Result<UploadReport, GroundError>> {
        match self.up.status() {
            UploadStatus::Done => Some(Ok(UploadReport {
                items: self.payload.len(),
                requests: self.up.requests(),
                resends: self.up.resends(),
                wall_time_s: now_s - self.start_s,
            })),
            UploadStatus::Failed(why) => Some(Err(match self.payload {
                Payload::Mission(_) => GroundError::Upload(why.clone()),
                Payload::Fence(_) => GroundError::Fence(format!(
                    "upload: {}",
                    why.replace("the mission", "the fence")
                )),
            })),
            UploadStatus::InProgress => None,
        }
    }

    fn messages(&self, p: &GroundProtocol, sends: &[UploadSend]) -> Vec<MavMessage> {
        let (sys, comp) = p.target();
        let mission_type = self.payload.mission_type();
        sends
            .iter()
            .filter_map(|s| match *s {
                UploadSend::Count(count) => Some(MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                    count,
                    target_system: sys,
                    target_component: comp,
                    mission_type,
                    ..Default::default()
                })),
                UploadSend::Item(seq) => match self.payload {
                    Payload::Mission(plan) => (plan.items.get(usize::from(seq)))
                        .map(|item| mission_item_int(item, sys, comp)),
                    Payload::Fence(fence) => {
                        (fence.get(usize::from(seq))).map(|item| fence_item_int(item, sys, comp))
                    }
                },
            })
            .collect()
    }
}

/// A fence read-back (`mission_type` FENCE) in MAVLink messages: MISSION_REQUEST_LIST →
/// MISSION_COUNT → MISSION_REQUEST_INT per item → MISSION_ITEM_INT → MISSION_ACK
/// ([`MissionDownload`]).
#[derive(Debug)]
pub struct FenceDownload {
    down: MissionDownload<FenceItem>,
    start_s: f64,
}

impl FenceDownload {
    /// Starts at `now_s`: the driver and the MISSION_REQUEST_LIST.
    pub fn start(p: &GroundProtocol, config: UploadConfig, now_s: f64) -> (Self, Vec<MavMessage>) {
        let mut down = MissionDownload::new(config);
        let sends = down.start(0.0);
        let d = Self {
            down,
            start_s: now_s,
        };
        let out = d.messages(p, &sends);
        (d, out)
    }

    /// One step at `now_s` with the message received, if any: the messages to send.
    pub fn step(
        &mut self,
        p: &mut GroundProtocol,
        now_s: f64,
        received: Option<&Received>,
    ) -> Vec<MavMessage> {
        let fence = MavMissionType::MAV_MISSION_TYPE_FENCE;
        let event = received.map_or(DownloadEvent::Tick, |r| {
            let to_us = |target: u8| target == 0 || target == SYSTEM_ID;
            let from_vehicle = p.is_from_vehicle(r);
            let _ = p.absorb(now_s, r);
            match &r.message {
                MavMessage::MISSION_COUNT(c)
                    if from_vehicle && to_us(c.target_system) && c.mission_type == fence =>
                {
                    DownloadEvent::Count(c.count)
                }
                MavMessage::MISSION_ITEM_INT(i)
                    if from_vehicle && to_us(i.target_system) && i.mission_type == fence =>
                {
                    DownloadEvent::Item {
                        seq: i.seq,
                        item: FenceItem {
                            seq: i.seq,
                            command: i.command as u16,
                            param1: i.param1,
                            lat_e7: i.x,
                            lon_e7: i.y,
                        },
                    }
                }
                MavMessage::MISSION_ACK(a)
                    if from_vehicle
                        && to_us(a.target_system)
                        && a.mission_type == fence
                        && a.mavtype != MavMissionResult::MAV_MISSION_ACCEPTED =>
                {
                    DownloadEvent::Refused(mission_result_name(a.mavtype))
                }
                _ => DownloadEvent::Tick,
            }
        });
        let sends = self.down.handle(now_s - self.start_s, event);
        self.messages(p, &sends)
    }

    /// `None` while in progress; then the items read back, or why it failed.
    pub fn done(&self) -> Option<Result<Vec<FenceItem>, GroundError>> {
        match self.down.status() {
            DownloadStatus::Done(items) => Some(Ok(items.clone())),
            DownloadStatus::Failed(why) => {
                Some(Err(GroundError::Fence(format!("read-back: {why}"))))
            }
            DownloadStatus::InProgress => None,
        }
    }

    fn messages(&self, p: &GroundProtocol, sends: &[DownloadSend]) -> Vec<MavMessage> {
        let (target_system, target_component) = p.target();
        let mission_type = MavMissionType::MAV_MISSION_TYPE_FENCE;
        sends
            .iter()
            .map(|s| match *s {
                DownloadSend::RequestList => {
                    MavMessage::MISSION_REQUEST_LIST(MISSION_REQUEST_LIST_DATA {
                        target_system,
                        target_component,
                        mission_type,
                    })
                }
                DownloadSend::Request(seq) => {
                    MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                        seq,
                        target_system,
                        target_component,
                        mission_type,
                    })
                }
                DownloadSend::Ack => MavMessage::MISSION_ACK(MISSION_ACK_DATA {
                    target_system,
                    target_component,
                    mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
                    mission_type,
                    ..Default::default()
                }),
            })
            .collect()
    }
}

/// The flight loop's decisions, fed received messages and the wall clock: executor events in,
/// MAVLink messages out, and [`Update`]s for the caller to tell.
pub struct FlightLoop {
    frame: LocalFrame,
    config: GroundConfig,
    convergence_rad: f64,
    speedup: f64,
    start_s: f64,
    last_tick_s: f64,
    last_request_s: f64,
    last_progress_s: Option<f64>,
    aborted_at_s: Option<f64>,
    gave_up: bool,
    closed_reported: bool,
    link_lost: bool,
    last_global_ms: Option<u32>,
    /// When (our clock) the last position arrived.
    last_global_at_s: Option<f64>,
    last_mode: Option<VehicleMode>,
    sent_targets: usize,
    /// The last reference setpoint streamed and when (the log's target while streaming).
    last_track: Option<(f64, skyplan_flight::reference::Setpoint)>,
    /// The vehicle's clock minus ours (vehicle seconds): the largest seen, i.e. the position
    /// that came fastest; frozen once a reference's setpoints are stamped with it.
    boot_offset_s: Option<f64>,
    offset_frozen: bool,
    readings: usize,
    last_hits_ne: Vec<[f64; 2]>,
    warned: Vec<String>,
    replans: Vec<ReplanEvent>,
    log: Vec<LogRow>,
    updates: Vec<Update>,
    watcher: Option<Box<dyn RouteWatcher + Send>>,
    home_router: Option<Box<dyn HomeRouter + Send>>,
}

/// What one message brought: executor events and a sensor reading.
struct FromMessage {
    events: Vec<Event>,
    reading: Option<ObstacleReading>,
}

impl FlightLoop {
    /// A flight starting at `now_s` in the mission's `frame`, `watcher` (if any) seeing the
    /// sensor readings. The vehicle's position must be known (after a [`VehicleWait`]).
    pub fn start<E: FlightExecutor>(
        p: &mut GroundProtocol,
        ex: &E,
        frame: &LocalFrame,
        config: GroundConfig,
        watcher: Option<Box<dyn RouteWatcher + Send>>,
        now_s: f64,
    ) -> Result<Self, GroundError> {
        if watcher.is_some() && !ex.replans() {
            return Err(GroundError::Replan(
                "an uploaded mission (AUTO, --upload) cannot change its route in flight; fly it in GUIDED (without --upload) to replan from sensor readings".into(),
            ));
        }
        let Some(g) = p.global.clone() else {
            return Err(GroundError::NoVehicle(
                "call wait_for_vehicle first: no position yet".into(),
            ));
        };
        // True bearing of the map's grid north at the vehicle (UTM convergence; 0.37° at the
        // FCND home): headings are turned by it between the vehicle and the plan.
        let convergence_rad = grid_convergence_rad(frame, global_lla(&g))?;
        // The silence clock starts now: planning may have taken a while.
        p.last_heartbeat_s = Some(now_s);
        Ok(Self::with_convergence(
            frame,
            config,
            convergence_rad,
            watcher,
            now_s,
        ))
    }

    /// A flight with a given grid convergence (for harnesses without a vehicle position).
    pub fn with_convergence(
        frame: &LocalFrame,
        config: GroundConfig,
        convergence_rad: f64,
        watcher: Option<Box<dyn RouteWatcher + Send>>,
        now_s: f64,
    ) -> Self {
        Self {
            frame: *frame,
            config,
            convergence_rad,
            speedup: config.speedup.max(0.1),
            start_s: now_s,
            last_tick_s: now_s,
            last_request_s: now_s,
            last_progress_s: None,
            aborted_at_s: None,
            gave_up: false,
            closed_reported: false,
            link_lost: false,
            last_global_ms: None,
            last_global_at_s: None,
            last_mode: None,
            sent_targets: 0,
            last_track: None,
            boot_offset_s: None,
            offset_frozen: false,
            readings: 0,
            last_hits_ne: Vec::new(),
            warned: Vec::new(),
            replans: Vec::new(),
            log: Vec::new(),
            updates: Vec::new(),
            watcher,
            home_router: None,
        }
    }

    /// Plans the way home with `router` when the executor stops with
    /// [`FailsafeAction::Return`] (without one, the vehicle lands where it is).
    pub fn with_home_router(mut self, router: Box<dyn HomeRouter + Send>) -> Self {
        self.home_router = Some(router);
        self
    }

    /// Vehicle seconds since the flight started.
    fn vehicle_s(&self, now_s: f64) -> f64 {
        (now_s - self.start_s) * self.speedup
    }

    /// The flight is over: the executor has an outcome, or an aborted flight did not land in
    /// time.
    pub fn finished<E: FlightExecutor>(&self, ex: &E) -> bool {
        self.gave_up || ex.outcome().is_some()
    }

    /// The updates since the last call, in order.
    pub fn take_updates(&mut self) -> Vec<Update> {
        std::mem::take(&mut self.updates)
    }

    /// One turn of the loop at `now_s`: the message received (if any), then the clock's events
    /// (tick, lost link, timeout, `interrupted`, progress), fed to the executor; then the watcher
    /// sees any new reading. `closed` when the connection has closed. The messages to send.
    pub fn step<E: FlightExecutor>(
        &mut self,
        p: &mut GroundProtocol,
        ex: &mut E,
        now_s: f64,
        received: Option<&Received>,
        (closed, interrupted): (Option<&str>, bool),
    ) -> Vec<MavMessage> {
        let mut out = Vec::new();
        let FromMessage {
            mut events,
            reading,
        } = match received {
            Some(r) => self.absorb_message(p, ex, now_s, r),
            None => FromMessage {
                events: Vec::new(),
                reading: None,
            },
        };
        // Ask again now and then: a request lost on the way would cost the mission progress.
        if now_s - self.last_request_s > 10.0 {
            self.last_request_s = now_s;
            out.extend(p.stream_requests(false));
        }
        if !self.closed_reported
            && let Some(why) = closed
        {
            self.closed_reported = true;
            self.updates.push(Update::LinkClosed(why.to_string()));
        }
        events.extend(self.clock_events(p, ex, now_s, interrupted));
        if let Some(t) = self.aborted_at_s
            && now_s - t > self.config.abort_grace_s + ex.landing_budget_s() / self.speedup
        {
            self.gave_up = true;
            return out;
        }
        for e in events {
            let t = self.vehicle_s(now_s);
            let is_telemetry = matches!(e, Event::Telemetry(_));
            let output = ex.handle(t, e);
            self.dispatch(p, output, t, &mut out);
            if is_telemetry {
                self.log_row(p, ex, t);
            }
        }
        if let Some(reading) = reading {
            self.consult_watcher(p, ex, now_s, &reading, &mut out);
        }
        self.find_way_home(p, ex, now_s, &mut out);
        out
    }

    /// When the executor holds for the way home: the home router plans it, and the executor
    /// flies it, or lands where it is without one.
    fn find_way_home<E: FlightExecutor>(
        &mut self,
        p: &mut GroundProtocol,
        ex: &mut E,
        now_s: f64,
        out: &mut Vec<MavMessage>,
    ) {
        let Some(from_ned) = ex.way_home_wanted() else {
            return;
        };
        let t = self.vehicle_s(now_s);
        let output = match self.home_router.as_mut() {
            None => ex.no_way_home(t, "this flight has no planner for the way home".into()),
            Some(router) => match router.route_home(from_ned) {
                Ok(way) => match ex.return_home(t, &way) {
                    Ok(output) => output,
                    Err(e) => ex.no_way_home(t, format!("the way home was refused: {e}")),
                },
                Err(why) => ex.no_way_home(t, why),
            },
        };
        self.dispatch(p, output, t, out);
    }

    /// Absorbs one message: its executor events (mode, ack, text, telemetry, a regained link)
    /// and the sensor reading it carries.
    fn absorb_message<E: FlightExecutor>(
        &mut self,
        p: &mut GroundProtocol,
        ex: &E,
        now_s: f64,
        r: &Received,
    ) -> FromMessage {
        let mut events = Vec::new();
        let from_vehicle = p
            .vehicle
            .is_some_and(|(sys, _)| u32::from(sys) == r.header.system_id);
        let reading = match &r.message {
            MavMessage::OBSTACLE_DISTANCE(o) if from_vehicle => {
                self.reading(p, ex, now_s, |time_s, at, yaw, conv| {
                    reading_from_obstacle_distance(o, time_s, at, yaw, conv).map(Some)
                })
            }
            // What ArduPilot's proximity library sends: one 45° wedge per message.
            MavMessage::DISTANCE_SENSOR(d) if from_vehicle => {
                self.reading(p, ex, now_s, |time_s, at, yaw, conv| {
                    reading_from_distance_sensor(d, time_s, at, yaw, conv)
                })
            }
            _ => None,
        };
        let (heard_before, beats_before) = (p.last_heartbeat_s, p.heartbeats);
        let event = p.absorb(now_s, r);
        if self.link_lost && p.heartbeats != beats_before {
            // The vehicle speaks again: the executor commands the failsafe.
            self.link_lost = false;
            let silent_s = heard_before.map_or(0.0, |t| now_s - t);
            events.push(Event::LinkRegained { silent_s });
        }
        if let Some(e) = event {
            if let Event::StatusText(t) = &e {
                self.updates.push(Update::StatusText(t.clone()));
            }
            if let Event::Mode(m) = e
                && self.last_mode != Some(m)
            {
                self.last_mode = Some(m);
                self.updates.push(Update::Mode(m));
            }
            events.push(e);
        }
        if let MavMessage::GLOBAL_POSITION_INT(g) = &r.message
            && p.is_from_vehicle(r)
            && self.last_global_ms != Some(g.time_boot_ms)
            && let Some(mut tel) = p.telemetry(g, &self.frame, self.convergence_rad)
        {
            let ours_s = self.vehicle_s(now_s);
            if let (Some(ms), Some(at_s)) = (self.last_global_ms, self.last_global_at_s) {
                // Vehicle seconds: ours (wall × speed-up) against its stamps.
                let behind_s = (ours_s - at_s) - f64::from(g.time_boot_ms.wrapping_sub(ms)) * 1e-3;
                if behind_s > STALL_WARN_WALL_S * self.speedup {
                    self.updates.push(Update::Warning(format!(
                        "the vehicle's clock fell {:.1} s (wall time) behind ours between two positions (a stalled simulator or link): a trajectory waits for the vehicle's clock",
                        behind_s / self.speedup
                    )));
                }
            }
            self.last_global_ms = Some(g.time_boot_ms);
            self.last_global_at_s = Some(ours_s);
            tel.sample_time_s = self.sample_time_s(now_s, g.time_boot_ms);
            events.push(Event::Telemetry(tel));
        }
        FromMessage { events, reading }
    }

    /// The executor time at which the vehicle sampled a position stamped `time_boot_ms`,
    /// received at `now_s`: its stamp less the offset between the clocks (learnt here until
    /// frozen). `None` for a vehicle without a clock (stamp 0).
    fn sample_time_s(&mut self, now_s: f64, time_boot_ms: u32) -> Option<f64> {
        if time_boot_ms == 0 {
            return None;
        }
        let boot_s = f64::from(time_boot_ms) * 1e-3;
        let offset_s = boot_s - self.vehicle_s(now_s);
        if !self.offset_frozen {
            self.boot_offset_s = Some(self.boot_offset_s.map_or(offset_s, |o| o.max(offset_s)));
        }
        self.boot_offset_s.map(|o| boot_s - o)
    }

    /// A range message from the vehicle (OBSTACLE_DISTANCE, DISTANCE_SENSOR) decoded by
    /// `decode` (vehicle time, position, true yaw, convergence) at its last position (`None`
    /// before the first telemetry, for a message that carries no horizontal reading, or when it
    /// cannot be decoded: warned once per kind of error).
    fn reading<E: FlightExecutor>(
        &mut self,
        p: &GroundProtocol,
        ex: &E,
        now_s: f64,
        decode: impl FnOnce(
            f64,
            [f64; 3],
            f64,
            f64,
        ) -> Result<Option<ObstacleReading>, crate::obstacle::ObstacleError>,
    ) -> Option<ObstacleReading> {
        let t = ex.last_telemetry()?;
        let at = [t.north_m, t.east_m, t.down_m];
        let time_s = self.vehicle_s(now_s);
        match decode(time_s, at, p.yaw_rad, self.convergence_rad) {
            Ok(None) => None,
            Ok(Some(mut x)) => {
                x.velocity_ned_m_s = t.velocity_ned_m_s;
                self.readings += 1;
                self.last_hits_ne = x.hits_ne().collect();
                self.updates.push(Update::Reading(x.clone()));
                Some(x)
            }
            Err(e) => {
                let text = e.to_string();
                if !self.warned.contains(&text) {
                    self.warned.push(text.clone());
                    let warning = format!("{text}: reading ignored");
                    self.updates.push(Update::Warning(warning));
                }
                None
            }
        }
    }

    /// The clock's events at `now_s`: a tick every 50 ms, a lost link, the flight's budget run
    /// out, an interrupt; and the progress report.
    fn clock_events<E: FlightExecutor>(
        &mut self,
        p: &GroundProtocol,
        ex: &E,
        now_s: f64,
        interrupted: bool,
    ) -> Vec<Event> {
        let mut events = Vec::new();
        // A reference is streamed at ≥ 10 Hz of vehicle time: ticks every 0.05 vehicle seconds.
        let tick_s = match ex.tracking() {
            Some(_) => 0.05_f64.min(0.05 / self.speedup),
            None => 0.05,
        };
        if now_s - self.last_tick_s >= tick_s {
            self.last_tick_s = now_s;
            events.push(Event::Tick);
        }
        let silent_s = p.last_heartbeat_s.map_or(f64::INFINITY, |t| now_s - t);
        if silent_s > self.config.link_timeout_s {
            self.link_lost = true;
            events.push(Event::LinkLost { silent_s });
        }
        if let Some(limit) = self.config.timeout_s
            && self.aborted_at_s.is_none()
            && now_s - self.start_s > limit
        {
            self.aborted_at_s = Some(now_s);
            self.updates.push(Update::TimedOut(limit));
            events.push(Event::Abort(format!("--timeout-s {limit} exceeded")));
        }
        if self.aborted_at_s.is_none() && interrupted {
            self.aborted_at_s = Some(now_s);
            let action: FailsafeAction = self.config.on_interrupt;
            self.updates.push(Update::Interrupted(action));
            events.push(Event::Stop {
                reason: "interrupted by Ctrl-C".into(),
                action,
            });
        }
        if self
            .last_progress_s
            .is_none_or(|t| now_s - t >= self.config.progress_period_s)
        {
            self.last_progress_s = Some(now_s);
            self.updates.push(Update::Progress(Progress {
                time_s: self.vehicle_s(now_s),
                state: ex.state(),
                reached: ex.reached().len(),
                waypoints: ex.targets().len(),
                distance_left_m: ex.distance_left_m(),
                telemetry: ex.last_telemetry().cloned(),
                readings: self.readings,
                replans: self.replans.len(),
            }));
        }
        events
    }

    /// The executor's commands as messages (into `out`) and its notes as an update.
    fn dispatch(
        &mut self,
        p: &mut GroundProtocol,
        output: Output,
        t: f64,
        out: &mut Vec<MavMessage>,
    ) {
        for c in &output.commands {
            if matches!(c, Command::GoTo { .. } | Command::Track { .. }) {
                self.sent_targets += 1;
            }
            if let Command::Track { setpoint, time_s } = c {
                self.last_track = Some((t, *setpoint));
                // Stamped with the vehicle's time of the instant it holds at.
                self.offset_frozen = true;
                let stamp_ms = self.boot_offset_s.map_or(0, |o| {
                    ((time_s + o) * 1e3).round().clamp(1.0, f64::from(u32::MAX)) as u32
                });
                if let Ok(m) = p.track_target(&self.frame, setpoint, self.convergence_rad, stamp_ms)
                {
                    out.push(m);
                }
                continue;
            }
            // A target without latitude/longitude is not sent; the executor sees no progress.
            if let Ok(messages) = p.command(*c, &self.frame, self.convergence_rad) {
                out.extend(messages);
            }
        }
        if !output.notes.is_empty() {
            self.updates.push(Update::Notes(t, output.notes));
        }
    }

    /// A row of the flight log after a telemetry update.
    fn log_row<E: FlightExecutor>(&mut self, p: &GroundProtocol, ex: &E, t: f64) {
        let Some(tel) = ex.last_telemetry() else {
            return;
        };
        let (lat_deg, lon_deg) = p.global.as_ref().map_or((f64::NAN, f64::NAN), |g| {
            (f64::from(g.lat) * 1e-7, f64::from(g.lon) * 1e-7)
        });
        self.log.push(LogRow {
            time_s: t,
            lat_deg,
            lon_deg,
            state: ex.state(),
            north_m: tel.north_m,
            east_m: tel.east_m,
            alt_m: tel.alt_m(),
            yaw_rad: tel.yaw_rad,
            speed_m_s: tel.ground_speed_m_s(),
            target: match (ex.current_target(), self.last_track) {
                // Streaming a reference: the setpoint (sent within the last second).
                (Some((index, _)), Some((sent_s, sp))) if t - sent_s <= 1.0 => Some((
                    index,
                    skyplan_flight::executor::Target {
                        north_m: sp.point_ned[0],
                        east_m: sp.point_ned[1],
                        alt_m: -sp.point_ned[2],
                        heading_rad: sp.yaw_rad,
                    },
                )),
                (target, _) => target,
            },
        });
    }

    /// The watcher sees the reading with the route still to fly: keep, replace or hold.
    fn consult_watcher<E: FlightExecutor>(
        &mut self,
        p: &mut GroundProtocol,
        ex: &mut E,
        now_s: f64,
        reading: &ObstacleReading,
        out: &mut Vec<MavMessage>,
    ) {
        if !ex.accepts_route_change() {
            return;
        }
        let t = self.vehicle_s(now_s);
        let Some(watcher) = self.watcher.as_mut() else {
            return;
        };
        let output = match watcher.on_reading(reading, ex.remaining_targets()) {
            RouteDecision::Keep => None,
            RouteDecision::Replace { targets, event } => {
                match ex.replace_route(t, &targets, event.clone()) {
                    Ok(output) => {
                        self.replans.push(event);
                        Some(output)
                    }
                    // The route ahead is blocked and the new one cannot be flown: stop.
                    Err(e) => {
                        let warning = format!("replanned route refused: {e}");
                        self.updates.push(Update::Warning(warning.clone()));
                        Some(ex.hold_no_route(t, warning))
                    }
                }
            }
            RouteDecision::Hold { reason } => Some(ex.hold_no_route(t, reason)),
        };
        if let Some(output) = output {
            self.dispatch(p, output, t, out);
        }
    }

    /// The flight's account at `now_s`.
    pub fn summary(self, p: &GroundProtocol, now_s: f64) -> FlightSummary {
        let time_s = self.vehicle_s(now_s);
        FlightSummary {
            log: self.log,
            time_s,
            wall_time_s: now_s - self.start_s,
            position_targets_sent: self.sent_targets,
            heartbeats_received: p.heartbeats,
            replans: self.replans,
            readings: self.readings,
            last_hits_ne: self.last_hits_ne,
            tracking: None,
        }
    }
}

#[cfg(test)]
mod stall_tests {
    use super::*;
    use skyplan_flight::executor::{ExecutorConfig, MissionExecutor, Target};

    /// Positions whose stamps advance with our clock pass quietly; a vehicle whose clock stood
    /// still for 3 s of wall time (at 5× speed-up: 15 s of ours) is told once.
    #[test]
    fn a_vehicle_clock_that_stands_still_is_told() {
        let home = Lla {
            lat_deg: 37.79248,
            lon_deg: -122.39745,
            alt_m: 0.0,
        };
        let frame = LocalFrame::new(home).unwrap();
        let target = Target {
            north_m: 0.0,
            east_m: 0.0,
            alt_m: 5.0,
            heading_rad: 0.0,
        };
        let mut ex = MissionExecutor::new(&[target], ExecutorConfig::default()).unwrap();
        let config = GroundConfig {
            speedup: 5.0,
            ..GroundConfig::default()
        };
        let mut flight = FlightLoop::with_convergence(&frame, config, 0.0, None, 0.0);
        let mut p = GroundProtocol::new();
        let header = mavlink::MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: 0,
        };
        let mut send = |flight: &mut FlightLoop, p: &mut GroundProtocol, wall_s: f64, message| {
            let r = Received { header, message };
            flight.step(p, &mut ex, wall_s, Some(&r), (None, false));
        };
        send(
            &mut flight,
            &mut p,
            0.0,
            MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                mavtype: MavType::MAV_TYPE_QUADROTOR,
                autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
                ..Default::default()
            }),
        );
        let position = |time_boot_ms| {
            MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
                time_boot_ms,
                lat: (home.lat_deg * 1e7) as i32,
                lon: (home.lon_deg * 1e7) as i32,
                ..Default::default()
            })
        };
        let warnings = |flight: &mut FlightLoop| {
            (flight.take_updates().into_iter())
                .filter_map(|u| match u {
                    Update::Warning(w) if w.contains("clock fell") => Some(w),
                    _ => None,
                })
                .collect::<Vec<_>>()
        };
        // 0.1 s of wall time apart: 0.5 s of the vehicle's.
        for k in 0..10u32 {
            send(
                &mut flight,
                &mut p,
                0.1 * f64::from(k),
                position(1000 + 500 * k),
            );
        }
        assert_eq!(warnings(&mut flight), Vec::<String>::new());
        // 3 s of wall time, the vehicle's clock 0.5 s on.
        send(&mut flight, &mut p, 3.9, position(6000));
        let told = warnings(&mut flight);
        assert_eq!(told.len(), 1, "{told:?}");
        assert!(
            told[0].contains("fell 2.9 s (wall time) behind"),
            "{told:?}"
        );
        send(&mut flight, &mut p, 4.0, position(6500));
        assert_eq!(warnings(&mut flight), Vec::<String>::new());
    }
}
