//! What goes in and out of an executor: vehicle states, telemetry, events and commands.

use crate::reference::Setpoint;
use std::f64::consts::PI;
use std::fmt;

/// The states of the FCND client (PLANNING runs before the executor starts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlightState {
    /// Not in control: before the flight, and after it (control released).
    Manual,
    /// Taking control (guided/offboard mode) and arming.
    Arming,
    /// Climbing to the mission altitude.
    Takeoff,
    /// Flying to the waypoints one after another.
    Waypoint,
    /// Descending to the ground.
    Landing,
    /// On the ground, disarming.
    Disarming,
}

impl FlightState {
    /// The FCND name, upper case.
    pub fn name(self) -> &'static str {
        match self {
            FlightState::Manual => "MANUAL",
            FlightState::Arming => "ARMING",
            FlightState::Takeoff => "TAKEOFF",
            FlightState::Waypoint => "WAYPOINT",
            FlightState::Landing => "LANDING",
            FlightState::Disarming => "DISARMING",
        }
    }
}

impl fmt::Display for FlightState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A waypoint to fly to, in the mission's local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Metres north of home.
    pub north_m: f64,
    /// Metres east of home.
    pub east_m: f64,
    /// Altitude above home, metres (positive up).
    pub alt_m: f64,
    /// Heading to hold, radians clockwise from north.
    pub heading_rad: f64,
}

impl Target {
    /// Whether all four numbers are finite (the executor flies no other waypoint).
    ///
    /// ```
    /// use skyplan_flight::executor::Target;
    ///
    /// let t = Target { north_m: 1.0, east_m: 2.0, alt_m: 5.0, heading_rad: 0.0 };
    /// assert!(t.is_finite());
    /// assert!(!Target { alt_m: f64::NAN, ..t }.is_finite());
    /// ```
    pub fn is_finite(&self) -> bool {
        self.north_m.is_finite()
            && self.east_m.is_finite()
            && self.alt_m.is_finite()
            && self.heading_rad.is_finite()
    }

    /// Horizontal distance from the vehicle, metres.
    pub fn horizontal_error_m(&self, t: &Telemetry) -> f64 {
        (self.north_m - t.north_m).hypot(self.east_m - t.east_m)
    }

    /// Altitude error of the vehicle, metres (absolute).
    pub fn vertical_error_m(&self, t: &Telemetry) -> f64 {
        (self.alt_m - t.alt_m()).abs()
    }

    /// Heading error of the vehicle, radians (absolute).
    pub fn heading_error_rad(&self, t: &Telemetry) -> f64 {
        wrap_angle_rad(self.heading_rad - t.yaw_rad).abs()
    }

    /// Horizontal distance to another waypoint, metres.
    pub fn horizontal_distance_m(&self, to: &Target) -> f64 {
        (to.north_m - self.north_m).hypot(to.east_m - self.east_m)
    }
}

impl From<&skyplan_mission::Waypoint> for Target {
    fn from(w: &skyplan_mission::Waypoint) -> Self {
        Target {
            north_m: w.north_m,
            east_m: w.east_m,
            alt_m: w.alt_m,
            heading_rad: w.heading_rad,
        }
    }
}

impl From<[f64; 4]> for Target {
    /// A plan's waypoint: north, east, altitude, heading.
    fn from([north_m, east_m, alt_m, heading_rad]: [f64; 4]) -> Self {
        Target {
            north_m,
            east_m,
            alt_m,
            heading_rad,
        }
    }
}

/// What the vehicle reports, merged from its telemetry, in the mission's local frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Telemetry {
    /// Metres north of home.
    pub north_m: f64,
    /// Metres east of home.
    pub east_m: f64,
    /// Metres below home (negative in the air).
    pub down_m: f64,
    /// Velocity north, east, down, m/s.
    pub velocity_ned_m_s: [f64; 3],
    /// Heading, radians clockwise from north.
    pub yaw_rad: f64,
    /// Motors armed.
    pub armed: bool,
    /// The vehicle is in the mode that obeys position targets (GUIDED / OFFBOARD).
    pub guided: bool,
    /// The vehicle's own landed flag, when it sends one (EXTENDED_SYS_STATE).
    pub on_ground: Option<bool>,
    /// When the vehicle sampled this, in the executor's clock (seconds), when the link knows it
    /// from the vehicle's own time stamp; `None`: at the time of the event.
    pub sample_time_s: Option<f64>,
}

impl Telemetry {
    /// Altitude above home, metres.
    pub fn alt_m(&self) -> f64 {
        -self.down_m
    }
    /// Horizontal speed, m/s.
    pub fn ground_speed_m_s(&self) -> f64 {
        self.velocity_ned_m_s[0].hypot(self.velocity_ned_m_s[1])
    }
    /// Speed, m/s.
    pub fn speed_m_s(&self) -> f64 {
        self.ground_speed_m_s().hypot(self.velocity_ned_m_s[2])
    }
}

/// The commands that the vehicle acknowledges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommandKind {
    /// Enter the guided/offboard mode.
    TakeControl,
    /// Arm the motors.
    Arm,
    /// Take off.
    Takeoff,
    /// Land.
    Land,
    /// Disarm the motors.
    Disarm,
    /// Start the uploaded mission (AUTO, MISSION_START).
    StartMission,
    /// Hold position (LOITER / PX4 HOLD).
    Hold,
    /// Return to launch (RTL).
    ReturnToLaunch,
}

impl fmt::Display for CommandKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CommandKind::TakeControl => "guided mode",
            CommandKind::Arm => "arming",
            CommandKind::Takeoff => "takeoff",
            CommandKind::Land => "landing",
            CommandKind::Disarm => "disarming",
            CommandKind::StartMission => "mission start",
            CommandKind::Hold => "hold",
            CommandKind::ReturnToLaunch => "return to launch",
        })
    }
}

/// What the executor asks the link to send.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Switch to the mode that obeys position targets (GUIDED / OFFBOARD).
    TakeControl,
    /// Arm.
    Arm,
    /// Take off to this altitude above home.
    Takeoff {
        /// Metres above home.
        alt_m: f64,
    },
    /// Fly to a position and hold a heading (SET_POSITION_TARGET_LOCAL_NED, position + yaw).
    GoTo {
        /// Metres north of home.
        north_m: f64,
        /// Metres east of home.
        east_m: f64,
        /// Metres below home.
        down_m: f64,
        /// Heading, radians clockwise from north.
        yaw_rad: f64,
    },
    /// Follow a reference: this position + velocity + acceleration + yaw target
    /// (SET_POSITION_TARGET_*, only the yaw rate ignored), valid at executor time `time_s` (the
    /// link stamps it with the vehicle's time of that instant).
    Track {
        /// The reference's setpoint, in the mission's local frame.
        setpoint: Setpoint,
        /// Executor time at which the setpoint holds, seconds.
        time_s: f64,
    },
    /// Land where the vehicle is.
    Land,
    /// Disarm.
    Disarm,
    /// Fly the uploaded mission: AUTO mode, then MISSION_START.
    StartMission,
    /// Hold the position (ArduCopter LOITER, PX4 AUTO.LOITER).
    Hold,
    /// Return to launch and land there (RTL).
    ReturnToLaunch,
}

impl Command {
    /// A [`Command::GoTo`]'s position (metres north, east, down of home) and heading.
    pub fn position_target(&self) -> Option<([f64; 3], f64)> {
        match *self {
            Command::GoTo {
                north_m,
                east_m,
                down_m,
                yaw_rad,
            } => Some(([north_m, east_m, down_m], yaw_rad)),
            _ => None,
        }
    }
}

/// The vehicle's flight mode, as far as the executors care.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VehicleMode {
    /// Obeys position targets (ArduCopter GUIDED, PX4 OFFBOARD).
    Guided,
    /// Flies the uploaded mission (ArduCopter AUTO, PX4 AUTO.MISSION).
    Auto,
    /// Landing (LAND).
    Land,
    /// Holding position (LOITER, BRAKE, PX4 AUTO.LOITER).
    Hold,
    /// Returning to launch (RTL).
    ReturnToLaunch,
    /// Anything else (a pilot mode such as STABILIZE); the number is the custom mode.
    Other(u32),
}

impl fmt::Display for VehicleMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VehicleMode::Guided => f.write_str("GUIDED"),
            VehicleMode::Auto => f.write_str("AUTO"),
            VehicleMode::Land => f.write_str("LAND"),
            VehicleMode::Hold => f.write_str("HOLD"),
            VehicleMode::ReturnToLaunch => f.write_str("RTL"),
            VehicleMode::Other(m) => write!(f, "custom mode {m}"),
        }
    }
}

/// What the executor tells the vehicle to do when it stops a flight early: on a Ctrl-C
/// ([`Event::Stop`]) or when a lost link comes back ([`ExecutorConfig::failsafe`](super::ExecutorConfig::failsafe)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum FailsafeAction {
    /// Land where it is (NAV_LAND), then disarm.
    Land,
    /// Return to the launch point and land there (RTL), then disarm: the autopilot's own way
    /// home (a straight line at its return altitude), not planned around the map's obstacles.
    #[cfg_attr(feature = "clap", value(name = "rtl"))]
    ReturnToLaunch,
    /// Hold the position in the air (LOITER / PX4 HOLD); the flight ends once the vehicle
    /// confirms, leaving it to the pilot.
    Hold,
    /// Fly a route planned from where the vehicle is back to the launch point around the map's
    /// obstacles (same map, planner and margin, by the ground station's
    /// [`HomeRouter`](crate::sensing::HomeRouter)) in GUIDED, and land there; without a route
    /// home, land where it is. An executor that cannot change its route (AUTO) commands the
    /// autopilot's RTL instead.
    Return,
}

impl fmt::Display for FailsafeAction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FailsafeAction::Land => "land",
            FailsafeAction::ReturnToLaunch => "rtl",
            FailsafeAction::Hold => "hold",
            FailsafeAction::Return => "return",
        })
    }
}

/// What the executor is told.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// New telemetry (the merged latest state of the vehicle).
    Telemetry(Telemetry),
    /// The vehicle answered a command: `Ok` if accepted, else its answer (e.g. "DENIED").
    Ack {
        /// The command.
        command: CommandKind,
        /// Accepted, or the answer.
        accepted: Result<(), String>,
    },
    /// A status text from the vehicle (kept to explain refusals).
    StatusText(String),
    /// No heartbeat from the vehicle for this long: the flight is over.
    LinkLost {
        /// Seconds without a heartbeat.
        silent_s: f64,
    },
    /// Stop the flight: land if in the air (Ctrl-C, overall timeout).
    Abort(String),
    /// Stop the flight with this action if in the air (Ctrl-C with `--on-interrupt hold`);
    /// on the ground it ends the flight (disarming) whatever the action.
    Stop {
        /// Why.
        reason: String,
        /// Land, return to launch or hold.
        action: FailsafeAction,
    },
    /// A heartbeat came back after [`Event::LinkLost`]: with [`ExecutorConfig::failsafe`](super::ExecutorConfig::failsafe),
    /// the executor commands it.
    LinkRegained {
        /// Seconds the vehicle was silent.
        silent_s: f64,
    },
    /// The vehicle's mode, from each of its heartbeats.
    Mode(VehicleMode),
    /// MISSION_ITEM_REACHED: the vehicle reached this item of the uploaded mission.
    MissionItemReached(u16),
    /// MISSION_CURRENT: the vehicle is flying to this item of the uploaded mission.
    MissionCurrent(u16),
    /// Time passes.
    Tick,
}

/// Angle difference wrapped to (−π, π].
pub fn wrap_angle_rad(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI { w + 2.0 * PI } else { w }
}
