//! What the colliders planners outside the grid pipeline (3D, Voronoi) share: the map, its
//! local frame and the start and goal in local metres, resolved from the command line over the
//! config file over the defaults (the home; the default goal).

use crate::args::{Pair, PlanArgs};
use crate::config::Config;
use crate::exit::{Result, bad_input};
use crate::files::{BUNDLED_COLLIDERS, BUNDLED_NAME, read_text};
use skyplan_frames::{Lla, LocalFrame};
use skyplan_map::colliders::CollidersMap;

pub(crate) struct CollidersQuery {
    pub map_name: String,
    pub map: CollidersMap,
    pub frame: LocalFrame,
    pub cfg: Config,
    pub alt_m: f64,
    pub safety_m: f64,
    pub start_ne: (f64, f64),
    pub goal_ne: (f64, f64),
}

/// A position given as local north,east or as lat,lon, in local metres.
fn ne_of(
    frame: &LocalFrame,
    ne: Option<Pair>,
    lla: Option<Pair>,
    what: &str,
) -> Result<Option<(f64, f64)>> {
    if let Some(p) = ne {
        return Ok(Some((p.0, p.1)));
    }
    let Some(p) = lla else {
        return Ok(None);
    };
    let ned = frame
        .ned_from_lla(Lla {
            lat_deg: p.0,
            lon_deg: p.1,
            alt_m: 0.0,
        })
        .map_err(|e| bad_input(format!("--{what}-lla: {e}")))?;
    Ok(Some((ned.north_m, ned.east_m)))
}

pub(crate) fn resolve(args: &PlanArgs) -> Result<CollidersQuery> {
    let cfg = match &args.config {
        Some(path) => Config::load(path)?,
        None => Config::default(),
    };
    let map_path = args.map.clone().or(cfg.map.clone());
    let (map_name, text) = match &map_path {
        Some(path) => (path.display().to_string(), read_text(path)?),
        None => (BUNDLED_NAME.to_string(), BUNDLED_COLLIDERS.to_string()),
    };
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{map_name}: {e}")))?;
    let frame = LocalFrame::new(Lla {
        lat_deg: map.home.lat_deg,
        lon_deg: map.home.lon_deg,
        alt_m: 0.0,
    })
    .map_err(|e| bad_input(format!("{map_name}: home: {e}")))?;
    let alt_m = args.alt_m.or(cfg.alt_m).unwrap_or(5.0);
    let safety_m = args.safety_m.or(cfg.safety_m).unwrap_or(5.0);
    let pair = |p: Option<[f64; 2]>| p.map(|[a, b]| Pair(a, b));
    let start_ne = match ne_of(&frame, args.start_ne, args.start_lla, "start")? {
        Some(ne) => Some(ne),
        None => ne_of(&frame, pair(cfg.start_ne), pair(cfg.start_lla), "start")?,
    }
    .unwrap_or((0.0, 0.0));
    let goal_ne = match ne_of(&frame, args.goal_ne, args.goal_lla, "goal")? {
        Some(ne) => Some(ne),
        None => ne_of(&frame, pair(cfg.goal_ne), pair(cfg.goal_lla), "goal")?,
    }
    .unwrap_or(crate::plan_cmd::DEFAULT_GOAL_NE);
    Ok(CollidersQuery {
        map_name,
        map,
        frame,
        cfg,
        alt_m,
        safety_m,
        start_ne,
        goal_ne,
    })
}
