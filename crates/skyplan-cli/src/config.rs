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
        let parsed = skyplan_plan::parse_config_toml(&text)
            .map_err(|e| bad_input(format!("{name}: {e}")))?;
        let base = path.parent().unwrap_or(Path::new(""));
        let relative = |p: Option<String>| {
            p.map(|p| {
                let p = PathBuf::from(p);
                if p.is_relative() { base.join(p) } else { p }
            })
        };
        let skyplan_plan::ConfigText {
            request,
            map,
            out,
            format,
            plot,
        } = parsed;
        let (map, out, plot) = (relative(map), relative(out), relative(plot));
        Ok(Config {
            request,
            map,
            out,
            format,
            plot,
        })
    }
}
