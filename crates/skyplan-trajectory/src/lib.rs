//! Smooth, time-parametrised trajectories through a route, provably inside free space and
//! within a vehicle's limits (no I/O).
//!
//! The pipeline, for any planner's route (2D at one altitude, or 3D):
//!
//! 1. **Corridor** ([`build_corridor`]): the route is cut into stretches of at most
//!    [`CorridorOptions::piece_m`]; each stretch's bounding box, split until it is free, is grown
//!    face by face in free space ([`FreeSpace`]: the 3D box world with obstacles grown by the
//!    margin, or a grid at one altitude). Consecutive boxes share the route point between them.
//! 2. **Minimum jerk**: one quintic Bézier piece per box, position, velocity and acceleration
//!    continuous, at rest at both ends, every control point inside its box — so the whole
//!    continuous curve is inside the box (a Bézier curve lies in the convex hull of its control
//!    points). One quadratic programme, solved by `clarabel`: first at the speed limit
//!    everywhere, for the shape; then with durations from a speed profile along that shape (the
//!    turns' radii, acceleration from rest and to rest), the joins held near the shape's.
//! 3. **Time**: derivatives scale by powers of a common factor of the durations, so the factor
//!    that makes the tightest of the speed, climb, descent, acceleration and jerk bounds exactly
//!    tight is computed in closed form from bounds on the derivative curves (hull bounds after
//!    splitting, valid everywhere on the curve, not just at samples). Durations are then
//!    re-allocated piece by piece (a piece slower than its own bounds allow is shortened) while
//!    the total falls.
//! 4. **Proof** ([`verify`]): every guarantee is checked again from the final pieces; a
//!    trajectory that fails is never returned. If optimising fails or runs out of time, the
//!    jerk-limited stop-at-each-waypoint profile ([`stop_at_waypoints`]) is used instead (it
//!    flies the route's own segments) and the trajectory says why.
//!
//! ```
//! use skyplan_trajectory::{plan, GridLayer, Limits, Method, Options};
//! use skyplan_cspace::Grid2;
//! // A 20 m × 20 m room with a wall; the route goes round it at 10 m.
//! let mut text = String::new();
//! for r in 0..20 {
//!     let row: String = (0..20).map(|c| if c == 10 && r < 14 { '#' } else { '.' }).collect();
//!     text.push_str(&row);
//!     text.push('\n');
//! }
//! let free = GridLayer::new(Grid2::from_ascii(&text)?, 10.0);
//! let route = [[2.5, 2.5, 10.0], [16.5, 9.5, 10.0], [16.5, 11.5, 10.0], [2.5, 17.5, 10.0]];
//! let traj = plan(&route, &free, &Limits::default(), &Options::default())?;
//! assert_eq!(traj.method, Method::MinimumJerk);
//! let end = traj.state_at(traj.duration_s());
//! assert!((end.point_neu[0] - 2.5).abs() < 1e-9 && end.vel_neu_m_s == [0.0; 3]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod active_set;
mod bezier;
mod check;
mod corridor;
mod fallback;
mod optimize;
mod passes;
mod yaw;

pub use check::{Bounds, verify, verify_from};
pub use corridor::{CorridorCell, CorridorOptions, FreeSpace, GridLayer, build_corridor};
pub use fallback::stop_at_waypoints;
pub use passes::Pass;
use skyplan_world3::{Aabb, Neu};
use std::time::{Duration, Instant};

/// The vehicle's limits. Defaults suit a 1–2 kg multicopter.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Limits {
    /// Largest speed (norm of the velocity), m/s.
    pub max_speed_m_s: f64,
    /// Largest acceleration (norm), m/s².
    pub max_accel_m_s2: f64,
    /// Largest jerk (norm), m/s³.
    pub max_jerk_m_s3: f64,
    /// Largest climb rate, m/s.
    pub max_climb_m_s: f64,
    /// Largest descent rate, m/s.
    pub max_descent_m_s: f64,
    /// Largest yaw rate, degrees per second.
    pub max_yaw_rate_deg_s: f64,
}

impl Default for Limits {
    /// 10 m/s, 4 m/s², 10 m/s³, 3 m/s up, 1.5 m/s down, 90 °/s.
    fn default() -> Self {
        Self {
            max_speed_m_s: 10.0,
            max_accel_m_s2: 4.0,
            max_jerk_m_s3: 10.0,
            max_climb_m_s: 3.0,
            max_descent_m_s: 1.5,
            max_yaw_rate_deg_s: 90.0,
        }
    }
}

impl Limits {
    /// Each field with its largest accepted value (anything above is absurd for a multicopter).
    pub fn fields(&self) -> [(&'static str, f64, f64); 6] {
        [
            ("max_speed_m_s", self.max_speed_m_s, 100.0),
            ("max_accel_m_s2", self.max_accel_m_s2, 50.0),
            ("max_jerk_m_s3", self.max_jerk_m_s3, 1000.0),
            ("max_climb_m_s", self.max_climb_m_s, 100.0),
            ("max_descent_m_s", self.max_descent_m_s, 100.0),
            ("max_yaw_rate_deg_s", self.max_yaw_rate_deg_s, 3600.0),
        ]
    }

    /// Refuses a limit that is not a number above 0 and at most its cap, naming the field.
    ///
    /// ```
    /// let mut l = skyplan_trajectory::Limits::default();
    /// assert!(l.check().is_ok());
    /// l.max_accel_m_s2 = 80.0;
    /// assert_eq!(
    ///     l.check().unwrap_err().to_string(),
    ///     "max_accel_m_s2 = 80: expected a number above 0 and at most 50"
    /// );
    /// ```
    pub fn check(&self) -> Result<(), TrajectoryError> {
        for (field, value, cap) in self.fields() {
            if !(value > 0.0 && value <= cap) {
                return Err(TrajectoryError::Limit { field, value, cap });
            }
        }
        Ok(())
    }

    /// The yaw rate limit in radians per second.
    pub fn max_yaw_rate_rad_s(&self) -> f64 {
        self.max_yaw_rate_deg_s.to_radians()
    }
}

/// Why no trajectory could be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrajectoryError {
    /// A limit out of its range.
    #[error("{field} = {value}: expected a number above 0 and at most {cap}")]
    Limit {
        /// The limit's name.
        field: &'static str,
        /// The value given.
        value: f64,
        /// The largest accepted value.
        cap: f64,
    },
    /// The route is too tight for a corridor.
    #[error(
        "no safe corridor near north {:.1} m, east {:.1} m, altitude {:.1} m: {why}",
        near_neu[0], near_neu[1], near_neu[2]
    )]
    Corridor {
        /// Where, `[north_m, east_m, alt_m]`.
        near_neu: Neu,
        /// Why, in a sentence.
        why: String,
    },
    /// Fewer than two distinct points, or a point that is not finite.
    #[error("the route {0}")]
    Route(String),
    /// Not even the stop-at-each-waypoint profile passed the checks (the route is not free).
    #[error("no trajectory passed the checks: {0}")]
    Unproven(String),
}

/// Which method made a trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Minimum-jerk Bézier pieces in a corridor of free boxes, time scaled to the limits.
    MinimumJerk,
    /// The jerk-limited stop-at-each-waypoint profile along the route's segments.
    StopAtWaypoints,
}

impl Method {
    /// The name used in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Self::MinimumJerk => "minimum_jerk",
            Self::StopAtWaypoints => "stop_at_waypoints",
        }
    }
}

/// Where a piece provably stays: the convex set holding all its control points.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// A free box of the corridor.
    Box {
        /// The corner with the smallest coordinates `[north_m, east_m, alt_m]`.
        min: Neu,
        /// The corner with the largest.
        max: Neu,
    },
    /// A free segment of the route.
    Segment {
        /// One end.
        from: Neu,
        /// The other.
        to: Neu,
    },
}

impl Region {
    pub(crate) fn of_box(b: &Aabb) -> Self {
        Self::Box {
            min: b.min,
            max: b.max,
        }
    }
}

/// One polynomial piece of the position: a Bézier curve in `[north_m, east_m, alt_m]` over
/// `duration_s` (the local time `t` maps to `τ = t / duration_s`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Piece {
    /// How long the piece lasts, seconds.
    pub duration_s: f64,
    /// Bernstein control points (degree = count − 1), metres.
    pub control_points_neu: Vec<Neu>,
    /// The free region holding them.
    pub region: Region,
}

/// One piece of the yaw: a cubic Bézier in radians (unwrapped) over `duration_s`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct YawPiece {
    /// How long the piece lasts, seconds.
    pub duration_s: f64,
    /// Bernstein control points, radians clockwise from north.
    pub control_points_rad: [f64; 4],
}

/// The state at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Time since the start, seconds.
    pub t_s: f64,
    /// Position `[north_m, east_m, alt_m]`.
    pub point_neu: Neu,
    /// Velocity `[north, east, up]`, m/s.
    pub vel_neu_m_s: Neu,
    /// Acceleration `[north, east, up]`, m/s².
    pub accel_neu_m_s2: Neu,
    /// Heading, radians clockwise from north, in (−π, π].
    pub yaw_rad: f64,
}

/// A trajectory: position pieces and yaw pieces over the same duration, from rest to rest.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Trajectory {
    /// Which method made it.
    pub method: Method,
    /// Why the fallback was used: the optimiser failed, or stopping at each waypoint was faster
    /// (`None` for the optimised trajectory).
    pub fallback_reason: Option<String>,
    /// The limits it respects.
    pub limits: Limits,
    /// Proven bounds of the whole curve.
    pub bounds: Bounds,
    /// Position pieces, in order.
    pub pieces: Vec<Piece>,
    /// Yaw pieces, in order (their durations sum to the same total).
    pub yaw: Vec<YawPiece>,
    /// Wall time spent making it, microseconds.
    pub compute_us: u64,
}

/// Finds the piece holding time `t` (clamped to the whole duration) and the local `τ`.
fn locate<T>(items: &[T], dur: impl Fn(&T) -> f64, t: f64) -> Option<(&T, f64)> {
    let total: f64 = items.iter().map(&dur).sum();
    if t >= total {
        // The end exactly (the running sum below may fall short of it by rounding).
        return items.last().map(|it| (it, 1.0));
    }
    let mut start = 0.0;
    for (k, it) in items.iter().enumerate() {
        let d = dur(it);
        if t <= start + d || k + 1 == items.len() {
            let tau = if d > 0.0 {
                ((t - start) / d).clamp(0.0, 1.0)
            } else {
                0.0
            };
            return Some((it, tau));
        }
        start += d;
    }
    None
}

/// Wraps an angle to (−π, π].
pub fn wrap_rad(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

impl Trajectory {
    /// Total duration, seconds.
    pub fn duration_s(&self) -> f64 {
        self.pieces.iter().map(|p| p.duration_s).sum()
    }

    /// Length of the flown curve, metres (by dense quadrature of the speed).
    pub fn length_m(&self) -> f64 {
        let mut total = 0.0;
        for p in &self.pieces {
            let d = bezier::hodograph(&p.control_points_neu, p.duration_s);
            let n = 64;
            // Simpson's rule on the speed over the piece.
            let h = p.duration_s / n as f64;
            let mut s = 0.0;
            for i in 0..=n {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                s += w * bezier::norm(bezier::eval(&d, i as f64 / n as f64));
            }
            total += s * h / 3.0;
        }
        total
    }

    /// The state at time `t_s` (clamped to `[0, duration]`).
    pub fn state_at(&self, t_s: f64) -> State {
        let t = t_s.clamp(0.0, self.duration_s());
        let mut state = State {
            t_s: t,
            point_neu: [0.0; 3],
            vel_neu_m_s: [0.0; 3],
            accel_neu_m_s2: [0.0; 3],
            yaw_rad: 0.0,
        };
        if let Some((p, tau)) = locate(&self.pieces, |p| p.duration_s, t) {
            let c = &p.control_points_neu;
            let v = bezier::hodograph(c, p.duration_s);
            let a = bezier::hodograph(&v, p.duration_s);
            state.point_neu = bezier::eval(c, tau);
            if !v.is_empty() {
                state.vel_neu_m_s = bezier::eval(&v, tau);
            }
            if !a.is_empty() {
                state.accel_neu_m_s2 = bezier::eval(&a, tau);
            }
        }
        if let Some((y, tau)) = locate(&self.yaw, |y| y.duration_s, t) {
            let c: Vec<Neu> = y
                .control_points_rad
                .iter()
                .map(|&v| [v, 0.0, 0.0])
                .collect();
            state.yaw_rad = wrap_rad(bezier::eval(&c, tau)[0]);
        }
        state
    }

    /// Samples at `rate_hz` from 0 to the end (the end always included), each row
    /// `[t_s, north_m, east_m, alt_m, v_north, v_east, v_up, a_north, a_east, a_up, yaw_deg]`.
    pub fn samples(&self, rate_hz: f64) -> Vec<[f64; 11]> {
        let total = self.duration_s();
        let n = (total * rate_hz).floor() as usize;
        let mut times: Vec<f64> = (0..=n).map(|i| i as f64 / rate_hz).collect();
        if times.last().is_none_or(|&t| t < total - 1e-9) {
            times.push(total);
        }
        times
            .into_iter()
            .map(|t| {
                let s = self.state_at(t);
                [
                    s.t_s,
                    s.point_neu[0],
                    s.point_neu[1],
                    s.point_neu[2],
                    s.vel_neu_m_s[0],
                    s.vel_neu_m_s[1],
                    s.vel_neu_m_s[2],
                    s.accel_neu_m_s2[0],
                    s.accel_neu_m_s2[1],
                    s.accel_neu_m_s2[2],
                    s.yaw_rad.to_degrees(),
                ]
            })
            .collect()
    }
}

/// How a trajectory is made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// The corridor's pieces and growth (default: pieces of `max_speed² / max_accel`, clamped
    /// to 5–50 m, boxes grown up to 20 m a side).
    pub corridor: Option<CorridorOptions>,
    /// Wall-time budget for optimising; over it, the fallback is used (default 1 s).
    pub budget: Duration,
    /// Rounds of per-piece time re-allocation (default 6).
    pub refine_rounds: u32,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            corridor: None,
            budget: Duration::from_millis(1000),
            refine_rounds: 6,
        }
    }
}

fn check_route(route: &[Neu]) -> Result<Vec<Neu>, TrajectoryError> {
    if let Some(p) = route.iter().find(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(TrajectoryError::Route(format!(
            "has a point that is not a number: {}, {}, {}",
            p[0], p[1], p[2]
        )));
    }
    let mut pts: Vec<Neu> = Vec::with_capacity(route.len());
    for &p in route {
        if pts
            .last()
            .is_none_or(|&q| skyplan_world3::distance_m(p, q) > 1e-9)
        {
            pts.push(p);
        }
    }
    if pts.len() < 2 {
        return Err(TrajectoryError::Route(
            "has fewer than two distinct points: nothing to fly".into(),
        ));
    }
    Ok(pts)
}

/// The speed a vehicle may fly along `a → b` under the climb and descent limits.
pub(crate) fn leg_speed_m_s(a: Neu, b: Neu, limits: &Limits) -> f64 {
    let len = skyplan_world3::distance_m(a, b).max(1e-12);
    let dz = (b[2] - a[2]) / len;
    let mut v = limits.max_speed_m_s;
    if dz > 1e-12 {
        v = v.min(limits.max_climb_m_s / dz);
    } else if dz < -1e-12 {
        v = v.min(limits.max_descent_m_s / -dz);
    }
    v
}

/// Cuts each leg into stretches of about the distance needed to reach its speed (`v² / a`,
/// 1–50 m), so that pieces can hold a cruise and the corners are what slows the flight.
fn split_legs(route: &[Neu], limits: &Limits) -> Vec<Neu> {
    let mut out = vec![route[0]];
    for w in route.windows(2) {
        let v = leg_speed_m_s(w[0], w[1], limits);
        let piece_m = (v * v / limits.max_accel_m_s2).clamp(1.0, 50.0);
        let parts = (skyplan_world3::distance_m(w[0], w[1]) / piece_m)
            .ceil()
            .max(1.0) as usize;
        for k in 1..=parts {
            out.push(skyplan_world3::lerp(w[0], w[1], k as f64 / parts as f64));
        }
    }
    out
}

/// Makes a trajectory through `route` (`[north_m, east_m, alt_m]` points, start to goal) in
/// `free`, within `limits`: minimum jerk in a corridor, or the stop-at-each-waypoint fallback
/// with the reason (the optimiser failed, or stopping is faster, as on one straight leg).
/// Every trajectory returned has passed [`verify`], and none is slower than stopping at each
/// waypoint.
pub fn plan(
    route: &[Neu],
    free: &dyn FreeSpace,
    limits: &Limits,
    opts: &Options,
) -> Result<Trajectory, TrajectoryError> {
    let t0 = Instant::now();
    limits.check()?;
    let route = check_route(route)?;
    let planar = route.iter().all(|p| (p[2] - route[0][2]).abs() <= 1e-9);
    let corridor_opts = opts.corridor.unwrap_or(CorridorOptions {
        piece_m: 50.0,
        grow_m: 20.0,
    });
    let cells = build_corridor(&split_legs(&route, limits), free, planar, &corridor_opts)?;
    let deadline = t0 + opts.budget;
    let stop = stop_at_waypoints(&route, limits)?;
    let why = match optimize::minimum_jerk(&cells, planar, limits, deadline, opts.refine_rounds) {
        Ok(pieces) => {
            let mut traj = assemble(Method::MinimumJerk, None, limits, pieces);
            match verify(&traj, free) {
                // A straight leg is where stopping is time-optimal (the jerk-limited profile is
                // bang-bang; smooth pieces cannot match it), so the faster of the two is kept.
                Ok(_) if stop.duration_s() < traj.duration_s() => format!(
                    "stopping at each waypoint ({:.2} s) is faster than the optimised curve ({:.2} s)",
                    stop.duration_s(),
                    traj.duration_s()
                ),
                Ok(b) => {
                    traj.bounds = b;
                    traj.compute_us = t0.elapsed().as_micros() as u64;
                    return Ok(traj);
                }
                Err(e) => format!("the optimised trajectory failed its check ({e})"),
            }
        }
        Err(e) => e,
    };
    let mut traj = stop;
    traj.fallback_reason = Some(why);
    traj.bounds = verify(&traj, free).map_err(TrajectoryError::Unproven)?;
    traj.compute_us = t0.elapsed().as_micros() as u64;
    Ok(traj)
}

/// A trajectory from position pieces: yaw follows the direction of travel, turning at the
/// yaw-rate limit.
pub(crate) fn assemble(
    method: Method,
    fallback_reason: Option<String>,
    limits: &Limits,
    pieces: Vec<Piece>,
) -> Trajectory {
    let yaw = yaw::profile(&pieces, limits.max_yaw_rate_rad_s(), None);
    Trajectory {
        method,
        fallback_reason,
        limits: *limits,
        bounds: Bounds::default(),
        pieces,
        yaw,
        compute_us: 0,
    }
}

/// Makes a trajectory from a vehicle in motion: from `start` (its position, velocity,
/// acceleration and heading, as a trajectory being flown has them at some instant) through
/// `route` (whose first point is taken to be `start`'s position) to rest at the route's end,
/// in `free`, within `limits` — what a replan in flight switches to without stopping.
///
/// Minimum jerk in a corridor as [`plan`], with the start's velocity and acceleration held;
/// the durations come from a speed profile that starts at the start's speed, and any piece
/// over a limit is flown slower until every bound holds. There is no stop-at-each-waypoint
/// fallback from a moving start: when no curve passes [`verify_from`], the error says why
/// (the caller stops the vehicle instead). A start at rest is [`plan`]'s.
///
/// ```
/// use skyplan_trajectory::{plan, plan_from, GridLayer, Limits, Options};
/// use skyplan_cspace::Grid2;
/// // An empty 60 m × 60 m square at 10 m.
/// let free = GridLayer::new(Grid2::from_ascii(&(".".repeat(60) + "\n").repeat(60))?, 10.0);
/// let first = plan(&[[5.0, 5.0, 10.0], [5.0, 55.0, 10.0]], &free, &Limits::default(), &Options::default())?;
/// // Half-way east, turn north instead, without stopping.
/// let now = first.state_at(first.duration_s() / 2.0);
/// let turn = [now.point_neu, [55.0, now.point_neu[1], 10.0]];
/// let next = plan_from(&now, &turn, &free, &Limits::default(), &Options::default())?;
/// let s = next.state_at(0.0);
/// assert!((0..3).all(|i| (s.vel_neu_m_s[i] - now.vel_neu_m_s[i]).abs() < 1e-6));
/// assert_eq!(next.state_at(next.duration_s()).vel_neu_m_s, [0.0; 3]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn plan_from(
    start: &State,
    route: &[Neu],
    free: &dyn FreeSpace,
    limits: &Limits,
    opts: &Options,
) -> Result<Trajectory, TrajectoryError> {
    let t0 = Instant::now();
    limits.check()?;
    let (vel, accel) = (start.vel_neu_m_s, start.accel_neu_m_s2);
    if ![vel, accel, start.point_neu]
        .iter()
        .flatten()
        .chain([&start.yaw_rad])
        .all(|v| v.is_finite())
    {
        return Err(TrajectoryError::Route(
            "starts in a state that is not a number".into(),
        ));
    }
    let mut points = route.to_vec();
    if let Some(first) = points.first_mut() {
        *first = start.point_neu;
    }
    // A start evaluated on a level curve may be an ulp off the level: it is the level.
    if points.len() >= 2 && (points[0][2] - points[1][2]).abs() <= 1e-6 {
        points[0][2] = points[1][2];
    }
    if vel == [0.0; 3] && accel == [0.0; 3] {
        return plan(&points, free, limits, opts);
    }
    let route = check_route(&points)?;
    let planar = route.iter().all(|p| (p[2] - route[0][2]).abs() <= 1e-9)
        && vel[2].abs() <= 1e-12
        && accel[2].abs() <= 1e-12;
    let deadline = t0 + opts.budget;
    // The route as given; failing that (a sharp turn at speed leaves the corridor no room to
    // brake), with a run-out straight ahead first — the braking distance, then two thirds of
    // it — where that is free.
    let speed = bezier::norm(vel);
    let brake_m = speed * speed / (2.0 * limits.max_accel_m_s2)
        + speed * limits.max_accel_m_s2 / limits.max_jerk_m_s3;
    let mut why = String::new();
    for run_out_m in [0.0, brake_m, brake_m * 2.0 / 3.0] {
        let mut tried = route.clone();
        if run_out_m > 0.0 {
            let p = route[0];
            let ahead = [0, 1, 2].map(|i| p[i] + vel[i] / speed.max(1e-9) * run_out_m);
            if !(free.segment_is_free(p, ahead) && free.segment_is_free(ahead, route[1])) {
                continue;
            }
            tried.insert(1, ahead);
        }
        match moving_pieces(&tried, free, planar, limits, opts, deadline, (vel, accel)) {
            Ok(pieces) => {
                let yaw = yaw::profile(&pieces, limits.max_yaw_rate_rad_s(), Some(start.yaw_rad));
                let mut traj = Trajectory {
                    method: Method::MinimumJerk,
                    fallback_reason: None,
                    limits: *limits,
                    bounds: Bounds::default(),
                    pieces,
                    yaw,
                    compute_us: 0,
                };
                match verify_from(&traj, free, vel, accel) {
                    Ok(b) => {
                        traj.bounds = b;
                        traj.compute_us = t0.elapsed().as_micros() as u64;
                        return Ok(traj);
                    }
                    Err(e) => why = e,
                }
            }
            Err(TrajectoryError::Unproven(e)) => why = e,
            Err(e) if why.is_empty() => return Err(e),
            Err(_) => {}
        }
    }
    Err(TrajectoryError::Unproven(format!(
        "from the moving start: {why}"
    )))
}

/// The minimum-jerk pieces through `route` from a start moving at `vel` with `accel`.
fn moving_pieces(
    route: &[Neu],
    free: &dyn FreeSpace,
    planar: bool,
    limits: &Limits,
    opts: &Options,
    deadline: Instant,
    (vel, accel): (Neu, Neu),
) -> Result<Vec<Piece>, TrajectoryError> {
    let corridor_opts = opts.corridor.unwrap_or(CorridorOptions {
        piece_m: 50.0,
        grow_m: 20.0,
    });
    // Short stretches first: the start's motion is turned in the first pieces, and each gets
    // its own box to swing out into.
    let mut points = split_legs(route, limits);
    let first_leg_m = skyplan_world3::distance_m(points[0], points[1]);
    let cuts: Vec<Neu> = [3.0, 8.0, 15.0]
        .iter()
        .filter(|&&d| d < first_leg_m - 1.0)
        .map(|&d| skyplan_world3::lerp(points[0], points[1], d / first_leg_m))
        .collect();
    points.splice(1..1, cuts);
    let cells = build_corridor(&points, free, planar, &corridor_opts)?;
    optimize::minimum_jerk_from(&cells, planar, limits, deadline, vel, accel)
        .map_err(TrajectoryError::Unproven)
}
