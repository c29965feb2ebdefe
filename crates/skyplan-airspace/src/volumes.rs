//! A flight's 4D volumes: its route with times, cut into stretches, each stretch's footprint
//! grown by a lateral margin, its altitude band and its time window grown by buffers.

use crate::geometry::{LocalPlane, buffered_hull, convex_hull};
use crate::model::{Altitude, LatLng, Polygon, Volume3D, Volume4D};
use crate::{AirspaceError, Timestamp};
use serde::Serialize;
use skyplan_frames::{Lla, LocalFrame, Ned};
use skyplan_plan::Plan;

/// How a flight's volumes are made. The defaults suit a small multicopter on GNSS.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VolumeOptions {
    /// Lateral margin around the route (navigation error + safety), metres.
    pub lateral_margin_m: f64,
    /// Added below and above the route's altitudes, metres.
    pub vertical_buffer_m: f64,
    /// Added before and after each stretch's times, seconds.
    pub time_buffer_s: f64,
    /// Longest stretch of route in one volume, metres.
    pub stretch_m: f64,
    /// Longest stretch of time in one volume (before the buffer), seconds.
    pub stretch_s: f64,
    /// Cruise speed of the timing without a trajectory, m/s.
    pub cruise_m_s: f64,
    /// Acceleration of the timing without a trajectory, m/s².
    pub accel_m_s2: f64,
    /// Sample rate of the timing without a trajectory, Hz.
    pub sample_hz: f64,
    /// The home's height above the WGS84 ellipsoid, metres: the plan's altitudes are above
    /// home, the DSS's above the ellipsoid (skyplan's maps give no home height: 0).
    pub home_alt_w84_m: f64,
}

impl Default for VolumeOptions {
    /// 15 m lateral, 10 m vertical, 10 s time buffers; stretches of at most 150 m and 30 s;
    /// 10 m/s and 4 m/s² (the trajectory's default limits) sampled at 10 Hz; home at 0 m.
    fn default() -> Self {
        Self {
            lateral_margin_m: 15.0,
            vertical_buffer_m: 10.0,
            time_buffer_s: 10.0,
            stretch_m: 150.0,
            stretch_s: 30.0,
            cruise_m_s: 10.0,
            accel_m_s2: 4.0,
            sample_hz: 10.0,
            home_alt_w84_m: 0.0,
        }
    }
}

impl VolumeOptions {
    /// Refuses a value that is not finite and within its range, naming the field.
    pub fn check(&self) -> Result<(), AirspaceError> {
        for (field, value, lo, hi) in [
            ("lateral_margin_m", self.lateral_margin_m, 0.0, 10_000.0),
            ("vertical_buffer_m", self.vertical_buffer_m, 0.0, 10_000.0),
            ("time_buffer_s", self.time_buffer_s, 0.0, 86_400.0),
            ("stretch_m", self.stretch_m, 1.0, 100_000.0),
            ("stretch_s", self.stretch_s, 0.1, 86_400.0),
            ("cruise_m_s", self.cruise_m_s, 0.1, 100.0),
            ("accel_m_s2", self.accel_m_s2, 0.1, 50.0),
            ("sample_hz", self.sample_hz, 0.1, 1000.0),
            ("home_alt_w84_m", self.home_alt_w84_m, -1_000.0, 10_000.0),
        ] {
            if !(value >= lo && value <= hi) {
                return Err(AirspaceError::Invalid {
                    field: field.into(),
                    why: format!("{value} is not within {lo}..={hi}"),
                });
            }
        }
        Ok(())
    }
}

/// A point of the flight at a time after departure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimedPoint {
    /// Seconds after departure.
    pub t_s: f64,
    /// `[north_m, east_m, alt_m]` in the map's frame.
    pub nea: [f64; 3],
}

/// Where a flight's times came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Timing {
    /// The plan's trajectory samples.
    Trajectory,
    /// The route's polyline at a constant cruise speed, accelerating from rest at the start
    /// and braking to rest at the goal.
    ConstantSpeed,
    /// A space-time search's route: cell to cell at the cruise speed, hovering where it waits
    /// for another flight to pass (skyplan-fleet's safe-interval planner).
    SpaceTime,
}

/// The polyline `points` flown from rest to rest at `cruise_m_s` with `accel_m_s2`
/// (a trapezoidal speed profile over the whole length; corners are flown at speed), sampled
/// at `sample_hz` and at every corner.
///
/// ```
/// use skyplan_airspace::timed_route;
/// let path = timed_route(&[[0.0, 0.0, 10.0], [100.0, 0.0, 10.0]], 10.0, 4.0, 10.0)?;
/// // 2.5 s to reach 10 m/s (12.5 m), 7.5 s at 10 m/s, 2.5 s to stop.
/// assert_eq!(path.last().map(|p| p.t_s), Some(12.5));
/// assert_eq!(path.last().map(|p| p.nea), Some([100.0, 0.0, 10.0]));
/// # Ok::<(), skyplan_airspace::AirspaceError>(())
/// ```
pub fn timed_route(
    points: &[[f64; 3]],
    cruise_m_s: f64,
    accel_m_s2: f64,
    sample_hz: f64,
) -> Result<Vec<TimedPoint>, AirspaceError> {
    if points.is_empty() || points.iter().flatten().any(|c| !c.is_finite()) {
        return Err(AirspaceError::Route(
            "has no point, or one that is not finite".into(),
        ));
    }
    let (v, a) = (cruise_m_s, accel_m_s2);
    // Arc length at each point.
    let mut s_at = vec![0.0];
    for w in points.windows(2) {
        let d = ((w[1][0] - w[0][0]).powi(2)
            + (w[1][1] - w[0][1]).powi(2)
            + (w[1][2] - w[0][2]).powi(2))
        .sqrt();
        s_at.push(s_at.last().copied().unwrap_or(0.0) + d);
    }
    let length = s_at.last().copied().unwrap_or(0.0);
    // Trapezoid (or triangle when too short to reach the cruise speed).
    let peak = v.min((a * length).sqrt());
    let (t_ramp, d_ramp) = (peak / a, peak * peak / (2.0 * a));
    let total = 2.0 * t_ramp + (length - 2.0 * d_ramp).max(0.0) / peak.max(f64::MIN_POSITIVE);
    let total = if length > 0.0 { total } else { 0.0 };
    let s_of_t = |t: f64| -> f64 {
        if t <= t_ramp {
            0.5 * a * t * t
        } else if t <= total - t_ramp {
            d_ramp + peak * (t - t_ramp)
        } else {
            let r = (total - t).max(0.0);
            length - 0.5 * a * r * r
        }
        .clamp(0.0, length)
    };
    let t_of_s = |s: f64| -> f64 {
        if s <= d_ramp {
            (2.0 * s / a).sqrt()
        } else if s <= length - d_ramp {
            t_ramp + (s - d_ramp) / peak
        } else {
            total - (2.0 * (length - s).max(0.0) / a).sqrt()
        }
        .clamp(0.0, total)
    };
    let at_s = |s: f64| -> [f64; 3] {
        let k = s_at
            .partition_point(|&x| x <= s)
            .clamp(1, points.len().max(2) - 1);
        if points.len() == 1 {
            return points[0];
        }
        let (s0, s1) = (s_at[k - 1], s_at[k]);
        let f = if s1 > s0 {
            ((s - s0) / (s1 - s0)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        [0, 1, 2].map(|c| points[k - 1][c] + f * (points[k][c] - points[k - 1][c]))
    };
    let mut out: Vec<TimedPoint> = Vec::new();
    let steps = (total * sample_hz).floor() as usize;
    let mut corner = 0;
    for step in 0..=steps {
        let t = step as f64 / sample_hz;
        // Corners passed since the last sample, at their own times.
        while corner < points.len() && t_of_s(s_at[corner]) <= t {
            out.push(TimedPoint {
                t_s: t_of_s(s_at[corner]),
                nea: points[corner],
            });
            corner += 1;
        }
        out.push(TimedPoint {
            t_s: t,
            nea: at_s(s_of_t(t)),
        });
    }
    for (k, &p) in points.iter().enumerate().skip(corner) {
        out.push(TimedPoint {
            t_s: t_of_s(s_at[k]),
            nea: p,
        });
    }
    out.dedup_by(|b, a| a.t_s == b.t_s && a.nea == b.nea);
    Ok(out)
}

/// A plan's route with times: its trajectory's samples when it has one, else
/// [`timed_route`] over its waypoints with the options' cruise speed and acceleration.
pub fn timed_path(
    plan: &Plan,
    options: &VolumeOptions,
) -> Result<(Vec<TimedPoint>, Timing), AirspaceError> {
    if let Some(t) = &plan.trajectory {
        let path: Vec<TimedPoint> = t
            .samples
            .iter()
            .map(|r| TimedPoint {
                t_s: r[0],
                nea: [r[1], r[2], r[3]],
            })
            .collect();
        if !path.is_empty() {
            return Ok((path, Timing::Trajectory));
        }
    }
    let path = timed_route(
        &plan.points_nea(),
        options.cruise_m_s,
        options.accel_m_s2,
        options.sample_hz,
    )?;
    Ok((path, Timing::ConstantSpeed))
}

/// A flight's volumes, for a departure at the Unix epoch: [`FlightVolumes::at`] moves them to
/// any departure.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlightVolumes {
    /// The volumes as if the flight left at 1970-01-01T00:00:00Z.
    pub relative: Vec<Volume4D>,
    /// The flight's duration, seconds.
    pub duration_s: f64,
    /// Where the times came from.
    pub timing: Timing,
    /// The route with times the volumes cover.
    #[serde(skip)]
    pub path: Vec<TimedPoint>,
}

impl FlightVolumes {
    /// The volumes for a departure at `departure`.
    pub fn at(&self, departure: Timestamp) -> Vec<Volume4D> {
        self.relative
            .iter()
            .map(|v| v.shifted_ms(departure.unix_ms()))
            .collect()
    }
}

/// The volumes of `plan` (its map needs a geodetic home).
pub fn volumes_from_plan(
    plan: &Plan,
    options: &VolumeOptions,
) -> Result<FlightVolumes, AirspaceError> {
    let home = plan.home.ok_or(AirspaceError::NoHome)?;
    let frame = LocalFrame::new(Lla {
        lat_deg: home.lat_deg,
        lon_deg: home.lon_deg,
        alt_m: 0.0,
    })?;
    let (path, timing) = timed_path(plan, options)?;
    volumes_from_path(path, timing, &frame, options)
}

/// The volumes of a route with times in `frame`: the route cut into stretches of at most
/// `stretch_m` and `stretch_s` (at its points; consecutive stretches share one), each
/// stretch's points' convex hull grown by the lateral margin (an 8-gon circumscribing the
/// disc at each hull vertex), turned to latitude and longitude, its altitudes and times
/// grown by their buffers (times rounded outwards to the millisecond).
pub fn volumes_from_path(
    path: Vec<TimedPoint>,
    timing: Timing,
    frame: &LocalFrame,
    options: &VolumeOptions,
) -> Result<FlightVolumes, AirspaceError> {
    volumes_cut(path, timing, frame, options, None)
}

/// [`volumes_from_path`], with every stretch also ending before a point of it would lie more
/// than `max_bulge_m` from the straight line between its ends: each volume's footprint is then
/// within `2 · max_bulge_m` plus the margin of the route itself (every point of the stretch's
/// hull is within `max_bulge_m` of that chord, and every point of the chord within
/// `max_bulge_m` of the route between its ends). With 0, stretches end at every corner.
///
/// ```
/// use skyplan_airspace::{TimedPoint, Timing, VolumeOptions, volumes_hugging_path};
/// use skyplan_frames::{LocalFrame, Lla};
/// let frame = LocalFrame::new(Lla { lat_deg: 37.79, lon_deg: -122.39, alt_m: 0.0 })?;
/// let p = |t_s, n, e| TimedPoint { t_s, nea: [n, e, 20.0] };
/// // An L: 5 s north, 5 s east.
/// let path = vec![p(0.0, 0.0, 0.0), p(5.0, 50.0, 0.0), p(10.0, 50.0, 50.0)];
/// let o = VolumeOptions::default();
/// assert_eq!(skyplan_airspace::volumes_from_path(path.clone(), Timing::SpaceTime, &frame, &o)?.relative.len(), 1);
/// assert_eq!(volumes_hugging_path(path.clone(), Timing::SpaceTime, &frame, &o, 0.0)?.relative.len(), 2);
/// // A stair of 1 m steps keeps within 1 m of its chord: one volume.
/// let stair: Vec<TimedPoint> = (0..10).map(|k| p(k as f64, (k / 2) as f64, ((k + 1) / 2) as f64)).collect();
/// assert_eq!(volumes_hugging_path(stair, Timing::SpaceTime, &frame, &o, 1.0)?.relative.len(), 1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn volumes_hugging_path(
    path: Vec<TimedPoint>,
    timing: Timing,
    frame: &LocalFrame,
    options: &VolumeOptions,
    max_bulge_m: f64,
) -> Result<FlightVolumes, AirspaceError> {
    volumes_cut(path, timing, frame, options, Some(max_bulge_m.max(0.0)))
}

/// Whether every point of `path[i..=j]` is within `max` of the segment between its ends.
fn hugs_chord(path: &[TimedPoint], i: usize, j: usize, max: f64) -> bool {
    let (a, b) = (path[i].nea, path[j].nea);
    let d = [0, 1, 2].map(|c| b[c] - a[c]);
    let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    path[i..=j].iter().all(|p| {
        let w = [0, 1, 2].map(|c| p.nea[c] - a[c]);
        let t = if len2 > 0.0 {
            ((w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let e = [0, 1, 2].map(|c| w[c] - t * d[c]);
        (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() <= max + 1e-9
    })
}

fn volumes_cut(
    path: Vec<TimedPoint>,
    timing: Timing,
    frame: &LocalFrame,
    options: &VolumeOptions,
    max_bulge_m: Option<f64>,
) -> Result<FlightVolumes, AirspaceError> {
    options.check()?;
    if path.is_empty()
        || path
            .iter()
            .any(|p| !(p.t_s.is_finite() && p.nea.iter().all(|c| c.is_finite())))
    {
        return Err(AirspaceError::Route(
            "has no point, or one that is not finite".into(),
        ));
    }
    if path.windows(2).any(|w| w[1].t_s < w[0].t_s) {
        return Err(AirspaceError::Route("goes back in time".into()));
    }
    let dist = |a: &TimedPoint, b: &TimedPoint| {
        ((b.nea[0] - a.nea[0]).powi(2)
            + (b.nea[1] - a.nea[1]).powi(2)
            + (b.nea[2] - a.nea[2]).powi(2))
        .sqrt()
    };
    let mut volumes = Vec::new();
    let mut i = 0;
    loop {
        let mut j = (i + 1).min(path.len() - 1);
        let mut length = if j > i { dist(&path[i], &path[j]) } else { 0.0 };
        while j + 1 < path.len() {
            if max_bulge_m.is_some_and(|m| !hugs_chord(&path, i, j + 1, m)) {
                break;
            }
            let more = length + dist(&path[j], &path[j + 1]);
            if more > options.stretch_m || path[j + 1].t_s - path[i].t_s > options.stretch_s {
                break;
            }
            length = more;
            j += 1;
        }
        volumes.push(stretch_volume(&path[i..=j], frame, options)?);
        if j + 1 >= path.len() {
            break;
        }
        i = j;
    }
    let duration_s = path.last().map_or(0.0, |p| p.t_s) - path[0].t_s;
    Ok(FlightVolumes {
        relative: volumes,
        duration_s,
        timing,
        path,
    })
}

/// One stretch's volume (departure at the epoch).
fn stretch_volume(
    stretch: &[TimedPoint],
    frame: &LocalFrame,
    o: &VolumeOptions,
) -> Result<Volume4D, AirspaceError> {
    let en: Vec<[f64; 2]> = stretch.iter().map(|p| [p.nea[1], p.nea[0]]).collect();
    let grown = buffered_hull(&en, o.lateral_margin_m.max(0.01), 8);
    let mut lat_lng = Vec::with_capacity(grown.len());
    for [east_m, north_m] in grown {
        let lla = frame.lla_from_ned(Ned {
            north_m,
            east_m,
            down_m: 0.0,
        })?;
        lat_lng.push(LatLng {
            lat: lla.lat_deg,
            lng: lla.lon_deg,
        });
    }
    // Convex again in latitude and longitude (the projection bends straight lines by far
    // less than the margin).
    let plane = LocalPlane::about(lat_lng[0]);
    let xy: Vec<[f64; 2]> = lat_lng.iter().map(|&p| plane.xy(p)).collect();
    let vertices = convex_hull(&xy)
        .into_iter()
        .map(|p| plane.lat_lng(p))
        .collect();
    let (lo, hi) = stretch
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.nea[2]), hi.max(p.nea[2]))
        });
    let (t0, t1) = (stretch[0].t_s, stretch[stretch.len() - 1].t_s);
    let ms = |s: f64| Timestamp::from_unix_ms(s as i64);
    Ok(Volume4D {
        volume: Volume3D {
            outline_polygon: Polygon { vertices },
            altitude_lower: Altitude::w84_m(o.home_alt_w84_m + lo - o.vertical_buffer_m),
            altitude_upper: Altitude::w84_m(o.home_alt_w84_m + hi + o.vertical_buffer_m),
        },
        time_start: ms(((t0 - o.time_buffer_s) * 1000.0).floor()).into(),
        time_end: ms(((t1 + o.time_buffer_s) * 1000.0).ceil()).into(),
    })
}
