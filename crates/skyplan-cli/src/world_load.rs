//! Map files (by extension) and `--random` into a `skyplan_plan::World`, and the CLI's options
//! (over a config file) into a `PlanRequest`.

use crate::args::{Pair, PruneArg, RouteArgs};
use crate::config::Config;
use crate::exit::{Result, bad_input};
use crate::files::read_bytes;
use crate::grid_args::{FieldArg, GridMapArgs};
use skyplan_plan::{
    FieldMode, Limits, MapFileError, MapFileOptions, MapFormat, PlanRequest, PruneMode, World,
};
use std::path::{Path, PathBuf};

const RESOLUTION_NOT_TAKEN: &str = "--resolution: only bare .png/.pgm maps take it (a .yaml map gives its own; other maps are in metres)";

fn format_is(path: Option<&Path>, format: MapFormat) -> bool {
    path.and_then(MapFormat::of_path) == Some(format)
}

/// The world a command runs on: `--random`, the map file by extension, or the bundled city.
pub fn load_world(map: Option<&Path>, g: &GridMapArgs, limits: &Limits) -> Result<World> {
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
        World::random_within(size.width, size.height, g.density, g.seed, limits)?
    } else {
        match map {
            None => World::fcnd_city(),
            Some(path) => load_file(path, g, limits)?,
        }
    };
    match g.home {
        Some(Pair(lat, lon)) => Ok(world.with_home(lat, lon)?),
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
            "{name}: unknown map type; expected .csv (colliders), .yaml (map_server), .png/.pgm (with --resolution) or .map (MovingAI)"
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

/// The request typed on the command line (only what was given).
fn typed_request(a: &RouteArgs) -> PlanRequest {
    let pair = |p: Option<Pair>| p.map(|Pair(x, y)| [x, y]);
    let g = &a.grid;
    let p3 = &a.plan3d;
    PlanRequest {
        planner: a.planner,
        alt_m: a.slice.alt_m,
        safety_m: a.slice.safety_m,
        cell_m: a.slice.cell_m,
        start_ne: pair(a.start_ne),
        start_lla: pair(a.start_lla),
        goal_ne: pair(a.goal_ne),
        goal_lla: pair(a.goal_lla),
        start_alt_m: p3.start_alt_m,
        goal_alt_m: p3.goal_alt_m,
        start_heading_deg: a.start_heading_deg,
        connectivity: a.moves.connectivity,
        corner_cutting: a.moves.corner_cutting.then_some(true),
        prune: a.prune.map(|p| match p {
            PruneArg::Collinear => PruneMode::Collinear,
            PruneArg::None => PruneMode::None,
        }),
        epsilon: a.epsilon,
        shortcut: a.no_shortcut.then_some(false),
        time_limit_ms: p3.time_limit_ms,
        seed: Some(g.seed),
        min_alt_m: p3.min_alt_m,
        max_alt_m: p3.max_alt_m,
        climb_weight: p3.climb_weight,
        voxel_m: p3.voxel_m,
        layer_m: p3.layer_m,
        field: g.field.map(|f| match f {
            FieldArg::Length => FieldMode::Length,
            FieldArg::Steps => FieldMode::Steps,
        }),
        inscribed_radius_m: g.inscribed_radius_m,
        inflation_radius_m: g.inflation_radius_m,
        cost_scaling: g.cost_scaling,
        cost_weight: g.cost_weight,
        geometry: None,
        roadmap: Default::default(),
    }
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
    let world = load_world(map.as_deref(), &a.grid, &limits)?;
    let request = typed_request(a).or(config.text.request.clone());
    Ok(Resolved {
        world,
        limits,
        request,
        config,
    })
}
