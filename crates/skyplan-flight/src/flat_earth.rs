//! ArduPilot's local frame: a true-north flat-earth NED frame about the EKF origin.
//!
//! ArduPilot (and PX4's `map_projection` for short distances) turn latitude and longitude into
//! metres north and east of the EKF origin with a spherical flat-earth approximation:
//! `north = Δlat · LATLON_TO_M`, `east = Δlon · LATLON_TO_M · cos(mean latitude)` with
//! `LATLON_TO_M = 1e-7° in metres on a sphere of radius 6 378 100 m` (`Location::get_distance_NE`),
//! and back with `Location::offset` (the longitude scale at the mid latitude). Its north is true
//! north, not the UTM grid north of skyplan's map frame, and its metres are not exact metres:
//! this is the frame LOCAL_POSITION_NED and SET_POSITION_TARGET_LOCAL_NED use, and the one the
//! simulator flies in. skyplan talks to vehicles in latitude and longitude instead, so the two
//! frames never mix.
//!
//! ```
//! use skyplan_flight::flat_earth::FlatEarth;
//! let origin = FlatEarth::new(37.792480, -122.397450);
//! let (lat_deg, lon_deg) = origin.lat_lon_from_ne(100.0, -50.0);
//! let [n, e] = origin.ne_from_lat_lon(lat_deg, lon_deg);
//! assert!((n - 100.0).abs() < 1e-6 && (e + 50.0).abs() < 1e-6);
//! ```

/// Metres per 1e-7 degree on ArduPilot's sphere (`LATLON_TO_M`, radius 6 378 100 m).
pub const LATLON_TO_M: f64 = 0.011131884502145034;

/// ArduPilot's `Location::longitude_scale`: cos(latitude), at least 0.01.
pub fn longitude_scale(lat_deg: f64) -> f64 {
    lat_deg.to_radians().cos().max(0.01)
}

/// Longitude difference `a − b` in degrees, wrapped to (−180, 180].
fn diff_longitude_deg(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    if d > 180.0 { d - 360.0 } else { d }
}

/// A flat-earth frame about an origin (ArduPilot's EKF origin).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlatEarth {
    origin_lat_deg: f64,
    origin_lon_deg: f64,
}

impl FlatEarth {
    /// The frame about this origin.
    pub fn new(origin_lat_deg: f64, origin_lon_deg: f64) -> Self {
        Self {
            origin_lat_deg,
            origin_lon_deg,
        }
    }

    /// The origin, degrees latitude and longitude.
    pub fn origin_deg(&self) -> (f64, f64) {
        (self.origin_lat_deg, self.origin_lon_deg)
    }

    /// Metres north and east of the origin (`Location::get_distance_NE` from the origin).
    pub fn ne_from_lat_lon(&self, lat_deg: f64, lon_deg: f64) -> [f64; 2] {
        let scale = longitude_scale((lat_deg + self.origin_lat_deg) / 2.0);
        [
            (lat_deg - self.origin_lat_deg) * 1e7 * LATLON_TO_M,
            diff_longitude_deg(lon_deg, self.origin_lon_deg) * 1e7 * LATLON_TO_M * scale,
        ]
    }

    /// Latitude and longitude, degrees, of a point north and east of the origin
    /// (`Location::offset` of the origin).
    pub fn lat_lon_from_ne(&self, north_m: f64, east_m: f64) -> (f64, f64) {
        let dlat_deg = north_m / LATLON_TO_M * 1e-7;
        let scale = longitude_scale(self.origin_lat_deg + dlat_deg / 2.0);
        let dlon_deg = east_m / LATLON_TO_M * 1e-7 / scale;
        let lon = self.origin_lon_deg + dlon_deg;
        let lon = if lon > 180.0 {
            lon - 360.0
        } else if lon < -180.0 {
            lon + 360.0
        } else {
            lon
        };
        (self.origin_lat_deg + dlat_deg, lon)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ArduPilot's integer arithmetic (`Location::offset_latlng` with `int32_t` 1e-7 degrees,
    /// then `get_distance_NE`), transcribed literally from `libraries/AP_Common/Location.cpp`
    /// (ArduPilot 4.7.0-dev, commit 90700977c5): the reference the f64 frame is checked against.
    fn ardupilot_offset(lat: i32, lng: i32, ofs_north: f64, ofs_east: f64) -> (i32, i32) {
        const LATLON_TO_M_INV: f64 = 89.83204953368922;
        let scale = |lat: i32| (f64::from(lat) * 1.0e-7 * std::f64::consts::PI / 180.0).cos();
        let dlat = (ofs_north * LATLON_TO_M_INV) as i32;
        let dlng = ((ofs_east * LATLON_TO_M_INV) / scale(lat + dlat / 2)) as i64;
        (lat + dlat, (dlng + i64::from(lng)) as i32)
    }

    fn ardupilot_distance_ne(lat1: i32, lng1: i32, lat2: i32, lng2: i32) -> [f64; 2] {
        let mid = ((i64::from(lat1) + i64::from(lat2)) / 2) as i32;
        let scale = (f64::from(mid) * 1.0e-7 * std::f64::consts::PI / 180.0).cos();
        [
            f64::from(lat2 - lat1) * LATLON_TO_M,
            f64::from(lng2 - lng1) * LATLON_TO_M * scale,
        ]
    }

    #[test]
    fn matches_ardupilot_location_offset_and_get_distance_ne() {
        // The FCND home, and a far one near the pole of the scale.
        for (lat0, lon0) in [
            (37.792480, -122.397450),
            (-33.8688, 151.2093),
            (64.1, -21.9),
        ] {
            let frame = FlatEarth::new(lat0, lon0);
            let (lat0_e7, lon0_e7) = ((lat0 * 1e7).round() as i32, (lon0 * 1e7).round() as i32);
            for (n, e) in [
                (0.0, 0.0),
                (1000.0, 0.0),
                (0.0, 1000.0),
                (-730.5, 412.25),
                (5000.0, -8000.0),
            ] {
                let (lat, lon) = frame.lat_lon_from_ne(n, e);
                let (lat_ap, lon_ap) = ardupilot_offset(lat0_e7, lon0_e7, n, e);
                // ArduPilot truncates to 1e-7° (≤ 1.1 cm); the rest agrees.
                assert!((lat * 1e7 - f64::from(lat_ap)).abs() <= 1.0, "{n} {e}");
                assert!((lon * 1e7 - f64::from(lon_ap)).abs() <= 1.0, "{n} {e}");
                let [n_ap, e_ap] = ardupilot_distance_ne(lat0_e7, lon0_e7, lat_ap, lon_ap);
                let [n2, e2] =
                    frame.ne_from_lat_lon(f64::from(lat_ap) * 1e-7, f64::from(lon_ap) * 1e-7);
                assert!(
                    (n2 - n_ap).abs() < 1e-6 && (e2 - e_ap).abs() < 1e-3,
                    "{n} {e}"
                );
                // And the round trip, as the vehicle does it, is within ArduPilot's 1e-7°.
                assert!((n2 - n).abs() < 0.012 && (e2 - e).abs() < 0.012, "{n} {e}");
            }
        }
    }

    #[test]
    fn a_kilometre_north_is_ardupilots_kilometre_not_the_ellipsoids() {
        // 1 km north of the FCND home: ArduPilot's sphere (a = 6 378 100 m) puts it at
        // Δlat = 1000 / LATLON_TO_M · 1e-7 = 0.0089832°, while the WGS84 meridian arc at 37.8°
        // gives 0.0090096° (M = 6 359 405 m): the flat-earth frame is 0.29 % short in latitude.
        let frame = FlatEarth::new(37.792480, -122.397450);
        let (lat, _) = frame.lat_lon_from_ne(1000.0, 0.0);
        assert!((lat - 37.792480 - 0.0089832050).abs() < 1e-9, "{lat}");
        // Longitude: 1 km east is 0.0089832° / cos(37.79248°) = 0.0113678°.
        let (_, lon) = frame.lat_lon_from_ne(0.0, 1000.0);
        assert!((lon + 122.397450 - 0.0113677576).abs() < 1e-9, "{lon}");
    }

    #[test]
    fn wraps_the_antimeridian() {
        let frame = FlatEarth::new(0.0, 179.9999);
        let (_, lon) = frame.lat_lon_from_ne(0.0, 50.0);
        assert!(lon < -179.9, "{lon}");
        let [_, e] = frame.ne_from_lat_lon(0.0, lon);
        assert!((e - 50.0).abs() < 1e-6, "{e}");
    }
}
