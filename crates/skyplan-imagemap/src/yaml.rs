//! ROS `map_server` metadata.

use crate::ImageMapError;
use serde::Deserialize;

/// How pixel values become occupancy (ROS `map_server` `mode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MapMode {
    /// Occupied, free or unknown by the two thresholds. The default.
    #[default]
    Trinary,
    /// As trinary, but values between the thresholds scale to 0–100, and transparent pixels are
    /// unknown.
    Scale,
    /// The grey level is the occupancy (0–100), anything above is unknown.
    Raw,
}

/// The metadata of an occupancy image, as in a ROS `map_server` YAML file.
#[derive(Debug, Clone, PartialEq)]
pub struct MapYaml {
    /// Image file name, relative to the YAML file (empty for a bare image).
    pub image: String,
    /// Edge length of a pixel, metres.
    pub resolution: f64,
    /// `[x, y, yaw]` of the lower-left corner of the lower-left pixel, metres and radians
    /// (x = east, y = north). Only yaw 0 is supported.
    pub origin: [f64; 3],
    /// Occupancy probability above which a pixel is occupied.
    pub occupied_thresh: f64,
    /// Occupancy probability below which a pixel is free.
    pub free_thresh: f64,
    /// White is occupied and black free, instead of the reverse.
    pub negate: bool,
    /// How values are interpreted.
    pub mode: MapMode,
}

impl MapYaml {
    /// The metadata of a bare image: this resolution, origin (0, 0), map_server's default
    /// thresholds (0.65 and 0.196), not negated, trinary.
    pub fn bare(resolution: f64) -> Self {
        Self {
            image: String::new(),
            resolution,
            origin: [0.0; 3],
            occupied_thresh: 0.65,
            free_thresh: 0.196,
            negate: false,
            mode: MapMode::Trinary,
        }
    }

    /// Parses map_server YAML text. `image`, `resolution` and `origin` are required; the others
    /// default as in map_server; unknown keys are ignored. Every error names its field.
    ///
    /// ```
    /// use skyplan_imagemap::{MapMode, MapYaml};
    /// let yaml = "image: map.pgm\nresolution: 0.05\norigin: [-10.0, -5.0, 0.0]\n\
    ///             occupied_thresh: 0.65\nfree_thresh: 0.196\nnegate: 0\nmode: scale\n";
    /// let meta = MapYaml::parse(yaml)?;
    /// assert_eq!((meta.image.as_str(), meta.resolution, meta.mode), ("map.pgm", 0.05, MapMode::Scale));
    /// let err = MapYaml::parse("image: m.png\nresolution: -1\norigin: [0, 0, 0]").unwrap_err();
    /// assert!(err.to_string().starts_with("resolution:"));
    /// # Ok::<(), skyplan_imagemap::ImageMapError>(())
    /// ```
    pub fn parse(text: &str) -> Result<Self, ImageMapError> {
        let raw: RawYaml = serde_norway::from_str(text).map_err(|e| ImageMapError::Yaml {
            field: "yaml".into(),
            message: e.to_string(),
        })?;
        let bad = |field: &str, message: String| ImageMapError::Yaml {
            field: field.into(),
            message,
        };
        let missing = |field: &str| bad(field, "missing (a required map_server field)".into());
        let image = raw.image.ok_or_else(|| missing("image"))?;
        if image.trim().is_empty() {
            return Err(bad("image", "expected an image file name".into()));
        }
        let resolution = raw.resolution.ok_or_else(|| missing("resolution"))?;
        let origin = raw.origin.ok_or_else(|| missing("origin"))?;
        let origin: [f64; 3] = match origin[..] {
            [x, y, yaw] => [x, y, yaw],
            [x, y] => [x, y, 0.0],
            _ => {
                return Err(bad(
                    "origin",
                    format!("expected [x, y, yaw], found {} numbers", origin.len()),
                ));
            }
        };
        let negate = match raw.negate {
            None => false,
            Some(Negate::Flag(b)) => b,
            Some(Negate::Int(0)) => false,
            Some(Negate::Int(1)) => true,
            Some(Negate::Int(n)) => {
                return Err(bad("negate", format!("expected 0 or 1, found {n}")));
            }
        };
        let mode = match raw.mode.as_deref().map(str::to_ascii_lowercase).as_deref() {
            None | Some("trinary") => MapMode::Trinary,
            Some("scale") => MapMode::Scale,
            Some("raw") => MapMode::Raw,
            Some(other) => {
                return Err(bad(
                    "mode",
                    format!("expected trinary, scale or raw, found {other:?}"),
                ));
            }
        };
        let meta = Self {
            image,
            resolution,
            origin,
            occupied_thresh: raw.occupied_thresh.unwrap_or(0.65),
            free_thresh: raw.free_thresh.unwrap_or(0.196),
            negate,
            mode,
        };
        meta.validate()?;
        Ok(meta)
    }

    /// Checks the ranges: resolution > 0, finite origin with yaw 0, thresholds in [0, 1] with
    /// `free_thresh ≤ occupied_thresh`.
    pub fn validate(&self) -> Result<(), ImageMapError> {
        let bad = |field: &str, message: String| {
            Err(ImageMapError::Yaml {
                field: field.into(),
                message,
            })
        };
        if !(self.resolution.is_finite() && self.resolution > 0.0) {
            return bad(
                "resolution",
                format!("expected metres per pixel > 0, found {}", self.resolution),
            );
        }
        if !self.origin.iter().all(|v| v.is_finite()) {
            return bad(
                "origin",
                format!("expected finite numbers, found {:?}", self.origin),
            );
        }
        if self.origin[2] != 0.0 {
            return bad(
                "origin",
                format!(
                    "yaw {} rad: only maps aligned with the axes (yaw 0) are supported",
                    self.origin[2]
                ),
            );
        }
        for (field, v) in [
            ("occupied_thresh", self.occupied_thresh),
            ("free_thresh", self.free_thresh),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(
                    field,
                    format!("expected a probability in [0, 1], found {v}"),
                );
            }
        }
        if self.free_thresh > self.occupied_thresh {
            return bad(
                "free_thresh",
                format!(
                    "{} is above occupied_thresh {}",
                    self.free_thresh, self.occupied_thresh
                ),
            );
        }
        Ok(())
    }
}

#[derive(Debug, Deserialize)]
struct RawYaml {
    image: Option<String>,
    resolution: Option<f64>,
    origin: Option<Vec<f64>>,
    occupied_thresh: Option<f64>,
    free_thresh: Option<f64>,
    negate: Option<Negate>,
    mode: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Negate {
    Flag(bool),
    Int(i64),
}
