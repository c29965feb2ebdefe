//! A simulated multicopter: simple but honest dynamics, no I/O.
//!
//! A position controller (proportional, with the square-root braking law so that it stops at the
//! target within the acceleration limit) asks for a velocity within the horizontal, climb and
//! descent limits, the faster of the horizontal and the vertical slowed to arrive with the
//! slower (a straight line to the target in 3D, as ArduCopter's waypoint controller flies it);
//! the velocity follows it as a first-order lag with time constant
//! [`SimConfig::velocity_tau_s`], its change clamped to the acceleration limit; the heading turns
//! toward the target heading at most at the yaw-rate limit. The ground stops descent (it may
//! rise under the vehicle: [`SimVehicle::set_ground_up_m`]; meeting it outside a landing is a
//! [`SimEvent::GroundStrike`]).
//!
//! A GUIDED target with velocity and acceleration ([`SimVehicle::set_target`]) is followed as
//! ArduCopter's position-velocity-acceleration controller does: the target moves on with its own
//! velocity and acceleration between updates (constant acceleration), and the vehicle's
//! acceleration is the target's (feed-forward) plus a velocity loop (gain 1 /
//! [`SimConfig::velocity_tau_s`]) on the target's velocity plus a position loop
//! ([`SimConfig::position_gain_per_s`]) on its position, within the acceleration limit; the
//! speed limits apply to the position loop's correction only (the reference sets the speed).
//! Without an update for [`GUIDED_TIMEOUT_S`] the target stops where it is (ArduCopter's
//! `GUID_TIMEOUT`). A position-only target is flown exactly as before.
//!
//! Modes follow ArduCopter: GUIDED obeys position targets and NAV_TAKEOFF, LAND descends where it
//! is, AUTO flies the uploaded mission, LOITER holds, RTL flies straight back over the home at
//! the altitude it had when RTL began or at `RTL_ALT` (climbing to it first when below, as ArduCopter does), then lands
//! there and disarms. Positions are NED metres about the home.
//!
//! ```
//! use skyplan_flight::sim::{SimConfig, SimMode, SimVehicle};
//! let mut v = SimVehicle::new(SimConfig::default());
//! v.set_mode(SimMode::Guided);
//! v.arm().unwrap();
//! v.takeoff(10.0).unwrap();
//! for _ in 0..1000 { v.step(0.02); } // 20 s
//! assert!((v.state().position_ned_m[2] + 10.0).abs() < 0.1);
//! ```

use crate::executor::wrap_angle_rad;
use std::fmt;

/// Seconds a GUIDED target with velocity and acceleration is followed without an update; then
/// its velocity and acceleration are dropped and the vehicle stops at it (ArduCopter's
/// `GUID_TIMEOUT`, 3 s).
pub const GUIDED_TIMEOUT_S: f64 = 3.0;

/// A GUIDED target: a position and heading, with the velocity and acceleration it has now
/// (feed-forward), either of them absent when the sender masked it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimTarget {
    /// Position, metres north, east, down of home.
    pub position_ned_m: [f64; 3],
    /// Velocity, m/s north, east, down (`None`: not given).
    pub velocity_ned_m_s: Option<[f64; 3]>,
    /// Acceleration, m/s² north, east, down (`None`: not given).
    pub accel_ned_m_s2: Option<[f64; 3]>,
    /// Heading, radians clockwise from north (NaN: keep the current one).
    pub yaw_rad: f64,
}

impl SimTarget {
    /// The target `dt_s` seconds later (earlier if negative), moved on at constant acceleration:
    /// how a target stamped at another time is brought to the vehicle's now.
    ///
    /// ```
    /// use skyplan_flight::sim::SimTarget;
    /// let t = SimTarget { position_ned_m: [0.0; 3], velocity_ned_m_s: Some([1.0, 0.0, 0.0]),
    ///     accel_ned_m_s2: Some([2.0, 0.0, 0.0]), yaw_rad: 0.0 };
    /// let later = t.advanced(0.5);
    /// assert_eq!(later.position_ned_m, [0.75, 0.0, 0.0]);
    /// assert_eq!(later.velocity_ned_m_s, Some([2.0, 0.0, 0.0]));
    /// ```
    pub fn advanced(self, dt_s: f64) -> Self {
        let v = self.velocity_ned_m_s.unwrap_or([0.0; 3]);
        let a = self.accel_ned_m_s2.unwrap_or([0.0; 3]);
        Self {
            position_ned_m: std::array::from_fn(|i| {
                self.position_ned_m[i] + v[i] * dt_s + 0.5 * a[i] * dt_s * dt_s
            }),
            velocity_ned_m_s: self
                .velocity_ned_m_s
                .map(|v| std::array::from_fn(|i| v[i] + a[i] * dt_s)),
            ..self
        }
    }
}

/// The moving part of a GUIDED target with feed-forward.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FeedForward {
    velocity: [f64; 3],
    accel: [f64; 3],
    /// Simulated time of the last update.
    updated_s: f64,
}

/// Flight modes (ArduCopter numbering in [`SimMode::arducopter_custom_mode`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimMode {
    /// Manual flight; the simulated pilot holds the vehicle where it is.
    Stabilize,
    /// Obeys position targets and take-off commands.
    Guided,
    /// Flies the uploaded mission.
    Auto,
    /// Holds its position.
    Loiter,
    /// Descends where it is and disarms on the ground.
    Land,
    /// Returns to the home at its altitude, then lands there and disarms.
    Rtl,
}

impl SimMode {
    /// ArduCopter's `custom_mode` number of this mode.
    pub fn arducopter_custom_mode(self) -> u32 {
        use crate::modes::arducopter;
        match self {
            SimMode::Stabilize => arducopter::STABILIZE,
            SimMode::Auto => arducopter::AUTO,
            SimMode::Guided => arducopter::GUIDED,
            SimMode::Loiter => arducopter::LOITER,
            SimMode::Rtl => arducopter::RTL,
            SimMode::Land => arducopter::LAND,
        }
    }

    /// The mode of an ArduCopter `custom_mode` number, if simulated.
    pub fn from_arducopter_custom_mode(mode: u32) -> Option<Self> {
        use crate::modes::arducopter;
        Some(match mode {
            arducopter::STABILIZE => SimMode::Stabilize,
            arducopter::AUTO => SimMode::Auto,
            arducopter::GUIDED => SimMode::Guided,
            arducopter::LOITER => SimMode::Loiter,
            arducopter::RTL => SimMode::Rtl,
            arducopter::LAND => SimMode::Land,
            _ => return None,
        })
    }
}

impl fmt::Display for SimMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SimMode::Stabilize => "STABILIZE",
            SimMode::Guided => "GUIDED",
            SimMode::Auto => "AUTO",
            SimMode::Loiter => "LOITER",
            SimMode::Land => "LAND",
            SimMode::Rtl => "RTL",
        })
    }
}

/// Limits and time constants of the simulated vehicle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Horizontal speed limit, m/s.
    pub max_ground_speed_m_s: f64,
    /// Climb rate limit, m/s.
    pub max_climb_m_s: f64,
    /// Descent rate limit, m/s.
    pub max_descent_m_s: f64,
    /// Acceleration limit, m/s².
    pub max_accel_m_s2: f64,
    /// Time constant of the velocity response, seconds.
    pub velocity_tau_s: f64,
    /// Position controller gain, 1/s.
    pub position_gain_per_s: f64,
    /// Yaw rate limit, rad/s.
    pub max_yaw_rate_rad_s: f64,
    /// Descent rate in LAND, m/s.
    pub land_speed_m_s: f64,
    /// A mission waypoint is reached within this distance, metres.
    pub acceptance_radius_m: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            max_ground_speed_m_s: 5.0,
            max_climb_m_s: 2.5,
            max_descent_m_s: 1.5,
            max_accel_m_s2: 3.0,
            velocity_tau_s: 0.3,
            position_gain_per_s: 1.0,
            max_yaw_rate_rad_s: 90f64.to_radians(),
            land_speed_m_s: 1.0,
            acceptance_radius_m: 1.0,
        }
    }
}

/// ArduCopter's default `RTL_ALT`, metres (1500 cm).
pub const DEFAULT_RTL_ALT_M: f64 = 15.0;

/// One item of an uploaded mission, in the local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SimMissionItem {
    /// Climb to this altitude where the vehicle is.
    Takeoff {
        /// Metres above home.
        alt_m: f64,
    },
    /// Fly to a point (NAV_WAYPOINT). As ArduCopter with its default `WP_YAW_BEHAVIOR`, the
    /// vehicle faces the waypoint while flying to it (`param4` is ignored) unless a
    /// [`SimMissionItem::Yaw`] comes right before it.
    Waypoint {
        /// Metres north of home.
        north_m: f64,
        /// Metres east of home.
        east_m: f64,
        /// Metres above home.
        alt_m: f64,
    },
    /// CONDITION_YAW (absolute): as on ArduCopter, which starts the "do" items between two
    /// NAV_WAYPOINTs when the first is reached, the vehicle faces this heading on the way to the
    /// next waypoint and holds it there.
    Yaw {
        /// Heading, radians clockwise from north.
        yaw_rad: f64,
    },
    /// DO_CHANGE_SPEED: as ArduCopter's, the horizontal speed of the leg being flown and the
    /// legs after it (until another one), in place of the configured speed limit.
    Speed {
        /// Ground speed, m/s (positive).
        speed_m_s: f64,
    },
    /// Land where the vehicle is, staying in AUTO, then disarm; as on ArduCopter, the item is
    /// reported reached (MISSION_ITEM_REACHED) only after the touchdown.
    Land,
    /// An item the simulator does not fly (skipped).
    Unsupported,
}

/// Why the simulated vehicle refused a command.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct SimRefusal(pub String);

/// What happened during a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimEvent {
    /// A mission item was reached (MISSION_ITEM_REACHED).
    MissionItemReached(u16),
    /// The vehicle touched down.
    Landed,
    /// The vehicle disarmed itself after landing.
    AutoDisarmed,
    /// The vehicle flew into the ground (terrain rising into its way, or a descent below it)
    /// outside a landing: a crash on a real vehicle.
    GroundStrike,
}

/// The vehicle's state, as its telemetry reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimState {
    /// Simulated time since boot, seconds.
    pub time_s: f64,
    /// Position, metres north, east, down of home.
    pub position_ned_m: [f64; 3],
    /// Velocity, m/s north, east, down.
    pub velocity_ned_m_s: [f64; 3],
    /// Heading, radians clockwise from north, in (−π, π].
    pub yaw_rad: f64,
    /// Yaw rate, rad/s.
    pub yaw_rate_rad_s: f64,
    /// Motors armed.
    pub armed: bool,
    /// Flight mode.
    pub mode: SimMode,
    /// On the ground.
    pub on_ground: bool,
    /// Index of the mission item being flown (AUTO).
    pub mission_current: u16,
}

/// The simulated vehicle.
#[derive(Debug, Clone)]
pub struct SimVehicle {
    config: SimConfig,
    time_s: f64,
    position: [f64; 3],
    velocity: [f64; 3],
    yaw_rad: f64,
    yaw_rate_rad_s: f64,
    armed: bool,
    mode: SimMode,
    on_ground: bool,
    /// Position and heading target (NED, yaw) of GUIDED, LOITER and AUTO.
    target: Option<([f64; 3], f64)>,
    /// The target's velocity and acceleration (GUIDED, [`SimVehicle::set_target`]).
    feed_forward: Option<FeedForward>,
    mission: Vec<SimMissionItem>,
    mission_current: usize,
    /// RTL: the home has been reached and the vehicle descends.
    rtl_descending: bool,
    /// RTL is climbing to its return altitude before going home.
    rtl_climbing: bool,
    /// The return altitude above home, metres (ArduCopter `RTL_ALT`, set in centimetres).
    rtl_alt_m: f64,
    /// ArduCopter `RTL_CONE_SLOPE` (kept and echoed; this simulator has no cone).
    rtl_cone_slope: f32,
    /// AUTO: the land item is being flown.
    mission_landing: bool,
    /// AUTO: the speed a DO_CHANGE_SPEED set, m/s (`None`: the configured limit).
    mission_speed_m_s: Option<f64>,
    /// The ground under the vehicle, metres up from the home's ground (0: flat; terrain
    /// moves it, [`SimVehicle::set_ground_up_m`]).
    ground_up_m: f64,
}

fn norm2(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

impl SimVehicle {
    /// A disarmed vehicle on the ground at home, facing north, in STABILIZE.
    pub fn new(config: SimConfig) -> Self {
        Self {
            config,
            time_s: 0.0,
            position: [0.0; 3],
            velocity: [0.0; 3],
            yaw_rad: 0.0,
            yaw_rate_rad_s: 0.0,
            armed: false,
            mode: SimMode::Stabilize,
            on_ground: true,
            target: None,
            feed_forward: None,
            mission: Vec::new(),
            mission_current: 0,
            rtl_descending: false,
            rtl_climbing: false,
            rtl_alt_m: DEFAULT_RTL_ALT_M,
            rtl_cone_slope: 3.0,
            mission_landing: false,
            mission_speed_m_s: None,
            ground_up_m: 0.0,
        }
    }

    /// Where the ground is under the vehicle now, metres up from the home's ground (the home
    /// is where the vehicle stands when created: 0 there). A caller with terrain sets it before
    /// each [`SimVehicle::step`]; the ground stops descents, and a vehicle that meets it away
    /// from a landing touches down there.
    ///
    /// ```
    /// use skyplan_flight::sim::{SimConfig, SimMode, SimVehicle};
    /// let mut v = SimVehicle::new(SimConfig::default());
    /// v.set_mode(SimMode::Guided);
    /// v.arm().unwrap();
    /// v.takeoff(20.0).unwrap();
    /// for _ in 0..1500 { v.step(0.02); }
    /// v.set_mode(SimMode::Land);
    /// v.set_ground_up_m(12.0); // a hill under it
    /// for _ in 0..1500 { v.set_ground_up_m(12.0); v.step(0.02); }
    /// let s = v.state();
    /// assert!(s.on_ground && !s.armed && (s.position_ned_m[2] + 12.0).abs() < 1e-9);
    /// ```
    pub fn set_ground_up_m(&mut self, up_m: f64) {
        if up_m.is_finite() {
            self.ground_up_m = up_m;
        }
    }

    /// Whether it is landing now: LAND, RTL's descent at home, or a mission's land item.
    pub fn landing(&self) -> bool {
        match self.mode {
            SimMode::Land => true,
            SimMode::Rtl => self.rtl_descending,
            SimMode::Auto => self.mission_landing,
            _ => false,
        }
    }

    /// The current state.
    pub fn state(&self) -> SimState {
        SimState {
            time_s: self.time_s,
            position_ned_m: self.position,
            velocity_ned_m_s: self.velocity,
            yaw_rad: self.yaw_rad,
            yaw_rate_rad_s: self.yaw_rate_rad_s,
            armed: self.armed,
            mode: self.mode,
            on_ground: self.on_ground,
            mission_current: self.mission_current.min(u16::MAX as usize) as u16,
        }
    }

    /// The uploaded mission.
    pub fn mission(&self) -> &[SimMissionItem] {
        &self.mission
    }

    /// Arms the motors (on the ground only).
    pub fn arm(&mut self) -> Result<(), SimRefusal> {
        if self.armed {
            return Ok(());
        }
        if !self.on_ground {
            return Err(SimRefusal("Arm: vehicle is not on the ground".into()));
        }
        if self.mode == SimMode::Land {
            return Err(SimRefusal("Arm: mode not armable (LAND)".into()));
        }
        self.armed = true;
        Ok(())
    }

    /// Disarms the motors (on the ground only: a multicopter would fall).
    pub fn disarm(&mut self) -> Result<(), SimRefusal> {
        if !self.armed {
            return Ok(());
        }
        if !self.on_ground {
            return Err(SimRefusal("Disarm: vehicle is flying".into()));
        }
        self.armed = false;
        Ok(())
    }

    /// Changes the flight mode; entering GUIDED, LOITER or AUTO holds the current position first.
    pub fn set_mode(&mut self, mode: SimMode) {
        if mode == self.mode {
            return;
        }
        self.mode = mode;
        self.feed_forward = None;
        match mode {
            SimMode::Guided | SimMode::Loiter | SimMode::Stabilize => {
                self.target = (!self.on_ground).then_some((self.position, self.yaw_rad));
            }
            SimMode::Auto => {
                self.mission_current = 0;
                self.mission_landing = false;
                self.mission_speed_m_s = None;
                self.target = None;
            }
            SimMode::Land => self.target = None,
            SimMode::Rtl => {
                // As ArduCopter: below RTL_ALT, climb where it is first, then go home at it.
                self.rtl_descending = false;
                let alt_m = -self.position[2];
                self.rtl_climbing = !self.on_ground && alt_m < self.rtl_alt_m - 0.1;
                self.target = (!self.on_ground).then_some(if self.rtl_climbing {
                    (
                        [self.position[0], self.position[1], -self.rtl_alt_m],
                        self.yaw_rad,
                    )
                } else {
                    ([0.0, 0.0, self.position[2]], self.yaw_rad)
                });
            }
        }
    }

    /// PARAM_SET of the parameters this simulator has: `RTL_ALT` (centimetres, 200 to 300000
    /// as ArduCopter takes it; RTL climbs to it before going home) and `RTL_CONE_SLOPE`
    /// (kept, without effect). Returns the value now held (what PARAM_VALUE echoes), or `None`
    /// for a name it does not have or a value out of range (ArduPilot then sends nothing).
    ///
    /// ```
    /// use skyplan_flight::sim::{SimConfig, SimVehicle};
    /// let mut v = SimVehicle::new(SimConfig::default());
    /// assert_eq!(v.set_param("RTL_ALT", 18000.0), Some(18000.0));
    /// assert_eq!(v.rtl_alt_m(), 180.0);
    /// assert_eq!(v.set_param("RTL_ALT", -5.0), None);
    /// assert_eq!(v.set_param("NO_SUCH", 1.0), None);
    /// ```
    pub fn set_param(&mut self, name: &str, value: f32) -> Option<f32> {
        match name {
            "RTL_ALT" if (200.0..=300_000.0).contains(&value) => {
                self.rtl_alt_m = f64::from(value) / 100.0;
                Some(value)
            }
            "RTL_CONE_SLOPE" if (0.0..=10.0).contains(&value) => {
                self.rtl_cone_slope = value;
                Some(value)
            }
            _ => None,
        }
    }

    /// The value of a parameter this simulator has (see [`SimVehicle::set_param`]).
    pub fn param(&self, name: &str) -> Option<f32> {
        match name {
            "RTL_ALT" => Some((self.rtl_alt_m * 100.0) as f32),
            "RTL_CONE_SLOPE" => Some(self.rtl_cone_slope),
            _ => None,
        }
    }

    /// The return altitude of RTL above home, metres.
    pub fn rtl_alt_m(&self) -> f64 {
        self.rtl_alt_m
    }

    /// NAV_TAKEOFF: climb to `alt_m` above home where the vehicle is (GUIDED, armed, on the ground).
    pub fn takeoff(&mut self, alt_m: f64) -> Result<(), SimRefusal> {
        if self.mode != SimMode::Guided {
            return Err(SimRefusal(format!(
                "Takeoff: not in GUIDED mode ({})",
                self.mode
            )));
        }
        if !self.armed {
            return Err(SimRefusal("Takeoff: vehicle not armed".into()));
        }
        if !alt_m.is_finite() || alt_m <= 0.0 {
            return Err(SimRefusal(format!("Takeoff: bad altitude {alt_m}")));
        }
        if !self.on_ground {
            return Err(SimRefusal("Takeoff: already flying".into()));
        }
        self.target = Some(([self.position[0], self.position[1], -alt_m], self.yaw_rad));
        self.feed_forward = None;
        Ok(())
    }

    /// NAV_LAND: switch to LAND.
    pub fn land(&mut self) {
        self.set_mode(SimMode::Land);
    }

    /// A position target with heading (GUIDED only, and only once flying).
    pub fn set_position_target(
        &mut self,
        position_ned_m: [f64; 3],
        yaw_rad: f64,
    ) -> Result<(), SimRefusal> {
        if self.mode != SimMode::Guided {
            return Err(SimRefusal(format!(
                "position target ignored: not in GUIDED mode ({})",
                self.mode
            )));
        }
        if position_ned_m.iter().any(|x| !x.is_finite()) {
            return Err(SimRefusal("position target is not finite".into()));
        }
        if self.on_ground && self.target.is_none() {
            return Err(SimRefusal("position target ignored: take off first".into()));
        }
        let yaw = if yaw_rad.is_finite() {
            yaw_rad
        } else {
            self.yaw_rad
        };
        self.target = Some((position_ned_m, yaw));
        self.feed_forward = None;
        Ok(())
    }

    /// A GUIDED target with heading and, when given, velocity and acceleration (feed-forward;
    /// see the module documentation). Without either it is [`SimVehicle::set_position_target`]
    /// exactly. GUIDED only, and only once flying.
    pub fn set_target(&mut self, target: SimTarget) -> Result<(), SimRefusal> {
        if target.velocity_ned_m_s.is_none() && target.accel_ned_m_s2.is_none() {
            return self.set_position_target(target.position_ned_m, target.yaw_rad);
        }
        let velocity = target.velocity_ned_m_s.unwrap_or([0.0; 3]);
        let accel = target.accel_ned_m_s2.unwrap_or([0.0; 3]);
        if velocity.iter().chain(&accel).any(|x| !x.is_finite()) {
            return Err(SimRefusal(
                "target velocity or acceleration is not finite".into(),
            ));
        }
        self.set_position_target(target.position_ned_m, target.yaw_rad)?;
        self.feed_forward = Some(FeedForward {
            velocity,
            accel,
            updated_s: self.time_s,
        });
        Ok(())
    }

    /// Replaces the mission (AUTO restarts from its first item).
    pub fn set_mission(&mut self, items: Vec<SimMissionItem>) {
        self.mission = items;
        self.mission_current = 0;
    }

    /// Advances the simulation by `dt_s` seconds (use ≤ 0.02 s steps) and tells what happened.
    pub fn step(&mut self, dt_s: f64) -> Vec<SimEvent> {
        let mut events = Vec::new();
        if dt_s.is_nan() || dt_s <= 0.0 {
            return events;
        }
        self.time_s += dt_s;
        if self.mode == SimMode::Auto && self.armed {
            self.advance_mission(&mut events);
        }
        let c = self.config;
        let (v_cmd, yaw_target) = if self.follows_feed_forward() {
            self.feed_forward_step(dt_s)
        } else {
            self.position_step(dt_s)
        };
        self.ground_contact(v_cmd, &mut events);
        // Heading, within the yaw-rate limit (only when flying).
        if self.armed && !self.on_ground {
            let err = wrap_angle_rad(yaw_target - self.yaw_rad);
            let max = c.max_yaw_rate_rad_s * dt_s;
            let turn = err.clamp(-max, max);
            self.yaw_rad = wrap_angle_rad(self.yaw_rad + turn);
            self.yaw_rate_rad_s = turn / dt_s;
        } else {
            self.yaw_rate_rad_s = 0.0;
        }
        if !self.armed && self.on_ground {
            self.velocity = [0.0; 3];
            self.feed_forward = None;
        }
        events
    }

    /// Whether a GUIDED target with feed-forward is being followed now.
    fn follows_feed_forward(&self) -> bool {
        self.feed_forward.is_some()
            && self.armed
            && self.mode == SimMode::Guided
            && self.target.is_some()
    }

    /// One step after a target with feed-forward: the target moves on, the vehicle accelerates
    /// by its acceleration plus the velocity and position loops, within the acceleration limit;
    /// the commanded velocity and the heading to turn to.
    fn feed_forward_step(&mut self, dt_s: f64) -> ([f64; 3], f64) {
        let c = self.config;
        let (Some(mut ff), Some((mut p_t, yaw))) = (self.feed_forward, self.target) else {
            return ([0.0; 3], self.yaw_rad);
        };
        if self.time_s - ff.updated_s > GUIDED_TIMEOUT_S {
            ff.velocity = [0.0; 3];
            ff.accel = [0.0; 3];
        }
        // Position loop: a velocity correction within the speed limits.
        let mut corr: [f64; 3] =
            std::array::from_fn(|i| c.position_gain_per_s * (p_t[i] - self.position[i]));
        let h = norm2([corr[0], corr[1]]);
        if h > c.max_ground_speed_m_s {
            corr[0] *= c.max_ground_speed_m_s / h;
            corr[1] *= c.max_ground_speed_m_s / h;
        }
        corr[2] = corr[2].clamp(-c.max_climb_m_s, c.max_descent_m_s);
        let v_cmd: [f64; 3] = std::array::from_fn(|i| ff.velocity[i] + corr[i]);
        // Velocity loop plus the feed-forward, within the acceleration limit.
        let mut a: [f64; 3] = std::array::from_fn(|i| {
            ff.accel[i] + (v_cmd[i] - self.velocity[i]) / c.velocity_tau_s.max(dt_s)
        });
        let a_norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        if a_norm > c.max_accel_m_s2 {
            for x in &mut a {
                *x *= c.max_accel_m_s2 / a_norm;
            }
        }
        for ((v, p), a) in self.velocity.iter_mut().zip(&mut self.position).zip(a) {
            *p += *v * dt_s + 0.5 * a * dt_s * dt_s;
            *v += a * dt_s;
        }
        // The target moves on over the step too (constant acceleration), as AC_PosControl's
        // does between updates.
        for ((p, v), a) in p_t.iter_mut().zip(&mut ff.velocity).zip(ff.accel) {
            *p += *v * dt_s + 0.5 * a * dt_s * dt_s;
            *v += a * dt_s;
        }
        self.target = Some((p_t, yaw));
        self.feed_forward = Some(ff);
        (v_cmd, yaw)
    }

    /// One step after a position target (or none): the commanded velocity followed as a
    /// first-order lag within the acceleration limit; the commanded velocity and the heading.
    fn position_step(&mut self, dt_s: f64) -> ([f64; 3], f64) {
        let c = self.config;
        let (v_cmd, yaw_target) = self.commanded_velocity();
        // First-order velocity response, within the acceleration limit.
        let k = (dt_s / c.velocity_tau_s).min(1.0);
        let mut dv: [f64; 3] = std::array::from_fn(|i| (v_cmd[i] - self.velocity[i]) * k);
        let dv_norm = (dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]).sqrt();
        let dv_max = c.max_accel_m_s2 * dt_s;
        if dv_norm > dv_max {
            for x in &mut dv {
                *x *= dv_max / dv_norm;
            }
        }
        for ((v, p), dv) in self.velocity.iter_mut().zip(&mut self.position).zip(dv) {
            *v += dv;
            *p += *v * dt_s;
        }
        (v_cmd, yaw_target)
    }

    /// The velocity commanded now (north, east, down) and the heading to turn to: toward the
    /// target in GUIDED, AUTO and RTL's return, straight down when landing.
    fn commanded_velocity(&mut self) -> ([f64; 3], f64) {
        let c = self.config;
        let mut v_cmd = [0.0; 3];
        let mut yaw_target = self.yaw_rad;
        if self.armed && self.mode == SimMode::Rtl && self.rtl_climbing {
            if -self.position[2] >= self.rtl_alt_m - 0.2 {
                self.rtl_climbing = false;
                self.target = Some(([0.0, 0.0, -self.rtl_alt_m], self.yaw_rad));
            }
        } else if self.armed && self.mode == SimMode::Rtl && !self.rtl_descending {
            let d = norm2([self.position[0], self.position[1]]);
            let speed = norm2([self.velocity[0], self.velocity[1]]);
            if d <= c.acceptance_radius_m && speed < 0.5 {
                self.rtl_descending = true;
            }
        }
        if self.armed {
            let descend = self.mode == SimMode::Land
                || self.mode == SimMode::Rtl && self.rtl_descending
                || self.mode == SimMode::Auto && self.mission_landing;
            match self.mode {
                _ if descend => {
                    let hold = self.target.map_or(self.position, |(p, _)| p);
                    let h = self.horizontal_command([hold[0], hold[1]]);
                    v_cmd = [h[0], h[1], c.land_speed_m_s];
                    self.target = Some(([hold[0], hold[1], 0.0], self.yaw_rad));
                }
                _ => {
                    if let Some((p, yaw)) = self.target {
                        let mut h = self.horizontal_command([p[0], p[1]]);
                        let dz = p[2] - self.position[2];
                        let brake = (2.0 * c.max_accel_m_s2 * dz.abs()).sqrt();
                        let vz = (c.position_gain_per_s * dz.abs()).min(brake);
                        let mut vz = if dz > 0.0 {
                            vz.min(c.max_descent_m_s)
                        } else {
                            -vz.min(c.max_climb_m_s)
                        };
                        // As ArduCopter's waypoint controller: a straight line to the target in
                        // 3D, the faster of the horizontal and the vertical waiting for the
                        // slower (a climb or descent is not done ahead of the leg).
                        let (h_m_s, d_h) = (
                            norm2(h),
                            norm2([p[0] - self.position[0], p[1] - self.position[1]]),
                        );
                        if h_m_s > 1e-6 && vz.abs() > 1e-6 {
                            let (t_h, t_v) = (d_h / h_m_s, dz.abs() / vz.abs());
                            if t_v < t_h {
                                vz *= t_v / t_h;
                            } else {
                                h = [h[0] * t_h / t_v, h[1] * t_h / t_v];
                            }
                        }
                        v_cmd = [h[0], h[1], vz];
                        yaw_target = yaw;
                    }
                }
            }
        }
        (v_cmd, yaw_target)
    }

    /// The ground stops the descent; touching down is told, and disarms in LAND, RTL and a
    /// mission's landing.
    fn ground_contact(&mut self, v_cmd: [f64; 3], events: &mut Vec<SimEvent>) {
        let was_on_ground = self.on_ground;
        let ground_down_m = -self.ground_up_m;
        let landing = self.landing();
        if self.armed && !was_on_ground && !landing && self.position[2] >= ground_down_m {
            events.push(SimEvent::GroundStrike);
        }
        if self.position[2] >= ground_down_m {
            self.position[2] = ground_down_m;
            if self.velocity[2] > 0.0 {
                self.velocity[2] = 0.0;
            }
        }
        let climbing = self.velocity[2] < -0.05 || v_cmd[2] < 0.0;
        self.on_ground = self.position[2] > ground_down_m - 0.05 && !climbing;
        if self.on_ground {
            self.position[2] = ground_down_m;
            self.velocity[2] = 0.0;
            self.velocity[0] *= 0.5;
            self.velocity[1] *= 0.5;
        }
        if self.on_ground && !was_on_ground {
            events.push(SimEvent::Landed);
            let mission_landing = self.mode == SimMode::Auto && self.mission_landing;
            if (matches!(self.mode, SimMode::Land | SimMode::Rtl) || mission_landing) && self.armed
            {
                self.armed = false;
                self.target = None;
                events.push(SimEvent::AutoDisarmed);
            }
            if mission_landing {
                let seq = self.mission_current.min(u16::MAX as usize) as u16;
                events.push(SimEvent::MissionItemReached(seq));
                self.mission_landing = false;
            }
        }
    }

    /// Horizontal velocity command toward a point: proportional, braking, speed-limited.
    fn horizontal_command(&self, to: [f64; 2]) -> [f64; 2] {
        let c = self.config;
        let e = [to[0] - self.position[0], to[1] - self.position[1]];
        let d = norm2(e);
        if d < 1e-9 {
            return [0.0, 0.0];
        }
        let limit_m_s = match (self.mode, self.mission_speed_m_s) {
            (SimMode::Auto, Some(s)) => s,
            _ => c.max_ground_speed_m_s,
        };
        let speed = (c.position_gain_per_s * d)
            .min((2.0 * c.max_accel_m_s2 * d).sqrt())
            .min(limit_m_s);
        [e[0] / d * speed, e[1] / d * speed]
    }

    fn advance_mission(&mut self, events: &mut Vec<SimEvent>) {
        let c = self.config;
        while let Some(item) = self.mission.get(self.mission_current).copied() {
            let seq = self.mission_current.min(u16::MAX as usize) as u16;
            match item {
                SimMissionItem::Takeoff { alt_m } => {
                    let target = [self.position[0], self.position[1], -alt_m];
                    if self.target.is_none_or(|(p, _)| p[2] != -alt_m) {
                        self.target = Some((target, self.yaw_rad));
                    }
                    if -self.position[2] >= 0.95 * alt_m {
                        events.push(SimEvent::MissionItemReached(seq));
                        self.mission_current += 1;
                        continue;
                    }
                    return;
                }
                SimMissionItem::Waypoint {
                    north_m,
                    east_m,
                    alt_m,
                } => {
                    let p = [north_m, east_m, -alt_m];
                    let d_h = norm2([p[0] - self.position[0], p[1] - self.position[1]]);
                    // A CONDITION_YAW before the waypoint holds its heading on the way; else
                    // face the waypoint (WP_YAW_BEHAVIOR 2), keeping the heading in the last 2 m.
                    // The "do" items right before the waypoint (CONDITION_YAW, DO_CHANGE_SPEED).
                    let before = self.mission[..self.mission_current].iter().rev();
                    let held = before
                        .take_while(|i| {
                            matches!(i, SimMissionItem::Yaw { .. } | SimMissionItem::Speed { .. })
                        })
                        .find_map(|i| match i {
                            SimMissionItem::Yaw { yaw_rad } => Some(*yaw_rad),
                            _ => None,
                        });
                    let yaw = match held {
                        Some(yaw_rad) => yaw_rad,
                        _ if d_h > 2.0 => (p[1] - self.position[1]).atan2(p[0] - self.position[0]),
                        _ => self.target.map_or(self.yaw_rad, |(_, y)| y),
                    };
                    self.target = Some((p, yaw));
                    let d = (d_h.powi(2) + (p[2] - self.position[2]).powi(2)).sqrt();
                    if d <= c.acceptance_radius_m {
                        events.push(SimEvent::MissionItemReached(seq));
                        self.mission_current += 1;
                        continue;
                    }
                    return;
                }
                SimMissionItem::Yaw { .. } => {
                    // Started with the next waypoint (the vehicle turns within the yaw-rate limit).
                    events.push(SimEvent::MissionItemReached(seq));
                    self.mission_current += 1;
                }
                SimMissionItem::Speed { speed_m_s } => {
                    self.mission_speed_m_s = Some(speed_m_s);
                    events.push(SimEvent::MissionItemReached(seq));
                    self.mission_current += 1;
                }
                SimMissionItem::Land => {
                    if !self.mission_landing {
                        self.mission_landing = true;
                        self.target = Some((self.position, self.yaw_rad));
                    }
                    return;
                }
                SimMissionItem::Unsupported => {
                    self.mission_current += 1;
                }
            }
        }
        // Mission done: hold.
        if self.mode == SimMode::Auto {
            self.mode = SimMode::Loiter;
            self.target = Some((self.position, self.yaw_rad));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(v: &mut SimVehicle, seconds: f64) -> Vec<SimEvent> {
        let mut all = Vec::new();
        let steps = (seconds / 0.02).round() as usize;
        for _ in 0..steps {
            all.extend(v.step(0.02));
        }
        all
    }

    fn flying(alt_m: f64) -> SimVehicle {
        let mut v = SimVehicle::new(SimConfig::default());
        v.set_mode(SimMode::Guided);
        v.arm().unwrap();
        v.takeoff(alt_m).unwrap();
        run(&mut v, 15.0);
        v
    }

    /// Flies `v` for `seconds` over a ground `ground_up_m(north, east)`, set before each step.
    fn run_over(
        v: &mut SimVehicle,
        seconds: f64,
        ground_up_m: impl Fn(f64, f64) -> f64,
    ) -> Vec<SimEvent> {
        let mut all = Vec::new();
        for _ in 0..(seconds / 0.02).round() as usize {
            let p = v.state().position_ned_m;
            v.set_ground_up_m(ground_up_m(p[0], p[1]));
            all.extend(v.step(0.02));
        }
        all
    }

    #[test]
    fn a_climbing_or_descending_target_is_flown_in_a_straight_line() {
        // From 10 m up to a point 80 m north and 30 m higher, and back down: every sampled
        // position within 1 m of the straight line between the ends.
        for (from_up, to_up) in [(10.0, 40.0), (40.0, 10.0)] {
            let mut v = flying(from_up);
            run(&mut v, 15.0); // settled at its altitude
            let start = v.state().position_ned_m;
            let end = [80.0, 0.0, -to_up];
            v.set_position_target(end, 0.0).unwrap();
            let mut worst: f64 = 0.0;
            for _ in 0..3000 {
                v.step(0.02);
                let p = v.state().position_ned_m;
                let (dn, dd) = (end[0] - start[0], end[2] - start[2]);
                let t = (((p[0] - start[0]) * dn + (p[2] - start[2]) * dd) / (dn * dn + dd * dd))
                    .clamp(0.0, 1.0);
                let off = (p[0] - start[0] - t * dn).hypot(p[2] - start[2] - t * dd);
                worst = worst.max(off);
            }
            let p = v.state().position_ned_m;
            assert!(
                (p[0] - end[0]).abs() < 0.1 && (p[2] - end[2]).abs() < 0.1,
                "{p:?}"
            );
            assert!(
                worst < 1.0,
                "{from_up} → {to_up} m: {worst:.2} m off the line"
            );
        }
    }

    #[test]
    fn rising_ground_strikes_a_level_flight_and_a_landing_stops_on_it() {
        // A slope rising 1 m per 2 m north of 20 m north: 25 m high at 70 m.
        let slope = |n: f64, _e: f64| ((n - 20.0) * 0.5).clamp(0.0, 40.0);
        let mut v = flying(15.0);
        v.set_position_target([100.0, 0.0, -15.0], 0.0).unwrap();
        let events = run_over(&mut v, 40.0, slope);
        assert!(events.contains(&SimEvent::GroundStrike), "{events:?}");
        let s = v.state();
        assert!(
            s.position_ned_m[0] < 60.0,
            "it cannot pass the slope: {:?}",
            s.position_ned_m
        );
        // Above the slope and clear of it, LAND stops on the ground there, without a strike.
        let mut v = flying(40.0);
        v.set_position_target([60.0, 0.0, -40.0], 0.0).unwrap();
        let events = run_over(&mut v, 30.0, slope);
        assert!(!events.contains(&SimEvent::GroundStrike), "{events:?}");
        v.set_mode(SimMode::Land);
        let events = run_over(&mut v, 60.0, slope);
        let s = v.state();
        assert!(!events.contains(&SimEvent::GroundStrike), "{events:?}");
        assert!(events.contains(&SimEvent::Landed) && s.on_ground && !s.armed);
        let ground = slope(s.position_ned_m[0], s.position_ned_m[1]);
        assert!(
            (s.position_ned_m[2] + ground).abs() < 1e-9,
            "{:?} on {ground}",
            s.position_ned_m
        );
        assert!(ground > 15.0, "landed on the slope: {ground}");
    }

    /// A scripted GUIDED flight with position-only targets: take-off, two targets.
    fn scripted(target: impl Fn(&mut SimVehicle, [f64; 3], f64)) -> SimState {
        let mut v = SimVehicle::new(SimConfig::default());
        v.set_mode(SimMode::Guided);
        v.arm().unwrap();
        v.takeoff(7.0).unwrap();
        run(&mut v, 8.0);
        target(&mut v, [40.0, -25.0, -9.0], 1.0);
        run(&mut v, 14.0);
        target(&mut v, [10.0, 30.0, -4.0], -2.0);
        run(&mut v, 6.0);
        v.state()
    }

    /// Position-only targets fly bit for bit alike through `set_position_target` and through
    /// `set_target` without velocity and acceleration, and as the simulator flew them when its
    /// waypoint controller began flying straight lines in 3D (session 14; the feed-forward
    /// targets of commit c3335f7 had left them unchanged before).
    #[test]
    fn position_only_targets_fly_exactly_as_before() {
        let golden: [u64; 7] = [
            4628481673298431302,
            13835949769852632121,
            13842877537150379921,
            13835945758800189303,
            4616628156252615343,
            4600860193949518246,
            13835058055282163711,
        ];
        let bits = |s: SimState| -> Vec<u64> {
            (s.position_ned_m.iter().chain(&s.velocity_ned_m_s))
                .chain([&s.yaw_rad])
                .map(|x| x.to_bits())
                .collect()
        };
        let old = scripted(|v, p, yaw| v.set_position_target(p, yaw).unwrap());
        assert_eq!(bits(old), golden, "{old:?}");
        let new = scripted(|v, p, yaw| {
            v.set_target(SimTarget {
                position_ned_m: p,
                velocity_ned_m_s: None,
                accel_ned_m_s2: None,
                yaw_rad: yaw,
            })
            .unwrap()
        });
        assert_eq!(bits(new), golden, "{new:?}");
    }

    /// A target moving at constant velocity, sent once with its velocity: the vehicle catches
    /// it and then flies with it (the target moves on between updates), faster than the
    /// position-only speed limit; with no update for GUIDED_TIMEOUT_S the target stops.
    #[test]
    fn a_moving_target_with_feed_forward_is_tracked_and_stops_after_the_guided_timeout() {
        let mut v = flying(10.0);
        let speed = 7.0; // above max_ground_speed_m_s: the reference sets the speed
        let moving = |t_s: f64| SimTarget {
            position_ned_m: [speed * t_s, 0.0, -10.0],
            velocity_ned_m_s: Some([speed, 0.0, 0.0]),
            accel_ned_m_s2: Some([0.0; 3]),
            yaw_rad: 0.0,
        };
        let t0 = v.state().time_s;
        // Updated at 10 Hz for 20 s.
        let mut worst_late: f64 = 0.0;
        for k in 0..200 {
            let t = f64::from(k) * 0.1;
            v.set_target(moving(t)).unwrap();
            run(&mut v, 0.1);
            let s = v.state();
            let expected = speed * (s.time_s - t0);
            if t > 10.0 {
                worst_late = worst_late.max((s.position_ned_m[0] - expected).abs());
            }
        }
        assert!(worst_late < 0.01, "{worst_late}");
        // Silence: the target goes on for GUIDED_TIMEOUT_S, then stops where it got to.
        let t_last = v.state().time_s - 0.1;
        run(&mut v, 20.0);
        let s = v.state();
        let stop_n = speed * (t_last - t0) + speed * GUIDED_TIMEOUT_S;
        assert!(
            (s.position_ned_m[0] - stop_n).abs() < 0.3 * speed,
            "{s:?} vs {stop_n}"
        );
        assert!(s.velocity_ned_m_s[0].abs() < 0.05, "{s:?}");
    }

    /// A start far from the target: the acceleration limit holds while it catches up.
    #[test]
    fn feed_forward_keeps_the_acceleration_limit() {
        let c = SimConfig::default();
        let mut v = flying(5.0);
        let mut prev = v.state();
        v.set_target(SimTarget {
            position_ned_m: [50.0, 20.0, -5.0],
            velocity_ned_m_s: Some([3.0, 0.0, 0.0]),
            accel_ned_m_s2: Some([10.0, 0.0, 0.0]),
            yaw_rad: 0.0,
        })
        .unwrap();
        for _ in 0..100 {
            v.step(0.02);
            let s = v.state();
            let dv: f64 = (0..3)
                .map(|i| (s.velocity_ned_m_s[i] - prev.velocity_ned_m_s[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(dv <= c.max_accel_m_s2 * 0.02 + 1e-9, "accel {}", dv / 0.02);
            prev = s;
        }
    }

    #[test]
    fn takeoff_needs_guided_and_armed() {
        let mut v = SimVehicle::new(SimConfig::default());
        assert!(v.takeoff(5.0).is_err());
        v.set_mode(SimMode::Guided);
        assert!(v.takeoff(5.0).unwrap_err().0.contains("not armed"));
        v.arm().unwrap();
        v.takeoff(5.0).unwrap();
    }

    #[test]
    fn respects_speed_acceleration_and_yaw_rate_limits() {
        let c = SimConfig::default();
        let mut v = flying(5.0);
        v.set_position_target([200.0, 0.0, -5.0], std::f64::consts::PI)
            .unwrap();
        let mut prev = v.state();
        for _ in 0..3000 {
            v.step(0.02);
            let s = v.state();
            let speed = s.velocity_ned_m_s[0].hypot(s.velocity_ned_m_s[1]);
            assert!(speed <= c.max_ground_speed_m_s + 1e-9, "speed {speed}");
            let dv: f64 = (0..3)
                .map(|i| (s.velocity_ned_m_s[i] - prev.velocity_ned_m_s[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(dv <= c.max_accel_m_s2 * 0.02 + 1e-9, "accel {}", dv / 0.02);
            let dyaw = wrap_angle_rad(s.yaw_rad - prev.yaw_rad).abs();
            assert!(dyaw <= c.max_yaw_rate_rad_s * 0.02 + 1e-9);
            prev = s;
        }
        let s = v.state();
        // 60 s is enough for 200 m at 5 m/s with braking; no overshoot beyond 0.1 m.
        assert!(
            (s.position_ned_m[0] - 200.0).abs() < 0.1,
            "{:?}",
            s.position_ned_m
        );
        assert!((s.yaw_rad.abs() - std::f64::consts::PI).abs() < 1e-6);
    }

    #[test]
    fn first_order_response_reaches_63_percent_in_one_time_constant() {
        // Without the acceleration limit, a step in commanded velocity is followed exponentially.
        let cfg = SimConfig {
            max_accel_m_s2: 1e9,
            position_gain_per_s: 1e9,
            ..SimConfig::default()
        };
        let mut v = SimVehicle::new(cfg);
        v.set_mode(SimMode::Guided);
        v.arm().unwrap();
        v.takeoff(5.0).unwrap();
        run(&mut v, 10.0);
        v.set_position_target([1000.0, 0.0, -5.0], 0.0).unwrap();
        let steps = (cfg.velocity_tau_s / 0.001).round() as usize;
        for _ in 0..steps {
            v.step(0.001);
        }
        let vn = v.state().velocity_ned_m_s[0];
        let expected = cfg.max_ground_speed_m_s * (1.0 - (-1.0f64).exp());
        assert!((vn - expected).abs() < 0.05, "{vn} vs {expected}");
    }

    #[test]
    fn land_descends_and_auto_disarms_and_disarm_refused_in_flight() {
        let mut v = flying(5.0);
        assert!(v.disarm().is_err());
        v.land();
        let events = run(&mut v, 10.0);
        assert!(events.contains(&SimEvent::Landed));
        assert!(events.contains(&SimEvent::AutoDisarmed));
        let s = v.state();
        assert!(
            s.on_ground && !s.armed && s.position_ned_m[2] == 0.0,
            "{s:?}"
        );
    }

    /// DO_CHANGE_SPEED sets the speed of the leg after it, above or below the configured limit,
    /// and a CONDITION_YAW before it still holds its heading on that leg.
    #[test]
    fn a_change_of_speed_paces_the_next_legs() {
        let wp = |north_m| SimMissionItem::Waypoint {
            north_m,
            east_m: 0.0,
            alt_m: 5.0,
        };
        let mut v = SimVehicle::new(SimConfig::default());
        v.set_mission(vec![
            SimMissionItem::Takeoff { alt_m: 5.0 },
            SimMissionItem::Speed { speed_m_s: 8.0 },
            wp(150.0),
            SimMissionItem::Yaw { yaw_rad: 1.0 },
            SimMissionItem::Speed { speed_m_s: 2.0 },
            wp(250.0),
            SimMissionItem::Land,
        ]);
        v.arm().unwrap();
        v.set_mode(SimMode::Auto);
        // The fastest ground speed on each leg (by the item being flown) and the heading held.
        let mut fastest = [0.0f64; 8];
        let mut yaw_on_slow_leg = Vec::new();
        for _ in 0..20_000 {
            v.step(0.02);
            let s = v.state();
            let ground = norm2([s.velocity_ned_m_s[0], s.velocity_ned_m_s[1]]);
            let item = usize::from(s.mission_current).min(7);
            // (On the slow leg, once the vehicle has slowed down from the fast one.)
            if item != 5 || s.position_ned_m[0] > 170.0 {
                fastest[item] = fastest[item].max(ground);
            }
            if item == 5 && s.position_ned_m[0] > 170.0 {
                yaw_on_slow_leg.push(s.yaw_rad);
            }
            if !s.armed && s.on_ground {
                break;
            }
        }
        assert!(fastest[2] > 7.9 && fastest[2] <= 8.0 + 1e-9, "{fastest:?}");
        assert!(fastest[5] > 1.9 && fastest[5] <= 2.0 + 1e-9, "{fastest:?}");
        assert!(!yaw_on_slow_leg.is_empty());
        assert!(yaw_on_slow_leg.iter().all(|y| (y - 1.0).abs() < 1e-6));
        // A new AUTO run starts at the configured speed again.
        v.set_mode(SimMode::Loiter);
        v.set_mode(SimMode::Auto);
        assert_eq!(v.mission_speed_m_s, None);
    }

    #[test]
    fn auto_flies_the_mission_like_arducopter() {
        use std::f64::consts::{FRAC_PI_2, PI};
        let mut v = SimVehicle::new(SimConfig::default());
        let wp = |north_m, east_m| SimMissionItem::Waypoint {
            north_m,
            east_m,
            alt_m: 5.0,
        };
        v.set_mission(vec![
            SimMissionItem::Takeoff { alt_m: 5.0 },
            wp(10.0, 0.0),
            SimMissionItem::Yaw { yaw_rad: PI },
            wp(10.0, 10.0),
            wp(-10.0, 10.0),
            SimMissionItem::Land,
        ]);
        v.arm().unwrap();
        v.set_mode(SimMode::Auto);
        let mut reached = Vec::new();
        let mut landed_at = None;
        let mut modes_in_descent = Vec::new();
        for k in 0..4000 {
            for e in v.step(0.02) {
                match e {
                    SimEvent::MissionItemReached(seq) => reached.push((seq, k, v.state().yaw_rad)),
                    SimEvent::Landed => landed_at = Some(k),
                    SimEvent::AutoDisarmed => {}
                    SimEvent::GroundStrike => panic!("a mission on flat ground struck it"),
                }
            }
            let s = v.state();
            if s.mission_current == 5 && s.armed {
                modes_in_descent.push(s.mode);
            }
        }
        let seqs: Vec<u16> = reached.iter().map(|r| r.0).collect();
        assert_eq!(seqs, vec![0, 1, 2, 3, 4, 5]);
        // NAV_WAYPOINT's heading is the direction of flight (param4 ignored) …
        assert!(wrap_angle_rad(reached[1].2).abs() < 0.05, "{reached:?}");
        assert!(
            wrap_angle_rad(reached[4].2 - PI).abs() < 0.05,
            "{reached:?}"
        );
        // … but a CONDITION_YAW before a waypoint holds its heading on the way there and on
        // arrival (the leg to (10, 10) flies east, the vehicle faces south).
        assert!(
            wrap_angle_rad(reached[3].2 - PI).abs() < 0.05,
            "{reached:?}"
        );
        assert!((wrap_angle_rad(reached[3].2) - FRAC_PI_2).abs() > 1.0);
        // The land item: flown in AUTO, reported only at the touchdown.
        assert!(!modes_in_descent.is_empty());
        assert!(modes_in_descent.iter().all(|m| *m == SimMode::Auto));
        assert_eq!(Some(reached[5].1), landed_at);
        let s = v.state();
        assert!(s.on_ground && !s.armed && s.mode == SimMode::Auto);
        assert!(
            (s.position_ned_m[0] + 10.0).abs() < 1.0 && (s.position_ned_m[1] - 10.0).abs() < 1.0
        );
    }

    #[test]
    fn rtl_below_rtl_alt_climbs_to_it_then_flies_home_at_it() {
        let mut v = flying(7.0);
        assert_eq!(v.set_param("RTL_ALT", 4000.0), Some(4000.0));
        v.set_position_target([30.0, -40.0, -7.0], 0.0).unwrap();
        run(&mut v, 30.0);
        v.set_mode(SimMode::Rtl);
        let mut max_alt_m: f64 = 0.0;
        for _ in 0..6000 {
            v.step(0.02);
            let s = v.state();
            let d = s.position_ned_m[0].hypot(s.position_ned_m[1]);
            max_alt_m = max_alt_m.max(-s.position_ned_m[2]);
            // Straight up first: below 39.5 m it is still over where RTL began (50 m out).
            if -s.position_ned_m[2] < 39.5 && !s.on_ground && d > 2.0 {
                assert!(
                    d > 49.0,
                    "left for home at {:.1} m, {d:.1} m out",
                    -s.position_ned_m[2]
                );
            }
        }
        assert!((max_alt_m - 40.0).abs() < 0.5, "{max_alt_m}");
        let s = v.state();
        assert!(s.on_ground && !s.armed, "{s:?}");
        assert!(
            s.position_ned_m[0].hypot(s.position_ned_m[1]) < 1.0,
            "{s:?}"
        );
    }

    #[test]
    fn rtl_at_or_above_rtl_alt_flies_home_at_its_altitude_then_lands_and_disarms() {
        let mut v = flying(7.0);
        assert_eq!(v.set_param("RTL_ALT", 500.0), Some(500.0));
        v.set_position_target([30.0, -40.0, -7.0], 0.0).unwrap();
        run(&mut v, 30.0);
        v.set_mode(SimMode::Rtl);
        let mut max_alt_error: f64 = 0.0;
        let mut events = Vec::new();
        for _ in 0..3000 {
            events.extend(v.step(0.02));
            let s = v.state();
            if s.position_ned_m[0].hypot(s.position_ned_m[1]) > 2.0 {
                max_alt_error = max_alt_error.max((s.position_ned_m[2] + 7.0).abs());
            }
        }
        assert!(max_alt_error < 0.2, "{max_alt_error}");
        assert!(events.contains(&SimEvent::AutoDisarmed));
        let s = v.state();
        assert!(s.on_ground && !s.armed && s.mode == SimMode::Rtl, "{s:?}");
        assert!(
            s.position_ned_m[0].hypot(s.position_ned_m[1]) < 1.0,
            "{s:?}"
        );
        assert_eq!(SimMode::from_arducopter_custom_mode(6), Some(SimMode::Rtl));
    }
}
