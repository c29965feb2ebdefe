//! MAVLink `OBSTACLE_DISTANCE` (id 330) to and from [`ObstacleReading`].
//!
//! As common.xml defines it: 72 `distances` in centimetres, element 0 at `angle_offset` degrees
//! from the frame's forward axis, each `increment_f` degrees wide (or `increment` when
//! `increment_f` is 0; negative: counter-clockwise); `UINT16_MAX` is "unknown / not used",
//! `max_distance + 1` (anything above `max_distance`) is "no obstacle within range". The frame
//! says what element 0 is measured from: north for the earth frames (`MAV_FRAME_GLOBAL*`,
//! `MAV_FRAME_LOCAL_NED`, `MAV_FRAME_LOCAL_OFFSET_NED`; `MAV_FRAME_GLOBAL` = 0 is the
//! default), the vehicle's nose for the body frames (`MAV_FRAME_BODY_FRD`, and the deprecated
//! `MAV_FRAME_BODY_NED` / `MAV_FRAME_BODY_OFFSET_NED`, as ArduPilot reads them).
//!
//! skyplan's simulator sends `MAV_FRAME_LOCAL_NED` (true north), `increment` 5 and
//! `increment_f` 5.0, `angle_offset` 0 (element 0 centred on north), `min_distance` 20 cm.
//! Readings are turned into the map's frame (grid north) by the UTM convergence.
//!
//! And MAVLink `DISTANCE_SENSOR` (id 132), which is what ArduPilot's proximity library sends a
//! ground station (it never sends `OBSTACLE_DISTANCE` itself): one message per horizontal body
//! orientation (`MAV_SENSOR_ROTATION_NONE` … `YAW_315`, ids 10–17), each the nearest obstacle in
//! that 45° wedge in centimetres, `max_distance` − 10 cm when nothing is within range
//! ([`distance_sensors`], [`reading_from_distance_sensor`]). The wedge does not say where in it
//! the obstacle is, so a reading puts it on the whole arc at that distance: conservative.

use mavlink::dialects::common::{
    DISTANCE_SENSOR_DATA, MavDistanceSensor, MavFrame, MavMessage, MavSensorOrientation,
    OBSTACLE_DISTANCE_DATA,
};
use skyplan_flight::sensing::{ObstacleReading, SectorRange};
use skyplan_flight::sensor::{RangeSensor, SECTORS};

/// Why an `OBSTACLE_DISTANCE` was not used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ObstacleError {
    /// `increment` and `increment_f` are both 0.
    #[error("OBSTACLE_DISTANCE: increment and increment_f are both 0 (sector width unknown)")]
    NoIncrement,
    /// A frame that is neither north- nor nose-aligned.
    #[error(
        "OBSTACLE_DISTANCE: frame {0} is not supported (expected MAV_FRAME_LOCAL_NED, a MAV_FRAME_GLOBAL* frame or MAV_FRAME_BODY_FRD)"
    )]
    Frame(u32),
    /// A `DISTANCE_SENSOR` whose `max_distance` is 0 or not above `min_distance`.
    #[error("DISTANCE_SENSOR: max_distance {max_cm} cm is not above min_distance {min_cm} cm")]
    SensorRange {
        /// `min_distance`, cm.
        min_cm: u16,
        /// `max_distance`, cm.
        max_cm: u16,
    },
    /// `max_distance` is 0 or not above `min_distance`.
    #[error("OBSTACLE_DISTANCE: max_distance {max_cm} cm is not above min_distance {min_cm} cm")]
    Range {
        /// `min_distance`, cm.
        min_cm: u16,
        /// `max_distance`, cm.
        max_cm: u16,
    },
}

/// What sector 0 of a frame is measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reference {
    /// North (earth frames).
    North,
    /// The vehicle's nose (body frames): rotated by its yaw.
    Nose,
}

/// The reference of a MAV_FRAME, if supported.
#[allow(deprecated)]
pub fn frame_reference(frame: MavFrame) -> Option<Reference> {
    use MavFrame::*;
    match frame {
        MAV_FRAME_GLOBAL
        | MAV_FRAME_GLOBAL_INT
        | MAV_FRAME_GLOBAL_RELATIVE_ALT
        | MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
        | MAV_FRAME_GLOBAL_TERRAIN_ALT
        | MAV_FRAME_GLOBAL_TERRAIN_ALT_INT
        | MAV_FRAME_LOCAL_NED
        | MAV_FRAME_LOCAL_OFFSET_NED => Some(Reference::North),
        MAV_FRAME_BODY_FRD | MAV_FRAME_BODY_NED | MAV_FRAME_BODY_OFFSET_NED => {
            Some(Reference::Nose)
        }
        _ => None,
    }
}

/// A sweep as `OBSTACLE_DISTANCE` in `MAV_FRAME_LOCAL_NED` (sector 0 centred on true north,
/// 5° clockwise steps). `time_usec` is the time since boot.
///
/// ```
/// use skyplan_flight::sensing::SectorRange;
/// use skyplan_flight::sensor::RangeSensor;
/// use skyplan_link::obstacle::obstacle_distance;
/// use mavlink::dialects::common::MavMessage;
/// let mut sweep = vec![SectorRange::Clear; 72];
/// sweep[18] = SectorRange::Obstacle(12.345);
/// sweep[40] = SectorRange::Unknown;
/// let MavMessage::OBSTACLE_DISTANCE(m) = obstacle_distance(&sweep, &RangeSensor::default(), 0) else { unreachable!() };
/// assert_eq!((m.distances[18], m.distances[0], m.distances[40]), (1235, 3001, u16::MAX));
/// assert_eq!((m.min_distance, m.max_distance, m.increment, m.increment_f), (20, 3000, 5, 5.0));
/// ```
pub fn obstacle_distance(
    sweep: &[SectorRange],
    sensor: &RangeSensor,
    time_usec: u64,
) -> MavMessage {
    let min_cm = (sensor.min_range_m * 100.0).round().clamp(0.0, 65533.0) as u16;
    let max_cm = (sensor.max_range_m * 100.0)
        .round()
        .clamp(f64::from(min_cm) + 1.0, 65534.0) as u16;
    let mut distances = [u16::MAX; SECTORS];
    for (d, r) in distances.iter_mut().zip(sweep) {
        *d = match r {
            SectorRange::Obstacle(m) => (m * 100.0)
                .round()
                .clamp(f64::from(min_cm), f64::from(max_cm))
                as u16,
            SectorRange::Clear => max_cm + 1,
            SectorRange::Unknown => u16::MAX,
        };
    }
    let step_deg = 360.0 / SECTORS as f64;
    MavMessage::OBSTACLE_DISTANCE(OBSTACLE_DISTANCE_DATA {
        time_usec,
        distances,
        min_distance: min_cm,
        max_distance: max_cm,
        sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
        increment: step_deg as u8,
        increment_f: step_deg as f32,
        angle_offset: 0.0,
        frame: MavFrame::MAV_FRAME_LOCAL_NED,
    })
}

/// Decodes an `OBSTACLE_DISTANCE` into a reading in the map's frame: `time_s` and
/// `position_ned` are the vehicle's then (map frame), `yaw_true_rad` its heading from true north
/// (used by body frames), `convergence_rad` the true bearing of the map's grid north (0 for a
/// true-north map).
///
/// ```
/// use mavlink::dialects::common::{MavFrame, OBSTACLE_DISTANCE_DATA};
/// use skyplan_flight::sensing::SectorRange;
/// use skyplan_link::obstacle::reading_from_obstacle_distance;
/// let mut m = OBSTACLE_DISTANCE_DATA { min_distance: 10, max_distance: 2000, increment: 10, ..Default::default() };
/// m.distances = [2001; 72];
/// m.distances[0] = 500;               // 5 m ahead of the nose
/// m.distances[1] = u16::MAX;          // not measured
/// m.frame = MavFrame::MAV_FRAME_BODY_FRD;
/// let yaw = 90f64.to_radians();       // the nose points east
/// let r = reading_from_obstacle_distance(&m, 1.0, [0.0, 0.0, -5.0], yaw, 0.0)?;
/// assert_eq!((r.ranges[0], r.ranges[1], r.ranges[2]), (SectorRange::Obstacle(5.0), SectorRange::Unknown, SectorRange::Clear));
/// let hit: Vec<[f64; 2]> = r.hits_ne().collect();
/// assert!(hit[0][0].abs() < 1e-9 && (hit[0][1] - 5.0).abs() < 1e-9); // 5 m east
/// # Ok::<(), skyplan_link::obstacle::ObstacleError>(())
/// ```
pub fn reading_from_obstacle_distance(
    m: &OBSTACLE_DISTANCE_DATA,
    time_s: f64,
    position_ned: [f64; 3],
    yaw_true_rad: f64,
    convergence_rad: f64,
) -> Result<ObstacleReading, ObstacleError> {
    let increment_deg = if m.increment_f != 0.0 && m.increment_f.is_finite() {
        f64::from(m.increment_f)
    } else if m.increment != 0 {
        f64::from(m.increment)
    } else {
        return Err(ObstacleError::NoIncrement);
    };
    if m.max_distance == 0 || m.max_distance <= m.min_distance {
        return Err(ObstacleError::Range {
            min_cm: m.min_distance,
            max_cm: m.max_distance,
        });
    }
    let reference = frame_reference(m.frame).ok_or(ObstacleError::Frame(m.frame as u32))?;
    let offset_deg = if m.angle_offset.is_finite() {
        f64::from(m.angle_offset)
    } else {
        0.0
    };
    let base_rad = match reference {
        Reference::North => 0.0,
        Reference::Nose => yaw_true_rad,
    };
    // Sectors beyond a full turn repeat earlier bearings: unknown.
    let used = ((360.0 / increment_deg.abs()).round() as usize).clamp(1, SECTORS);
    let ranges = m
        .distances
        .iter()
        .enumerate()
        .map(|(i, &cm)| {
            if cm == u16::MAX || i >= used {
                SectorRange::Unknown
            } else if cm > m.max_distance {
                SectorRange::Clear
            } else {
                SectorRange::Obstacle(f64::from(cm) * 0.01)
            }
        })
        .collect();
    Ok(ObstacleReading {
        time_s,
        position_ned,
        velocity_ned_m_s: [0.0; 3],
        first_bearing_rad: base_rad + offset_deg.to_radians() - convergence_rad,
        increment_rad: increment_deg.to_radians(),
        min_range_m: f64::from(m.min_distance) * 0.01,
        max_range_m: f64::from(m.max_distance) * 0.01,
        ranges,
    })
}

/// Width of the wedge one `DISTANCE_SENSOR` orientation covers when it does not say
/// (`horizontal_fov` 0), degrees: ArduPilot's proximity sectors.
pub const WEDGE_DEG: f64 = 45.0;

/// The body yaw of a horizontal `DISTANCE_SENSOR` orientation, degrees (`None`: not
/// horizontal, as up and down are).
pub fn orientation_yaw_deg(o: MavSensorOrientation) -> Option<f64> {
    use MavSensorOrientation::*;
    let k = match o {
        MAV_SENSOR_ROTATION_NONE => 0,
        MAV_SENSOR_ROTATION_YAW_45 => 1,
        MAV_SENSOR_ROTATION_YAW_90 => 2,
        MAV_SENSOR_ROTATION_YAW_135 => 3,
        MAV_SENSOR_ROTATION_YAW_180 => 4,
        MAV_SENSOR_ROTATION_YAW_225 => 5,
        MAV_SENSOR_ROTATION_YAW_270 => 6,
        MAV_SENSOR_ROTATION_YAW_315 => 7,
        _ => return None,
    };
    Some(WEDGE_DEG * f64::from(k))
}

/// The angle from `b` to `a`, degrees in (−180, 180].
fn diff_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    if d > 180.0 { d - 360.0 } else { d }
}

/// A sweep (sector 0 on true north, 5° steps) as ArduPilot's proximity library reports it to a
/// ground station: eight `DISTANCE_SENSOR`s, ids 10–17, orientation `k` the wedge of 45° centred
/// `45 k`° clockwise from the nose (`yaw_true_rad`), each the nearest obstacle in its wedge, or
/// `max_distance` − 10 cm when none is within range.
///
/// ```
/// use mavlink::dialects::common::MavMessage;
/// use skyplan_flight::sensing::SectorRange;
/// use skyplan_flight::sensor::RangeSensor;
/// use skyplan_link::obstacle::distance_sensors;
/// let mut sweep = vec![SectorRange::Clear; 72];
/// sweep[18] = SectorRange::Obstacle(12.0); // 12 m due east
/// let nose_north = distance_sensors(&sweep, &RangeSensor::default(), 0.0, 0);
/// let cm: Vec<u16> = nose_north.iter().map(|m| match m {
///     MavMessage::DISTANCE_SENSOR(d) => d.current_distance,
///     _ => unreachable!(),
/// }).collect();
/// assert_eq!(cm, [2990, 2990, 1200, 2990, 2990, 2990, 2990, 2990]); // the right-hand wedge
/// ```
pub fn distance_sensors(
    sweep: &[SectorRange],
    sensor: &RangeSensor,
    yaw_true_rad: f64,
    time_boot_ms: u32,
) -> Vec<MavMessage> {
    use MavSensorOrientation::*;
    let min_cm = (sensor.min_range_m * 100.0).round().clamp(0.0, 65533.0) as u16;
    let max_cm = (sensor.max_range_m * 100.0)
        .round()
        .clamp(f64::from(min_cm) + 11.0, 65534.0) as u16;
    let step_deg = 360.0 / sweep.len().max(1) as f64;
    let orientations = [
        MAV_SENSOR_ROTATION_NONE,
        MAV_SENSOR_ROTATION_YAW_45,
        MAV_SENSOR_ROTATION_YAW_90,
        MAV_SENSOR_ROTATION_YAW_135,
        MAV_SENSOR_ROTATION_YAW_180,
        MAV_SENSOR_ROTATION_YAW_225,
        MAV_SENSOR_ROTATION_YAW_270,
        MAV_SENSOR_ROTATION_YAW_315,
    ];
    orientations
        .iter()
        .enumerate()
        .map(|(k, &orientation)| {
            let centre = yaw_true_rad.to_degrees() + WEDGE_DEG * k as f64;
            let nearest = sweep
                .iter()
                .enumerate()
                .filter(|(i, _)| diff_deg(*i as f64 * step_deg, centre).abs() <= WEDGE_DEG / 2.0)
                .filter_map(|(_, r)| match r {
                    SectorRange::Obstacle(d) => Some(*d),
                    _ => None,
                })
                .fold(f64::INFINITY, f64::min);
            let current = if nearest.is_finite() {
                (nearest * 100.0)
                    .round()
                    .clamp(f64::from(min_cm), f64::from(max_cm - 11)) as u16
            } else {
                max_cm - 10
            };
            MavMessage::DISTANCE_SENSOR(DISTANCE_SENSOR_DATA {
                time_boot_ms,
                min_distance: min_cm,
                max_distance: max_cm,
                current_distance: current,
                mavtype: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
                id: 10 + k as u8,
                orientation,
                covariance: 0,
                horizontal_fov: WEDGE_DEG.to_radians() as f32,
                ..Default::default()
            })
        })
        .collect()
}

/// Decodes a `DISTANCE_SENSOR` of a horizontal orientation into a reading in the map's frame
/// (as [`reading_from_obstacle_distance`]): 72 sectors of 5°, those of its wedge
/// (`horizontal_fov`, else [`WEDGE_DEG`], centred on the nose's yaw plus the orientation's)
/// all at the distance read — where in the wedge the obstacle is is not known, so the whole arc
/// is taken as occupied — or clear when it reads within 10 cm of `max_distance` (ArduPilot's
/// 19990 of 20000); the others
/// unknown. `Ok(None)` for the other orientations (up, down, custom).
///
/// ```
/// use mavlink::dialects::common::{DISTANCE_SENSOR_DATA, MavSensorOrientation};
/// use skyplan_flight::sensing::SectorRange;
/// use skyplan_link::obstacle::reading_from_distance_sensor;
/// let m = DISTANCE_SENSOR_DATA { min_distance: 20, max_distance: 20000, current_distance: 1500,
///     orientation: MavSensorOrientation::MAV_SENSOR_ROTATION_YAW_90, ..Default::default() };
/// // The nose points north: the right-hand wedge is east, 67.5° to 112.5°.
/// let r = reading_from_distance_sensor(&m, 1.0, [0.0, 0.0, -5.0], 0.0, 0.0)?.unwrap();
/// assert_eq!(r.ranges[18], SectorRange::Obstacle(15.0));
/// assert_eq!((r.ranges[14], r.ranges[22], r.ranges[23]), (SectorRange::Obstacle(15.0), SectorRange::Obstacle(15.0), SectorRange::Unknown));
/// # Ok::<(), skyplan_link::obstacle::ObstacleError>(())
/// ```
pub fn reading_from_distance_sensor(
    m: &DISTANCE_SENSOR_DATA,
    time_s: f64,
    position_ned: [f64; 3],
    yaw_true_rad: f64,
    convergence_rad: f64,
) -> Result<Option<ObstacleReading>, ObstacleError> {
    let Some(body_deg) = orientation_yaw_deg(m.orientation) else {
        return Ok(None);
    };
    if m.max_distance == 0 || m.max_distance <= m.min_distance {
        return Err(ObstacleError::SensorRange {
            min_cm: m.min_distance,
            max_cm: m.max_distance,
        });
    }
    let fov = f64::from(m.horizontal_fov).to_degrees();
    let wedge_deg = if fov.is_finite() && fov > 0.0 && fov < 360.0 {
        fov
    } else {
        WEDGE_DEG
    };
    let value = if u32::from(m.current_distance) + 10 >= u32::from(m.max_distance) {
        SectorRange::Clear
    } else {
        SectorRange::Obstacle(f64::from(m.current_distance.max(m.min_distance)) * 0.01)
    };
    let centre = yaw_true_rad.to_degrees() + body_deg;
    let step_deg = 360.0 / SECTORS as f64;
    let ranges = (0..SECTORS)
        .map(|i| {
            if diff_deg(i as f64 * step_deg, centre).abs() <= wedge_deg / 2.0 {
                value
            } else {
                SectorRange::Unknown
            }
        })
        .collect();
    Ok(Some(ObstacleReading {
        time_s,
        position_ned,
        velocity_ned_m_s: [0.0; 3],
        first_bearing_rad: -convergence_rad,
        increment_rad: step_deg.to_radians(),
        min_range_m: f64::from(m.min_distance) * 0.01,
        max_range_m: f64::from(m.max_distance) * 0.01,
        ranges,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sweep sent as ArduPilot's eight wedges and read back: each obstacle of the sweep lies
    /// in the arc of the wedge that holds it, at a distance no nearer than the wedge reads, and
    /// that distance is the nearest in the wedge (independently: the sweep's own sectors by
    /// true bearing); an empty wedge reads clear; up and down are not horizontal.
    #[test]
    fn distance_sensor_wedges_carry_the_nearest_obstacle_of_each_sector() {
        let mut rng = skyplan_testkit::XorShift::new(5);
        for _ in 0..200 {
            let mut sweep = vec![SectorRange::Clear; SECTORS];
            for _ in 0..6 {
                let i = (rng.unit() * SECTORS as f64) as usize;
                sweep[i] = SectorRange::Obstacle(0.5 + 29.0 * rng.unit());
            }
            let yaw = (rng.unit() - 0.5) * 7.0;
            let conv = (rng.unit() - 0.5) * 0.02;
            let sensor = RangeSensor::default();
            let messages = distance_sensors(&sweep, &sensor, yaw, 0);
            assert_eq!(messages.len(), 8);
            for m in &messages {
                let MavMessage::DISTANCE_SENSOR(d) = m else {
                    panic!("not a DISTANCE_SENSOR");
                };
                let r = reading_from_distance_sensor(d, 0.0, [0.0; 3], yaw, conv)
                    .unwrap()
                    .unwrap();
                let centre = yaw.to_degrees() + orientation_yaw_deg(d.orientation).unwrap();
                let in_wedge = |i: usize| diff_deg(5.0 * i as f64, centre).abs() <= 22.5;
                let nearest = (0..SECTORS)
                    .filter(|&i| in_wedge(i))
                    .filter_map(|i| match sweep[i] {
                        SectorRange::Obstacle(x) => Some(x),
                        _ => None,
                    })
                    .fold(f64::INFINITY, f64::min);
                for i in 0..SECTORS {
                    let got = r.ranges[i];
                    if !in_wedge(i) {
                        assert_eq!(got, SectorRange::Unknown, "sector {i}");
                    } else if nearest.is_finite() {
                        // To the centimetre the message carries.
                        let SectorRange::Obstacle(x) = got else {
                            panic!("sector {i}: {got:?}, expected {nearest} m");
                        };
                        assert!((x - nearest).abs() <= 0.005 + 1e-9, "{x} vs {nearest}");
                    } else {
                        assert_eq!(got, SectorRange::Clear);
                    }
                }
                assert!((r.first_bearing_rad + conv).abs() < 1e-12);
            }
        }
        let up = DISTANCE_SENSOR_DATA {
            min_distance: 20,
            max_distance: 3000,
            orientation: MavSensorOrientation::MAV_SENSOR_ROTATION_PITCH_90,
            ..Default::default()
        };
        assert_eq!(
            reading_from_distance_sensor(&up, 0.0, [0.0; 3], 0.0, 0.0),
            Ok(None)
        );
        let bad = DISTANCE_SENSOR_DATA {
            max_distance: 0,
            ..up
        };
        let bad = DISTANCE_SENSOR_DATA {
            orientation: MavSensorOrientation::MAV_SENSOR_ROTATION_NONE,
            ..bad
        };
        assert!(reading_from_distance_sensor(&bad, 0.0, [0.0; 3], 0.0, 0.0).is_err());
    }

    fn message(frame: MavFrame) -> OBSTACLE_DISTANCE_DATA {
        let mut distances = [3001u16; 72];
        distances[9] = 1234; // 45° from sector 0
        OBSTACLE_DISTANCE_DATA {
            distances,
            min_distance: 20,
            max_distance: 3000,
            increment: 5,
            frame,
            ..Default::default()
        }
    }

    fn hit(r: &ObstacleReading) -> [f64; 2] {
        let hits: Vec<_> = r.hits_ne().collect();
        assert_eq!(hits.len(), 1);
        hits[0]
    }

    #[test]
    #[allow(deprecated)]
    fn every_earth_frame_is_north_aligned_and_body_frames_turn_with_the_yaw() {
        let yaw = 30f64.to_radians();
        let (s, c) = (45f64.to_radians().sin(), 45f64.to_radians().cos());
        for frame in [
            MavFrame::MAV_FRAME_GLOBAL,
            MavFrame::MAV_FRAME_LOCAL_NED,
            MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            MavFrame::MAV_FRAME_GLOBAL_INT,
            MavFrame::MAV_FRAME_LOCAL_OFFSET_NED,
        ] {
            let r =
                reading_from_obstacle_distance(&message(frame), 0.0, [1.0, 2.0, -5.0], yaw, 0.0)
                    .unwrap();
            let [n, e] = hit(&r);
            assert!((n - (1.0 + 12.34 * c)).abs() < 1e-9 && (e - (2.0 + 12.34 * s)).abs() < 1e-9);
        }
        for frame in [
            MavFrame::MAV_FRAME_BODY_FRD,
            MavFrame::MAV_FRAME_BODY_NED,
            MavFrame::MAV_FRAME_BODY_OFFSET_NED,
        ] {
            let r =
                reading_from_obstacle_distance(&message(frame), 0.0, [0.0; 3], yaw, 0.0).unwrap();
            let [n, e] = hit(&r);
            let b = 75f64.to_radians(); // 30° yaw + 45°
            assert!((n - 12.34 * b.cos()).abs() < 1e-9 && (e - 12.34 * b.sin()).abs() < 1e-9);
        }
        let bad = reading_from_obstacle_distance(
            &message(MavFrame::MAV_FRAME_LOCAL_ENU),
            0.0,
            [0.0; 3],
            0.0,
            0.0,
        );
        assert!(matches!(bad, Err(ObstacleError::Frame(_))));
    }

    /// How many of the reading's sectors are `range`.
    fn sectors(r: &ObstacleReading, range: SectorRange) -> usize {
        r.ranges.iter().filter(|x| **x == range).count()
    }

    #[test]
    fn increment_f_wins_offset_and_convergence_turn_the_sectors() {
        let mut m = message(MavFrame::MAV_FRAME_LOCAL_NED);
        m.increment = 10; // ignored: increment_f is set
        m.increment_f = -2.5; // counter-clockwise
        m.angle_offset = 10.0;
        let conv = 0.37f64.to_radians();
        let r = reading_from_obstacle_distance(&m, 0.0, [0.0; 3], 0.0, conv).unwrap();
        let b = (10.0 - 9.0 * 2.5f64).to_radians() - conv;
        let [n, e] = hit(&r);
        assert!((n - 12.34 * b.cos()).abs() < 1e-9 && (e - 12.34 * b.sin()).abs() < 1e-9);
        // 2.5° sectors: all 72 are used (180°); 10° sectors: only 36.
        assert_eq!(sectors(&r, SectorRange::Clear), 71);
        m.increment_f = 0.0;
        let r = reading_from_obstacle_distance(&m, 0.0, [0.0; 3], 0.0, 0.0).unwrap();
        assert_eq!(sectors(&r, SectorRange::Unknown), 36);
        m.increment = 0;
        assert_eq!(
            reading_from_obstacle_distance(&m, 0.0, [0.0; 3], 0.0, 0.0),
            Err(ObstacleError::NoIncrement)
        );
    }

    #[test]
    fn unknown_clear_and_near_values_as_common_xml_defines_them() {
        let mut m = message(MavFrame::MAV_FRAME_LOCAL_NED);
        m.distances[0] = u16::MAX;
        m.distances[1] = 3000; // exactly max: an obstacle at the limit
        m.distances[2] = 3001; // max + 1: nothing
        m.distances[3] = 0; // touching
        let r = reading_from_obstacle_distance(&m, 0.0, [0.0; 3], 0.0, 0.0).unwrap();
        assert_eq!(r.ranges[0], SectorRange::Unknown);
        assert_eq!(r.ranges[1], SectorRange::Obstacle(30.0));
        assert_eq!(r.ranges[2], SectorRange::Clear);
        assert_eq!(r.ranges[3], SectorRange::Obstacle(0.0));
        assert_eq!((r.min_range_m, r.max_range_m), (0.2, 30.0));
        m.max_distance = 10;
        assert!(reading_from_obstacle_distance(&m, 0.0, [0.0; 3], 0.0, 0.0).is_err());
    }

    #[test]
    fn encode_then_decode_gives_the_sweep_back_to_the_centimetre() {
        let sensor = RangeSensor::default();
        let sweep: Vec<SectorRange> = (0..72)
            .map(|i| match i % 3 {
                0 => SectorRange::Obstacle(0.2 + i as f64 * 0.377),
                1 => SectorRange::Clear,
                _ => SectorRange::Unknown,
            })
            .collect();
        let MavMessage::OBSTACLE_DISTANCE(m) = obstacle_distance(&sweep, &sensor, 5) else {
            unreachable!()
        };
        let r = reading_from_obstacle_distance(&m, 0.0, [0.0; 3], 1.0, 0.0).unwrap();
        assert_eq!(r.first_bearing_rad, 0.0);
        for (a, b) in sweep.iter().zip(&r.ranges) {
            match (a, b) {
                (SectorRange::Obstacle(x), SectorRange::Obstacle(y)) => {
                    assert!((x - y).abs() <= 0.005 + 1e-12)
                }
                _ => assert_eq!(a, b),
            }
        }
    }
}
