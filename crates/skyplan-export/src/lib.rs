//! Waypoint file formats for skyplan.
//!
//! Every encoder turns a [`Mission`] into the bytes of one file and does no I/O of its own: the
//! caller (the CLI) decides where and how to write them.
//!
//! | [`Format`] | Encoder | Contents |
//! | --- | --- | --- |
//! | [`Format::Json`] | [`to_json`] | skyplan's own JSON: home, FCND rows, lat/lon per waypoint, metadata |
//! | [`Format::Csv`] | [`to_csv`] | `north_m,east_m,alt_m,heading_rad,lat_deg,lon_deg`, one row per waypoint |
//! | [`Format::Hdf5`] | [`to_hdf5`] | dataset `data`, float64 `[n, 4]` of FCND rows, as FCND's `h5py` code reads it |
//! | [`Format::GeoJson`] | [`to_geojson`] | RFC 7946 FeatureCollection: the route and its start and goal |
//! | [`Format::QgcPlan`] | [`to_qgc_plan`] | QGroundControl `.plan`: takeoff, waypoints, land |
//!
//! Every encoder rejects a mission holding a non-finite number ([`ExportError::NonFinite`]).
//!
//! ```
//! use skyplan_export::{encode, Format};
//! # use skyplan_frames::Lla;
//! # use skyplan_mission::{Mission, Waypoint};
//! # let home = Lla { lat_deg: 37.79248, lon_deg: -122.39745, alt_m: 0.0 };
//! # let wp = |north_m, lat_deg| Waypoint { north_m, east_m: 0.0, alt_m: 5.0, heading_rad: 0.0, lat_deg, lon_deg: -122.39745 };
//! # let mission = Mission { home, waypoints: vec![wp(0.0, 37.79248), wp(10.5, 37.792574)] };
//! let format = Format::from_path("route.csv".as_ref()).expect("known extension");
//! let bytes = encode(format, &mission, &serde_json::Value::Null)?;
//! let text = String::from_utf8(bytes).expect("CSV is UTF-8");
//! let mut lines = text.lines();
//! assert_eq!(lines.next(), Some("north_m,east_m,alt_m,heading_rad,lat_deg,lon_deg"));
//! assert_eq!(lines.next(), Some("0,0,5,0,37.79248,-122.39745"));
//! assert_eq!(lines.next(), Some("10.5,0,5,0,37.792574,-122.39745"));
//! # Ok::<(), skyplan_export::ExportError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod fmt_csv;
mod fmt_geojson;
mod fmt_hdf5;
mod fmt_json;
mod fmt_qgc;
mod fmt_samples;

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use skyplan_mission::Mission;

pub use fmt_csv::{CSV_HEADER, csv_row, to_csv};
pub use fmt_geojson::to_geojson;
pub use fmt_hdf5::{HDF5_DATASET, to_hdf5};
pub use fmt_json::{JSON_COLUMNS, JSON_FORMAT_ID, JSON_FORMAT_VERSION, to_json};
pub use fmt_qgc::{FenceCircle, FencePolygon, GeoFence, QgcPlanOptions, mavlink, to_qgc_plan};
pub use fmt_samples::{SAMPLES_DATASET, samples_csv, samples_hdf5};

/// A waypoint file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// skyplan's JSON document ([`to_json`]), extension `.json`.
    Json,
    /// Comma-separated values ([`to_csv`]), extension `.csv`.
    Csv,
    /// HDF5 file with an FCND `data` dataset ([`to_hdf5`]), extension `.h5` or `.hdf5`.
    Hdf5,
    /// GeoJSON FeatureCollection ([`to_geojson`]), extension `.geojson`.
    GeoJson,
    /// QGroundControl plan ([`to_qgc_plan`]), extension `.plan`.
    QgcPlan,
}

impl Format {
    /// Every format, in a stable order.
    pub const ALL: [Format; 5] = [
        Format::Json,
        Format::Csv,
        Format::Hdf5,
        Format::GeoJson,
        Format::QgcPlan,
    ];

    /// The format a file name's extension names (case-insensitive): `.json`, `.csv`, `.h5`,
    /// `.hdf5`, `.geojson` or `.plan`.
    ///
    /// ```
    /// use skyplan_export::Format;
    /// assert_eq!(Format::from_path("out/route.H5".as_ref()), Some(Format::Hdf5));
    /// assert_eq!(Format::from_path("mission.plan".as_ref()), Some(Format::QgcPlan));
    /// assert_eq!(Format::from_path("route.txt".as_ref()), None);
    /// ```
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "json" => Some(Format::Json),
            "csv" => Some(Format::Csv),
            "h5" | "hdf5" => Some(Format::Hdf5),
            "geojson" => Some(Format::GeoJson),
            "plan" => Some(Format::QgcPlan),
            _ => None,
        }
    }

    /// The format a `--format` value names (case-insensitive): `json`, `csv`, `hdf5` or `h5`,
    /// `geojson`, `plan` or `qgc`.
    ///
    /// ```
    /// use skyplan_export::Format;
    /// assert_eq!(Format::from_name("qgc"), Some(Format::QgcPlan));
    /// assert_eq!(Format::from_name("HDF5"), Some(Format::Hdf5));
    /// assert_eq!(Format::from_name("kml"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Format> {
        match name.to_ascii_lowercase().as_str() {
            "json" => Some(Format::Json),
            "csv" => Some(Format::Csv),
            "hdf5" | "h5" => Some(Format::Hdf5),
            "geojson" => Some(Format::GeoJson),
            "plan" | "qgc" => Some(Format::QgcPlan),
            _ => None,
        }
    }

    /// The canonical file extension, without the dot (`json`, `csv`, `h5`, `geojson`, `plan`).
    pub fn extension(self) -> &'static str {
        match self {
            Format::Json => "json",
            Format::Csv => "csv",
            Format::Hdf5 => "h5",
            Format::GeoJson => "geojson",
            Format::QgcPlan => "plan",
        }
    }

    /// The canonical name, as accepted by [`Format::from_name`] (`json`, `csv`, `hdf5`,
    /// `geojson`, `plan`).
    pub fn name(self) -> &'static str {
        match self {
            Format::Json => "json",
            Format::Csv => "csv",
            Format::Hdf5 => "hdf5",
            Format::GeoJson => "geojson",
            Format::QgcPlan => "plan",
        }
    }

    /// Whether the format is text (UTF-8); only HDF5 is binary.
    pub fn is_text(self) -> bool {
        !matches!(self, Format::Hdf5)
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Format {
    type Err = ExportError;

    /// Parses a name as [`Format::from_name`] does.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Format::from_name(s).ok_or_else(|| ExportError::UnknownFormat(s.to_owned()))
    }
}

/// Why a mission could not be exported.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// A `--format` name that names no format.
    #[error("unknown export format {0:?} (expected one of: json, csv, hdf5, geojson, plan)")]
    UnknownFormat(String),
    /// The format cannot represent a mission this short.
    #[error("{format} export needs at least {needed} waypoint(s), but the mission has {got}")]
    TooFewWaypoints {
        /// The format being written.
        format: Format,
        /// The fewest waypoints the format accepts.
        needed: usize,
        /// The mission's waypoint count.
        got: usize,
    },
    /// A coordinate, altitude or heading is NaN or infinite.
    #[error("{what} is not finite ({value})")]
    NonFinite {
        /// Which value, e.g. `waypoint 3 heading_rad` or `home alt_m`.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// An export option is out of range.
    #[error("invalid option {name} = {value}: {reason}")]
    InvalidOption {
        /// The option's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the option must be.
        reason: &'static str,
    },
    /// JSON serialization failed.
    #[error("JSON encoding failed: {0}")]
    Json(#[from] serde_json::Error),
    /// CSV serialization failed.
    #[error("CSV encoding failed: {0}")]
    Csv(#[from] csv::Error),
    /// HDF5 serialization failed.
    #[error("HDF5 encoding failed: {0}")]
    Hdf5(#[from] hdf5_writer::Error),
}

/// Options for [`encode_with`]; each format reads only its own.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExportOptions {
    /// Options for [`Format::QgcPlan`].
    pub qgc_plan: QgcPlanOptions,
}

/// Encodes a mission in `format` with default [`ExportOptions`].
///
/// `metadata` (any JSON value, e.g. the planner's settings) is embedded by [`Format::Json`] only;
/// the other formats ignore it.
pub fn encode(
    format: Format,
    mission: &Mission,
    metadata: &serde_json::Value,
) -> Result<Vec<u8>, ExportError> {
    encode_with(format, mission, metadata, &ExportOptions::default())
}

/// Encodes a mission in `format`, as [`encode`] does, with explicit options.
pub fn encode_with(
    format: Format,
    mission: &Mission,
    metadata: &serde_json::Value,
    options: &ExportOptions,
) -> Result<Vec<u8>, ExportError> {
    match format {
        Format::Json => to_json(mission, metadata).map(String::into_bytes),
        Format::Csv => to_csv(mission).map(String::into_bytes),
        Format::Hdf5 => to_hdf5(mission),
        Format::GeoJson => to_geojson(mission).map(String::into_bytes),
        Format::QgcPlan => to_qgc_plan(mission, &options.qgc_plan).map(String::into_bytes),
    }
}

/// Fails on the first NaN or infinite number in the mission.
pub(crate) fn check_finite(mission: &Mission) -> Result<(), ExportError> {
    let home = &mission.home;
    for (field, value) in [
        ("lat_deg", home.lat_deg),
        ("lon_deg", home.lon_deg),
        ("alt_m", home.alt_m),
    ] {
        if !value.is_finite() {
            return Err(ExportError::NonFinite {
                what: format!("home {field}"),
                value,
            });
        }
    }
    for (k, w) in mission.waypoints.iter().enumerate() {
        let fields = [
            ("north_m", w.north_m),
            ("east_m", w.east_m),
            ("alt_m", w.alt_m),
            ("heading_rad", w.heading_rad),
            ("lat_deg", w.lat_deg),
            ("lon_deg", w.lon_deg),
        ];
        for (field, value) in fields {
            if !value.is_finite() {
                return Err(ExportError::NonFinite {
                    what: format!("waypoint {k} {field}"),
                    value,
                });
            }
        }
    }
    Ok(())
}

/// Fails unless the mission has at least `needed` waypoints.
pub(crate) fn check_len(
    format: Format,
    mission: &Mission,
    needed: usize,
) -> Result<(), ExportError> {
    let got = mission.waypoints.len();
    if got < needed {
        return Err(ExportError::TooFewWaypoints {
            format,
            needed,
            got,
        });
    }
    Ok(())
}
