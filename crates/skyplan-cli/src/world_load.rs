//! Map files (by extension) and `--random` into a `skyplan_plan::World`, and the request typed
//! on the command line over the config file's.

use crate::args::RouteArgs;
use crate::config::Config;
use crate::exit::{Result, bad_input};
use crate::files::read_bytes;
use crate::grid_args::GridMapArgs;
use skyplan_plan::{Limits, MapFileError, MapFileOptions, MapFormat, PlanRequest, World};
use std::path::{Path, PathBuf};

const RESOLUTION_NOT_TAKEN: &str = "--resolution: only bare .png/.pgm maps take it (a .yaml map gives its own; other maps are in metres)";

fn format_is(path: Option<&Path>, format: MapFormat) -> bool {
    path.and_then(MapFormat::of_path) == Some(format)
}

/// The world a command runs on: `--random` (drawn with `seed`), the map file by extension, or
/// the bundled city.
pub fn load_world(
    map: Option<&Path>,
    g: &GridMapArgs,
    seed: u64,
    limits: &Limits,
) -> Result<World> {
    let colliders = (map.is_none() || format_is(map, MapFormat::Colliders)) && g.random.is_none();
    if g.resolution.is_some() && !format_is(map, MapFormat::Image) {
        return Err(bad_input(RESOLUTION_NOT_TAKEN));
    }
    if colliders && g.home.is_some() {
        return Err(bad_input(
            "--home: a colliders map carries its own home (line 1); drop --home",
        ));
    }
    let world = if let Some(size) = g.random {
        World::random_within(size.width, size.height, g.density, seed, limits)?
    } else {
        match map {
            None => World::fcnd_city(),
            Some(path) => load_file(path, g, limits)?,
        }
    };
    match g.home {
        Some([lat, lon]) => Ok(world.with_home(lat, lon)?),
        None => Ok(world),
    }
}

fn load_file(path: &Path, g: &GridMapArgs, limits: &Limits) -> Result<World> {
    let name = path.display().to_string();
    let options = MapFileOptions {
        resolution_m: g.resolution,
        unknown_free: g.unknown_free,
        limits: *limits,
    };
    World::load_file(path, &options, read_bytes).map_err(|e| match e {
        MapFileError::UnknownType => bad_input(format!(
            "{name}: unknown map type; expected .csv (colliders), .yaml (map_server), .png/.pgm (with --resolution), .map (MovingAI), .geojson (building footprints) or .osm/.osm.pbf (OpenStreetMap buildings)"
        )),
        MapFileError::NeedsResolution => bad_input(format!(
            "{name}: a bare image needs --resolution M (metres per pixel), or use a map_server .yaml"
        )),
        MapFileError::ResolutionNotTaken => bad_input(RESOLUTION_NOT_TAKEN),
        MapFileError::Read {
            via_yaml: true,
            error,
            ..
        } => bad_input(format!("{name}: field image: {:#}", error.error)),
        MapFileError::Read { error, .. } => error,
        MapFileError::Map(failure) => failure.into(),
    })
}

/// Puts the map on the DEM in `path` (GeoTIFF or SRTM `.hgt`), read with its size bounded.
pub fn with_terrain(world: World, path: &Path) -> Result<World> {
    let name = path.display().to_string();
    // Bounded before reading: a DEM is at most 100 M samples of up to 8 bytes.
    if let Ok(meta) = std::fs::metadata(path)
        && meta.len() > skyplan_map::terrain::MAX_DEM_BYTES
    {
        return Err(bad_input(format!(
            "{name}: {} bytes is more than a DEM of {} samples can hold; crop it (gdal_translate -projwin)",
            meta.len(),
            skyplan_map::terrain::MAX_DEM_SAMPLES
        )));
    }
    let bytes = crate::files::read_bytes(path)?;
    let dem = skyplan_map::terrain::parse_dem(&name, &bytes)
        .map_err(|e| bad_input(format!("{name}: {e}")))?;
    Ok(world.with_terrain(&name, dem)?)
}

/// The route options resolved: the world, the request (command line over config file), and the
/// config's file options.
pub struct Resolved {
    pub world: World,
    pub limits: Limits,
    pub request: PlanRequest,
    pub config: Config,
}

/// Reads the config (if any) and the map, and merges the request.
pub fn resolve(a: &RouteArgs) -> Result<Resolved> {
    let config = match &a.config {
        Some(path) => Config::load(path)?,
        None => Config::default(),
    };
    let map: Option<PathBuf> = a.map.clone().or(config.path(&config.text.map));
    let limits = a.memory.limits();
    let mut request = a.request.clone().or(config.text.request.clone());
    if let Some(path) = a.no_fly.clone().or(config.path(&config.text.no_fly)) {
        let text = crate::files::read_text(&path)?;
        // Checked here so that the error names the file.
        skyplan_map::nofly::parse_no_fly(&text)
            .map_err(|e| bad_input(format!("{}: {e}", path.display())))?;
        request.no_fly = Some(text);
    }
    let mut world = load_world(map.as_deref(), &a.grid, request.seed_or_default(), &limits)?;
    if let Some(path) = a.terrain.clone().or(config.path(&config.text.terrain)) {
        world = with_terrain(world, &path)?;
    } else if request.alt_agl_m.is_some() {
        return Err(bad_input(
            "--alt-agl-m keeps a height above the ground: give the ground with --terrain FILE (a GeoTIFF or SRTM .hgt DEM)",
        ));
    }
    Ok(Resolved {
        world,
        limits,
        request,
        config,
    })
}
