//! Geodetic frames for skyplan: WGS84 latitude/longitude ⇄ UTM ⇄ local NED about a home.
//!
//! The local frame follows the FCND convention: project the home and the point to UTM, then
//! `north = Δnorthing`, `east = Δeasting`, `down = −Δaltitude`. Unlike FCND's `global_to_local`,
//! a point in a neighbouring UTM zone is projected into the **home's** zone (Transverse Mercator
//! stays accurate well beyond the zone edge), so the local frame never jumps at a zone border.
//! Points more than [`MAX_ZONE_OVERREACH_DEG`] of longitude beyond the home zone's edge, or in
//! the other hemisphere, are refused with [`FrameError`].
//!
//! ```
//! use skyplan_frames::{LocalFrame, Lla, Ned};
//! let frame = LocalFrame::new(Lla { lat_deg: 37.792480, lon_deg: -122.397450, alt_m: 0.0 })?;
//! let ned = frame.ned_from_lla(Lla { lat_deg: 37.793480, lon_deg: -122.397450, alt_m: 10.0 })?;
//! // 0.001° north is 110.95 m; UTM grid north is 0.37° off true north here (meridian convergence).
//! assert!((ned.north_m - 110.9497).abs() < 1e-3 && (ned.east_m + 0.7151).abs() < 1e-3);
//! assert_eq!(ned.down_m, -10.0);
//! let back = frame.lla_from_ned(ned)?;
//! assert!((back.lat_deg - 37.793480).abs() < 1e-9);
//! # Ok::<(), skyplan_frames::FrameError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use serde::{Deserialize, Serialize};

/// A WGS84 geodetic position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Lla {
    /// Latitude, degrees north.
    pub lat_deg: f64,
    /// Longitude, degrees east.
    pub lon_deg: f64,
    /// Altitude, metres (same datum as the home's altitude).
    pub alt_m: f64,
}

/// A position in the local north-east-down frame about a home, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Ned {
    /// Metres north of home.
    pub north_m: f64,
    /// Metres east of home.
    pub east_m: f64,
    /// Metres below home (negative above it).
    pub down_m: f64,
}

/// A UTM position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Utm {
    /// Easting, metres (500 000 at the central meridian).
    pub easting_m: f64,
    /// Northing, metres (10 000 000 added in the southern hemisphere).
    pub northing_m: f64,
    /// Zone number, 1..=60.
    pub zone: u8,
    /// True in the northern hemisphere.
    pub north: bool,
}

/// How far (degrees of longitude) beyond its zone's edge a point may be projected into the home zone.
pub const MAX_ZONE_OVERREACH_DEG: f64 = 3.0;

/// Why a frame conversion was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// A latitude/longitude outside the valid ranges or not finite.
    #[error(
        "invalid position: latitude {lat_deg}° must be within ±84° (UTM) and longitude {lon_deg}° within ±180°"
    )]
    InvalidPosition {
        /// Latitude given, degrees.
        lat_deg: f64,
        /// Longitude given, degrees.
        lon_deg: f64,
    },
    /// The point lies too far from the home's UTM zone to share its local frame.
    #[error(
        "position ({lat_deg:.6}, {lon_deg:.6}) lies in UTM zone {point_zone}{point_hemisphere}, too far from the home's zone {home_zone}{home_hemisphere} to share its local frame (at most {MAX_ZONE_OVERREACH_DEG}° of longitude beyond the zone edge, same hemisphere)"
    )]
    OtherZone {
        /// Latitude given, degrees.
        lat_deg: f64,
        /// Longitude given, degrees.
        lon_deg: f64,
        /// The point's own zone number.
        point_zone: u8,
        /// `N` or `S`.
        point_hemisphere: char,
        /// The home's zone number.
        home_zone: u8,
        /// `N` or `S`.
        home_hemisphere: char,
    },
    /// A local offset that leaves the valid UTM range.
    #[error(
        "local position ({north_m:.1} m N, {east_m:.1} m E) is outside the home's UTM zone range"
    )]
    OutOfRange {
        /// North offset given, metres.
        north_m: f64,
        /// East offset given, metres.
        east_m: f64,
    },
}

fn check_lla(lat_deg: f64, lon_deg: f64) -> Result<(), FrameError> {
    if lat_deg.is_finite() && lon_deg.is_finite() && lat_deg.abs() <= 84.0 && lon_deg.abs() <= 180.0
    {
        Ok(())
    } else {
        Err(FrameError::InvalidPosition { lat_deg, lon_deg })
    }
}

/// Projects a position to UTM in its own zone (standard zones, with the Norway/Svalbard exceptions).
///
/// ```
/// // Reference: Python `utm.from_latlon(37.792480, -122.397450)`.
/// let u = skyplan_frames::utm_from_lla(37.792480, -122.397450)?;
/// assert_eq!((u.zone, u.north), (10, true));
/// assert!((u.easting_m - 553051.2535).abs() < 1e-3);
/// # Ok::<(), skyplan_frames::FrameError>(())
/// ```
pub fn utm_from_lla(lat_deg: f64, lon_deg: f64) -> Result<Utm, FrameError> {
    check_lla(lat_deg, lon_deg)?;
    let zone = utm::lat_lon_to_zone_number(lat_deg, lon_deg);
    Ok(utm_in_zone(lat_deg, lon_deg, zone))
}

/// Projects a position to UTM in a given zone (1..=60), as rasters in a fixed zone need
/// (a GeoTIFF in EPSG:326xx/327xx). The hemisphere is the position's own.
///
/// ```
/// // The same point as in `utm_from_lla`, in its own zone 10 and one zone east.
/// let own = skyplan_frames::utm_from_lla(37.792480, -122.397450)?;
/// let same = skyplan_frames::utm_from_lla_in_zone(37.792480, -122.397450, 10)?;
/// assert_eq!(own, same);
/// let east = skyplan_frames::utm_from_lla_in_zone(37.792480, -122.397450, 11)?;
/// assert!(east.easting_m < 100_000.0 && east.zone == 11); // 5.4° west of its meridian
/// assert!(skyplan_frames::utm_from_lla_in_zone(37.8, -122.4, 61).is_err());
/// # Ok::<(), skyplan_frames::FrameError>(())
/// ```
pub fn utm_from_lla_in_zone(lat_deg: f64, lon_deg: f64, zone: u8) -> Result<Utm, FrameError> {
    check_lla(lat_deg, lon_deg)?;
    if !(1..=60).contains(&zone) {
        return Err(FrameError::InvalidPosition { lat_deg, lon_deg });
    }
    Ok(utm_in_zone(lat_deg, lon_deg, zone))
}

fn utm_in_zone(lat_deg: f64, lon_deg: f64, zone: u8) -> Utm {
    let (northing_m, easting_m, _convergence) = utm::to_utm_wgs84(lat_deg, lon_deg, zone);
    Utm {
        easting_m,
        northing_m,
        zone,
        north: lat_deg >= 0.0,
    }
}

/// Longitude of a zone's central meridian, degrees.
fn central_meridian_deg(zone: u8) -> f64 {
    f64::from(zone) * 6.0 - 183.0
}

/// The local NED frame about a geodetic home.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    home: Lla,
    home_utm: Utm,
}

impl LocalFrame {
    /// Creates the frame; fails if the home is not a valid UTM position.
    pub fn new(home: Lla) -> Result<Self, FrameError> {
        let home_utm = utm_from_lla(home.lat_deg, home.lon_deg)?;
        Ok(Self { home, home_utm })
    }

    /// The home this frame is about.
    pub fn home(&self) -> Lla {
        self.home
    }

    /// The home's UTM position.
    pub fn home_utm(&self) -> Utm {
        self.home_utm
    }

    /// Local NED of a geodetic position (projected into the home's UTM zone).
    pub fn ned_from_lla(&self, lla: Lla) -> Result<Ned, FrameError> {
        check_lla(lla.lat_deg, lla.lon_deg)?;
        let zone = self.home_utm.zone;
        let own_zone = utm::lat_lon_to_zone_number(lla.lat_deg, lla.lon_deg);
        let hemisphere = |north: bool| if north { 'N' } else { 'S' };
        let overreach_deg = (lla.lon_deg - central_meridian_deg(zone)).abs() - 3.0;
        if (lla.lat_deg >= 0.0) != self.home_utm.north || overreach_deg > MAX_ZONE_OVERREACH_DEG {
            return Err(FrameError::OtherZone {
                lat_deg: lla.lat_deg,
                lon_deg: lla.lon_deg,
                point_zone: own_zone,
                point_hemisphere: hemisphere(lla.lat_deg >= 0.0),
                home_zone: zone,
                home_hemisphere: hemisphere(self.home_utm.north),
            });
        }
        let u = utm_in_zone(lla.lat_deg, lla.lon_deg, zone);
        Ok(Ned {
            north_m: u.northing_m - self.home_utm.northing_m,
            east_m: u.easting_m - self.home_utm.easting_m,
            down_m: -(lla.alt_m - self.home.alt_m),
        })
    }

    /// Geodetic position of a local NED point (the inverse of [`LocalFrame::ned_from_lla`]).
    pub fn lla_from_ned(&self, ned: Ned) -> Result<Lla, FrameError> {
        let easting = self.home_utm.easting_m + ned.east_m;
        let northing = self.home_utm.northing_m + ned.north_m;
        // Any letter of the right hemisphere works: the crate only uses it to pick N or S.
        let letter = if self.home_utm.north { 'N' } else { 'M' };
        let out_of_range = FrameError::OutOfRange {
            north_m: ned.north_m,
            east_m: ned.east_m,
        };
        if !(easting.is_finite() && northing.is_finite()) {
            return Err(out_of_range);
        }
        let (mut lat_deg, mut lon_deg) =
            utm::wsg84_utm_to_lat_lon(easting, northing, self.home_utm.zone, letter)
                .map_err(|_| out_of_range)?;
        // The crate's inverse series is off by up to a few millimetres, while its forward
        // projection matches Python `utm` to 0.1 mm. Refine with Newton steps on the forward
        // projection, using the local metres-per-degree as the Jacobian (the residual shrinks by
        // ~30× per step; three steps reach the forward projection's own accuracy).
        for _ in 0..3 {
            let u = utm_in_zone(lat_deg, lon_deg, self.home_utm.zone);
            let (d_north_m, d_east_m) = (northing - u.northing_m, easting - u.easting_m);
            let m_per_deg_lat = 111_132.954 * 0.9996;
            let m_per_deg_lon = m_per_deg_lat * lat_deg.to_radians().cos();
            lat_deg += d_north_m / m_per_deg_lat;
            lon_deg += d_east_m / m_per_deg_lon;
        }
        Ok(Lla {
            lat_deg,
            lon_deg,
            alt_m: self.home.alt_m - ned.down_m,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_far_zones_and_other_hemisphere() {
        let frame = LocalFrame::new(Lla {
            lat_deg: 37.79248,
            lon_deg: -122.39745,
            alt_m: 0.0,
        })
        .unwrap();
        let far = frame.ned_from_lla(Lla {
            lat_deg: 37.0,
            lon_deg: -110.0,
            alt_m: 0.0,
        });
        assert!(
            matches!(
                far,
                Err(FrameError::OtherZone {
                    point_zone: 12,
                    home_zone: 10,
                    ..
                })
            ),
            "{far:?}"
        );
        let south = frame.ned_from_lla(Lla {
            lat_deg: -1.0,
            lon_deg: -122.0,
            alt_m: 0.0,
        });
        assert!(matches!(south, Err(FrameError::OtherZone { .. })));
        let bad = frame.ned_from_lla(Lla {
            lat_deg: f64::NAN,
            lon_deg: 0.0,
            alt_m: 0.0,
        });
        assert!(matches!(bad, Err(FrameError::InvalidPosition { .. })));
    }

    proptest::proptest! {
        #[test]
        fn round_trip_is_within_a_millimetre(n in -5000.0..5000.0f64, e in -5000.0..5000.0f64, d in -100.0..0.0f64) {
            let frame = LocalFrame::new(Lla { lat_deg: 37.79248, lon_deg: -122.39745, alt_m: 3.0 }).unwrap();
            let ned = Ned { north_m: n, east_m: e, down_m: d };
            let back = frame.ned_from_lla(frame.lla_from_ned(ned).unwrap()).unwrap();
            proptest::prop_assert!((back.north_m - n).abs() < 1e-3 && (back.east_m - e).abs() < 1e-3);
            proptest::prop_assert!((back.down_m - d).abs() < 1e-9);
        }
    }
}
