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
use skyplan_plan::ConfigText;
use std::path::{Path, PathBuf};

/// A config file's keys and where it is: its file keys are relative to its directory.
#[derive(Debug, Default)]
pub struct Config {
    pub text: ConfigText,
    dir: PathBuf,
}

impl Config {
    /// Reads a config file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::files::read_text(path)?;
        let text = skyplan_plan::parse_config_toml(&text)
            .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
        let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
        Ok(Config { text, dir })
    }

    /// A file key (`map`, `out`, `plot`) as a path: a relative one from the config's directory.
    pub fn path(&self, key: &Option<String>) -> Option<PathBuf> {
        key.as_ref().map(|p| self.dir.join(p))
    }
}
