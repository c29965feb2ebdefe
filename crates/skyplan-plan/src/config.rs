//! The TOML plan config as text: the request's keys (FCND aliases `target_altitude`,
//! `safety_distance`, `method` accepted) plus the front end's file keys, kept as given (the
//! caller resolves paths and reads files).

use crate::PlanRequest;

/// A config file's contents.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct ConfigText {
    /// The plan request's keys.
    pub request: PlanRequest,
    /// `map`: the map file, as written.
    pub map: Option<String>,
    /// `out`: the waypoints file, as written.
    pub out: Option<String>,
    /// `format`: the waypoints format, as written.
    pub format: Option<String>,
    /// `plot`: the picture file, as written.
    pub plot: Option<String>,
    /// `no_fly`: the no-fly zone file (GeoJSON or QGroundControl `.plan`), relative to the
    /// config file (the CLI reads it into [`PlanRequest::no_fly`]).
    pub no_fly: Option<String>,
    /// `terrain`: the DEM file (GeoTIFF or SRTM `.hgt`), relative to the config file (the CLI
    /// puts the map on it, [`crate::World::with_terrain`]).
    pub terrain: Option<String>,
}

/// Why a config text was refused (the caller prefixes the file's name).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// Not TOML, or a key of the request is unknown or has the wrong type.
    #[error("invalid config: {0}")]
    Invalid(String),
    /// A file key holds something other than a string.
    #[error("{key}: expected a string, found {found}")]
    NotAString {
        /// The key.
        key: &'static str,
        /// What it held, as TOML.
        found: String,
    },
    /// `geometry` is an API option, not a config key.
    #[error("geometry is not a config key")]
    Geometry,
}

/// Parses a config's text (no I/O).
pub fn parse_config_toml(text: &str) -> Result<ConfigText, ConfigError> {
    let mut table: toml::Table =
        toml::from_str(text).map_err(|e| ConfigError::Invalid(e.to_string()))?;
    let mut take = |key: &'static str| match table.remove(key) {
        None => Ok(None),
        Some(toml::Value::String(s)) => Ok(Some(s)),
        Some(other) => Err(ConfigError::NotAString {
            key,
            found: other.to_string(),
        }),
    };
    let map = take("map")?;
    let out = take("out")?;
    let plot = take("plot")?;
    let format = take("format")?;
    let no_fly = take("no_fly")?;
    let terrain = take("terrain")?;
    let request: PlanRequest = table
        .try_into()
        .map_err(|e: toml::de::Error| ConfigError::Invalid(e.to_string()))?;
    if request.geometry.is_some() {
        return Err(ConfigError::Geometry);
    }
    Ok(ConfigText {
        request,
        map,
        out,
        format,
        plot,
        no_fly,
        terrain,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PlannerId;

    #[test]
    fn keys_aliases_and_files() {
        let c = parse_config_toml(
            "map = \"m.csv\"\ntarget_altitude = 7.5\nmethod = \"astar\"\nplot = \"p.png\"\n",
        )
        .unwrap();
        assert_eq!(c.map.as_deref(), Some("m.csv"));
        assert_eq!(c.plot.as_deref(), Some("p.png"));
        assert_eq!(c.out, None);
        assert_eq!(c.request.alt_m, Some(7.5));
        assert_eq!(c.request.planner, Some(PlannerId::Astar));
    }

    #[test]
    fn refusals_name_the_key() {
        let e = parse_config_toml("out = 3\n").unwrap_err();
        assert_eq!(e.to_string(), "out: expected a string, found 3");
        let e = parse_config_toml("safty_m = 3\n").unwrap_err().to_string();
        assert!(e.contains("safty_m"), "{e}");
        let e = parse_config_toml("geometry = true\n").unwrap_err();
        assert_eq!(e, ConfigError::Geometry);
        let e = parse_config_toml("alt_m = \n").unwrap_err().to_string();
        assert!(e.starts_with("invalid config: "), "{e}");
    }
}
