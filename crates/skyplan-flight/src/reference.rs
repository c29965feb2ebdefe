//! A time-parametrised reference for the vehicle to follow: position, velocity, acceleration
//! and heading at each instant, in the local NED frame about the home.
//!
//! A [`Reference`] is what a trajectory generator produces and what
//! [`crate::executor::ReferenceExecutor`] flies: it streams [`Reference::setpoint`] of the
//! reference clock as position + velocity + acceleration targets (the feed-forward of
//! ArduCopter's GUIDED position-velocity-acceleration controller). [`MinJerkLine`] is a simple
//! one, rest to rest along straight legs, for tests and examples.
//!
//! ```
//! use skyplan_flight::reference::{MinJerkLine, Reference};
//! let r = MinJerkLine::new(vec![[0.0, 0.0, -5.0], [10.0, 0.0, -5.0]], vec![4.0])?;
//! assert_eq!(r.duration_s(), 4.0);
//! let mid = r.setpoint(2.0);
//! assert!((mid.point_ned[0] - 5.0).abs() < 1e-12);
//! assert!((mid.vel_ned_m_s[0] - 1.875 * 10.0 / 4.0).abs() < 1e-12); // peak speed
//! assert_eq!(r.setpoint(99.0).point_ned, [10.0, 0.0, -5.0]); // clamped, at rest
//! # Ok::<(), skyplan_flight::reference::ReferenceError>(())
//! ```

/// One instant of a time-parametrised reference, in the local NED frame about home.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setpoint {
    /// Position, metres north, east, down of home.
    pub point_ned: [f64; 3],
    /// Velocity, m/s north, east, down.
    pub vel_ned_m_s: [f64; 3],
    /// Acceleration, m/s² north, east, down.
    pub accel_ned_m_s2: [f64; 3],
    /// Heading, radians clockwise from north.
    pub yaw_rad: f64,
}

impl Setpoint {
    /// A setpoint at rest at `point_ned`, facing `yaw_rad`.
    pub fn at_rest(point_ned: [f64; 3], yaw_rad: f64) -> Self {
        Self {
            point_ned,
            vel_ned_m_s: [0.0; 3],
            accel_ned_m_s2: [0.0; 3],
            yaw_rad,
        }
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.point_ned
            .iter()
            .chain(&self.vel_ned_m_s)
            .chain(&self.accel_ned_m_s2)
            .all(|x| x.is_finite())
            && self.yaw_rad.is_finite()
    }

    /// Distance from a point (NED metres) to this setpoint's position, metres.
    pub fn distance_m(&self, point_ned: [f64; 3]) -> f64 {
        (0..3)
            .map(|i| (self.point_ned[i] - point_ned[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

/// A reference trajectory the vehicle follows from its own clock (t = 0 at the start, at rest).
pub trait Reference: Send + Sync {
    /// How long the reference lasts, seconds (finite, ≥ 0).
    fn duration_s(&self) -> f64;
    /// The setpoint at reference time `t_s`, clamped to `[0, duration_s]`.
    fn setpoint(&self, t_s: f64) -> Setpoint;
}

/// A reference that cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ReferenceError(pub String);

/// Rest to rest along straight legs: each leg from one point to the next is a minimum-jerk
/// quintic `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵` (τ = t / T) over its duration, stopping at every point; the
/// heading is that of the leg (its horizontal direction; a vertical leg keeps the previous one).
#[derive(Debug, Clone, PartialEq)]
pub struct MinJerkLine {
    points_ned: Vec<[f64; 3]>,
    durations_s: Vec<f64>,
    /// Reference time at which each leg starts.
    starts_s: Vec<f64>,
    yaws_rad: Vec<f64>,
}

/// The quintic's position, speed and acceleration factors at `tau` in [0, 1] for a leg of
/// duration `t_s`: (s, ds/dt, d²s/dt²).
fn quintic(tau: f64, t_s: f64) -> (f64, f64, f64) {
    let (t2, t3) = (tau * tau, tau * tau * tau);
    let s = t3 * (10.0 - 15.0 * tau + 6.0 * t2);
    let ds = 30.0 * t2 * (1.0 - tau).powi(2) / t_s;
    let dds = (60.0 * tau - 180.0 * t2 + 120.0 * t3) / (t_s * t_s);
    (s, ds, dds)
}

impl MinJerkLine {
    /// Through `points_ned` (at least two, finite), leg `k` from point `k` to `k + 1` taking
    /// `durations_s[k]` seconds (finite, > 0).
    pub fn new(points_ned: Vec<[f64; 3]>, durations_s: Vec<f64>) -> Result<Self, ReferenceError> {
        if points_ned.len() < 2 {
            return Err(ReferenceError(
                "a reference needs at least two points".into(),
            ));
        }
        if durations_s.len() + 1 != points_ned.len() {
            return Err(ReferenceError(format!(
                "{} points need {} leg durations, not {}",
                points_ned.len(),
                points_ned.len() - 1,
                durations_s.len()
            )));
        }
        if points_ned.iter().flatten().any(|x| !x.is_finite()) {
            return Err(ReferenceError("a point is not finite".into()));
        }
        if durations_s.iter().any(|d| !d.is_finite() || *d <= 0.0) {
            return Err(ReferenceError(
                "every leg duration must be finite and positive".into(),
            ));
        }
        let mut starts_s = Vec::with_capacity(durations_s.len());
        let mut t = 0.0;
        for d in &durations_s {
            starts_s.push(t);
            t += d;
        }
        let mut yaws_rad = Vec::with_capacity(durations_s.len());
        let mut yaw = 0.0;
        for w in points_ned.windows(2) {
            let (dn, de) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            if dn.hypot(de) > 1e-9 {
                yaw = de.atan2(dn);
            }
            yaws_rad.push(yaw);
        }
        Ok(Self {
            points_ned,
            durations_s,
            starts_s,
            yaws_rad,
        })
    }

    /// Through `points_ned`, each leg timed so that its peak speed (1.875 × length / duration
    /// for the quintic) is `peak_speed_m_s` (finite, > 0); legs of zero length last 1 s.
    ///
    /// ```
    /// use skyplan_flight::reference::{MinJerkLine, Reference};
    /// let r = MinJerkLine::at_peak_speed(vec![[0.0, 0.0, -5.0], [0.0, 30.0, -5.0]], 6.0)?;
    /// assert!((r.duration_s() - 1.875 * 30.0 / 6.0).abs() < 1e-12);
    /// # Ok::<(), skyplan_flight::reference::ReferenceError>(())
    /// ```
    pub fn at_peak_speed(
        points_ned: Vec<[f64; 3]>,
        peak_speed_m_s: f64,
    ) -> Result<Self, ReferenceError> {
        if !peak_speed_m_s.is_finite() || peak_speed_m_s <= 0.0 {
            return Err(ReferenceError(format!(
                "the peak speed {peak_speed_m_s} m/s is not positive"
            )));
        }
        let durations = points_ned
            .windows(2)
            .map(|w| {
                let len: f64 = (0..3).map(|i| (w[1][i] - w[0][i]).powi(2)).sum::<f64>();
                match len.sqrt() {
                    l if l > 1e-9 => 1.875 * l / peak_speed_m_s,
                    _ => 1.0,
                }
            })
            .collect();
        Self::new(points_ned, durations)
    }

    /// The points, in order.
    pub fn points_ned(&self) -> &[[f64; 3]] {
        &self.points_ned
    }

    /// The legs' durations, seconds.
    pub fn durations_s(&self) -> &[f64] {
        &self.durations_s
    }
}

/// One reference followed up to `at_s`, then another from its own start: what a replan in
/// flight makes of the trajectory being flown (the second starts in the first's state at
/// `at_s`, so the setpoints run on without a jump).
///
/// ```
/// use std::sync::Arc;
/// use skyplan_flight::reference::{MinJerkLine, Reference, Spliced};
/// let first = Arc::new(MinJerkLine::new(vec![[0.0, 0.0, -5.0], [10.0, 0.0, -5.0]], vec![4.0])?);
/// let then = Arc::new(MinJerkLine::new(vec![[10.0, 0.0, -5.0], [10.0, 10.0, -5.0]], vec![5.0])?);
/// let r = Spliced::new(first, 4.0, then);
/// assert_eq!(r.duration_s(), 9.0);
/// assert_eq!(r.setpoint(2.0).point_ned[0], 5.0);
/// assert_eq!(r.setpoint(9.0).point_ned, [10.0, 10.0, -5.0]);
/// # Ok::<(), skyplan_flight::reference::ReferenceError>(())
/// ```
#[derive(Clone)]
pub struct Spliced {
    first: std::sync::Arc<dyn Reference>,
    at_s: f64,
    then: std::sync::Arc<dyn Reference>,
}

impl Spliced {
    /// `first` up to its time `at_s` (clamped to its duration), then `then`.
    pub fn new(
        first: std::sync::Arc<dyn Reference>,
        at_s: f64,
        then: std::sync::Arc<dyn Reference>,
    ) -> Self {
        let at_s = at_s.clamp(0.0, first.duration_s());
        Self { first, at_s, then }
    }

    /// When the second reference takes over, seconds of this one's clock.
    pub fn switch_s(&self) -> f64 {
        self.at_s
    }
}

impl Reference for Spliced {
    fn duration_s(&self) -> f64 {
        self.at_s + self.then.duration_s()
    }

    fn setpoint(&self, t_s: f64) -> Setpoint {
        if t_s < self.at_s {
            self.first.setpoint(t_s)
        } else {
            self.then.setpoint(t_s - self.at_s)
        }
    }
}

impl Reference for MinJerkLine {
    fn duration_s(&self) -> f64 {
        self.durations_s.iter().sum()
    }

    fn setpoint(&self, t_s: f64) -> Setpoint {
        let t = if t_s.is_nan() { 0.0 } else { t_s };
        let t = t.clamp(0.0, self.duration_s());
        // The last leg that has started by `t`.
        let k = self.starts_s.partition_point(|s| *s <= t).saturating_sub(1);
        let (a, b, d) = (
            self.points_ned[k],
            self.points_ned[k + 1],
            self.durations_s[k],
        );
        let tau = ((t - self.starts_s[k]) / d).clamp(0.0, 1.0);
        let (s, ds, dds) = quintic(tau, d);
        Setpoint {
            point_ned: std::array::from_fn(|i| a[i] + (b[i] - a[i]) * s),
            vel_ned_m_s: std::array::from_fn(|i| (b[i] - a[i]) * ds),
            accel_ned_m_s2: std::array::from_fn(|i| (b[i] - a[i]) * dds),
            yaw_rad: self.yaws_rad[k],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> MinJerkLine {
        MinJerkLine::new(
            vec![[0.0, 0.0, -10.0], [80.0, 0.0, -10.0], [80.0, 60.0, -12.0]],
            vec![20.0, 15.0],
        )
        .unwrap()
    }

    #[test]
    fn starts_and_ends_at_rest_at_the_points_and_stops_at_each_corner() {
        let r = square();
        assert_eq!(r.duration_s(), 35.0);
        for (t, p) in [(0.0, 0), (20.0, 1), (35.0, 2)] {
            let s = r.setpoint(t);
            for i in 0..3 {
                assert!(
                    (s.point_ned[i] - r.points_ned()[p][i]).abs() < 1e-12,
                    "{t} {s:?}"
                );
                assert!(s.vel_ned_m_s[i].abs() < 1e-12, "{t} {s:?}");
                assert!(s.accel_ned_m_s2[i].abs() < 1e-12, "{t} {s:?}");
            }
        }
        assert_eq!(r.setpoint(-3.0), r.setpoint(0.0));
        assert_eq!(r.setpoint(1e9), r.setpoint(35.0));
        assert!((r.setpoint(10.0).yaw_rad).abs() < 1e-12);
        assert!((r.setpoint(30.0).yaw_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    /// Velocity and acceleration are the derivatives of the position (central differences).
    #[test]
    fn velocity_and_acceleration_are_the_derivatives_of_the_position() {
        let r = square();
        let h = 1e-4;
        for k in 1..350 {
            let t = f64::from(k) * 0.1;
            if (t - 20.0).abs() < 2.0 * h {
                continue;
            }
            let (m, s, p) = (r.setpoint(t - h), r.setpoint(t), r.setpoint(t + h));
            for i in 0..3 {
                let v = (p.point_ned[i] - m.point_ned[i]) / (2.0 * h);
                let a = (p.vel_ned_m_s[i] - m.vel_ned_m_s[i]) / (2.0 * h);
                assert!((v - s.vel_ned_m_s[i]).abs() < 1e-6, "{t}: {v} vs {s:?}");
                assert!((a - s.accel_ned_m_s2[i]).abs() < 1e-5, "{t}: {a} vs {s:?}");
            }
        }
    }

    #[test]
    fn bad_references_are_refused() {
        assert!(MinJerkLine::new(vec![[0.0; 3]], vec![]).is_err());
        assert!(MinJerkLine::new(vec![[0.0; 3], [1.0; 3]], vec![0.0]).is_err());
        assert!(MinJerkLine::new(vec![[0.0; 3], [1.0; 3]], vec![1.0, 1.0]).is_err());
        assert!(MinJerkLine::new(vec![[0.0; 3], [f64::NAN; 3]], vec![1.0]).is_err());
        assert!(MinJerkLine::at_peak_speed(vec![[0.0; 3], [1.0; 3]], 0.0).is_err());
    }
}
