//! The TOML config file: the same values as the `plan` options (like the FCND config).
//!
//! ```toml
//! map = "data/colliders.csv"   # relative paths are relative to the config file
//! alt_m = 5.0                  # alias: target_altitude
//! safety_m = 5.0               # alias: safety_distance
//! goal_lla = [37.7965, -122.3982]
//! planner = "astar"            # alias: method
//! out = "waypoints.h5"
//! ```

use crate::args::{PlannerArg, PruneArg};
use crate::exit::{Classify, Kind, Result};
use anyhow::Context;
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    pub map: Option<PathBuf>,
    #[serde(alias = "target_altitude")]
    pub alt_m: Option<f64>,
    #[serde(alias = "safety_distance")]
    pub safety_m: Option<f64>,
    pub cell_m: Option<f64>,
    pub start_ne: Option<[f64; 2]>,
    pub start_lla: Option<[f64; 2]>,
    pub goal_ne: Option<[f64; 2]>,
    pub goal_lla: Option<[f64; 2]>,
    pub start_heading_deg: Option<f64>,
    pub connectivity: Option<u8>,
    pub corner_cutting: Option<bool>,
    #[serde(alias = "method")]
    pub planner: Option<PlannerArg>,
    pub prune: Option<PruneArg>,
    pub epsilon: Option<f64>,
    pub shortcut: Option<bool>,
    pub out: Option<PathBuf>,
    pub format: Option<String>,
    pub plot: Option<PathBuf>,
}

impl Config {
    /// Reads a config file; paths inside it become relative to its directory.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::files::read_text(path)?;
        let mut config: Config = toml::from_str(&text)
            .with_context(|| format!("{}: invalid config", path.display()))
            .or_exit(Kind::BadInput)?;
        let base = path.parent().unwrap_or(Path::new(""));
        for p in [&mut config.map, &mut config.out, &mut config.plot]
            .into_iter()
            .flatten()
        {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
        Ok(config)
    }
}
