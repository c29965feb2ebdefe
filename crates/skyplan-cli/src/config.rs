//! The TOML config file: the plan request's keys (as `skyplan_plan::PlanRequest`, FCND aliases
//! `target_altitude`, `safety_distance`, `method` accepted) plus the CLI's files.
//!
//! ```toml
//! map = "data/colliders.csv"   # relative paths are relative to the config file
//! alt_m = 5.0                  # alias: target_altitude
//! safety_m = 5.0               # alias: safety_distance
//! goal_lla = [37.7965, -122.3982]
//! planner = "astar"            # alias: method
//! out = "waypoints.h5"
//! ```

use crate::exit::{Result, bad_input};
use skyplan_plan::PlanRequest;
use std::path::{Path, PathBuf};

/// A config file: the request and the CLI's own keys.
#[derive(Debug, Default)]
pub struct Config {
    pub request: PlanRequest,
    pub map: Option<PathBuf>,
    pub out: Option<PathBuf>,
    pub format: Option<String>,
    pub plot: Option<PathBuf>,
}

impl Config {
    /// Reads a config file; paths inside it become relative to its directory.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::files::read_text(path)?;
        let name = path.display();
        let mut table: toml::Table =
            toml::from_str(&text).map_err(|e| bad_input(format!("{name}: invalid config: {e}")))?;
        let base = path.parent().unwrap_or(Path::new(""));
        let mut take = |key: &str| -> Result<Option<String>> {
            match table.remove(key) {
                None => Ok(None),
                Some(toml::Value::String(s)) => Ok(Some(s)),
                Some(other) => Err(bad_input(format!(
                    "{name}: {key}: expected a string, found {other}"
                ))),
            }
        };
        let relative = |p: Option<String>| {
            p.map(|p| {
                let p = PathBuf::from(p);
                if p.is_relative() { base.join(p) } else { p }
            })
        };
        let map = relative(take("map")?);
        let out = relative(take("out")?);
        let plot = relative(take("plot")?);
        let format = take("format")?;
        let request: PlanRequest = table
            .try_into()
            .map_err(|e| bad_input(format!("{name}: invalid config: {e}")))?;
        if request.geometry.is_some() {
            return Err(bad_input(format!("{name}: geometry is not a config key")));
        }
        Ok(Config {
            request,
            map,
            out,
            format,
            plot,
        })
    }
}
