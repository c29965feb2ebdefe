//! `GET /api/map`: the map's name, home, bounds and obstacles, and on request the grid at an
//! altitude and margin as run-length rows.

use crate::error::ApiError;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use skyplan_cspace::Grid2;
use skyplan_plan::{PlanRequest, PlanSpec, World};

/// Most cells a grid may have (in `/api/map` and in plans): 16 million, about 4000 × 4000.
pub const MAX_GRID_CELLS: f64 = 16_000_000.0;

/// The query of `GET /api/map`: any of the three asks for the grid (the others default to
/// 5 m, 5 m, 1 m).
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MapQuery {
    pub alt_m: Option<f64>,
    pub safety_m: Option<f64>,
    pub cell_m: Option<f64>,
}

impl MapQuery {
    /// The grid's slice as a plan request (resolved and checked by the planning API, with its
    /// defaults), when the grid is asked for.
    pub fn request(&self) -> Option<PlanRequest> {
        (self.alt_m.is_some() || self.safety_m.is_some() || self.cell_m.is_some()).then(|| {
            PlanRequest {
                alt_m: self.alt_m,
                safety_m: self.safety_m,
                cell_m: self.cell_m,
                ..PlanRequest::default()
            }
        })
    }
}

/// Refuses a cell size that would make a grid larger than [`MAX_GRID_CELLS`] on this world.
pub(crate) fn check_grid_size(world: &World, cell_m: f64, what: &str) -> Result<(), ApiError> {
    if world.fixed_grid().is_some() {
        return Ok(()); // the grid is the map's own, whatever the cell size asked
    }
    if !(cell_m.is_finite() && cell_m > 0.0) {
        return Err(ApiError::bad_request(format!(
            "{what} {cell_m}: expected a number above 0"
        )));
    }
    let b = world.bounds_ne(cell_m);
    let cells =
        ((b.north_max_m - b.north_min_m) / cell_m) * ((b.east_max_m - b.east_min_m) / cell_m);
    if cells > MAX_GRID_CELLS {
        let min_cell_m = ((b.north_max_m - b.north_min_m) * (b.east_max_m - b.east_min_m)
            / MAX_GRID_CELLS)
            .sqrt();
        return Err(ApiError::bad_request(format!(
            "{what} {cell_m}: the grid would have {cells:.0} cells, more than this server's {MAX_GRID_CELLS:.0}; use at least {min_cell_m:.2} m",
        )));
    }
    Ok(())
}

/// The grid at one altitude and margin: rows from the southern edge, each as run lengths of
/// alternating free and blocked cells, starting with free (a row starting blocked begins with 0).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct GridRuns {
    #[serde(flatten)]
    pub info: skyplan_plan::GridInfo,
    pub runs: Vec<Vec<u32>>,
}

impl GridRuns {
    pub fn new(grid: &Grid2, alt_m: f64, safety_m: f64) -> Self {
        let cols = grid.cols() as usize;
        let runs = grid
            .blocked_cells()
            .chunks(cols.max(1))
            .map(|row| {
                let mut out = Vec::new();
                let mut current = false; // runs start with free
                let mut len = 0u32;
                for &blocked in row {
                    if blocked == current {
                        len += 1;
                    } else {
                        out.push(len);
                        current = blocked;
                        len = 1;
                    }
                }
                out.push(len);
                out
            })
            .collect();
        Self {
            info: skyplan_plan::GridInfo::of(grid, alt_m, safety_m),
            runs,
        }
    }
}

/// The map without the grid (computed once), with the server's no-fly zones (GeoJSON text).
pub(crate) fn map_info(world: &World, no_fly: Option<&str>) -> Value {
    let home = world.frame().map(|f| {
        let h = f.home();
        json!({ "lat_deg": h.lat_deg, "lon_deg": h.lon_deg })
    });
    let bounds = world.bounds_ne(PlanSpec::default().cell_m);
    let obstacles: Vec<[f64; 6]> = world
        .colliders()
        .map(|m| {
            m.boxes
                .iter()
                .map(|b| {
                    [
                        b.north_m,
                        b.east_m,
                        b.half_north_m,
                        b.half_east_m,
                        b.bottom_m(),
                        b.top_m(),
                    ]
                })
                .collect()
        })
        .unwrap_or_default();
    // Footprint maps: each building's rings (outer first, then holes) and its band.
    let footprints: Vec<Value> = world
        .footprints()
        .map(|m| {
            m.footprints
                .iter()
                .map(|f| json!({ "rings": f.rings, "bottom_m": f.min_height_m, "top_m": f.height_m }))
                .collect()
        })
        .unwrap_or_default();
    let max_top_m = obstacles
        .iter()
        .map(|o| o[5])
        .chain(
            world
                .footprints()
                .into_iter()
                .flat_map(|m| m.footprints.iter().map(|f| f.height_m)),
        )
        .fold(0.0, f64::max);
    let (default_start_ne, default_goal_ne) = world.default_endpoints_ne();
    let terrain = world.terrain().map(|t| terrain_info(t, &bounds));
    json!({
        "name": world.name(),
        "kind": world.kind(),
        "home": home,
        "bounds": bounds,
        "default_start_ne": default_start_ne,
        "default_goal_ne": default_goal_ne,
        "obstacle_fields": ["north_m", "east_m", "half_north_m", "half_east_m", "bottom_m", "top_m"],
        "obstacles": obstacles,
        "max_top_m": max_top_m,
        "footprints": footprints,
        "terrain": terrain,
        "zones": zones_info(world, no_fly),
        "no_fly": no_fly,
    })
}

/// The zones of `no_fly` about the map's home (bands above home; no ceiling is `null`):
/// polygons as rings, circles as centre and radius. Empty without zones or a home, or if the
/// text does not read (the server checks it before serving).
fn zones_info(world: &World, no_fly: Option<&str>) -> Vec<Value> {
    use skyplan_map::nofly::ZoneShape;
    let (Some(text), Some(frame)) = (no_fly, world.frame()) else {
        return Vec::new();
    };
    let home = skyplan_map::colliders::GeodeticHome {
        lat_deg: frame.home().lat_deg,
        lon_deg: frame.home().lon_deg,
    };
    let zones = skyplan_map::nofly::parse_no_fly(text)
        .and_then(|z| z.project(home, world.terrain().map(|t| t.home_ground_amsl_m())))
        .unwrap_or_default();
    let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    zones
        .iter()
        .map(|z| {
            let (polygon, circle) = match &z.shape {
                ZoneShape::Polygon(rings) => (json!(rings), Value::Null),
                ZoneShape::Circle { centre, radius_m } => (
                    Value::Null,
                    json!({ "centre_ne": centre, "radius_m": radius_m }),
                ),
            };
            json!({
                "feature": z.feature,
                "inclusion": z.inclusion,
                "floor_m": finite(z.floor_m),
                "ceiling_m": finite(z.ceiling_m),
                "polygon": polygon,
                "circle": circle,
            })
        })
        .collect()
}

/// The ground under the map (over terrain): contour lines over its bounds, from 200 samples a
/// side, at about a dozen levels on a 1-2-5 step.
fn terrain_info(t: &skyplan_map::terrain::Terrain, b: &skyplan_plan::BoundsNe) -> Value {
    use skyplan_map::contour::{GroundGrid, contour_segments};
    let n = 200;
    let span = (b.north_max_m - b.north_min_m).max(b.east_max_m - b.east_min_m);
    let step_m = (span / (n - 1) as f64).max(1e-3);
    let north_n = (((b.north_max_m - b.north_min_m) / step_m).ceil() as usize + 1).max(2);
    let east_n = (((b.east_max_m - b.east_min_m) / step_m).ceil() as usize + 1).max(2);
    let origin_ne = [b.north_min_m, b.east_min_m];
    let values: Vec<f64> = (0..north_n * east_n)
        .map(|k| {
            let (i, j) = ((k / east_n) as f64, (k % east_n) as f64);
            t.ground_m(origin_ne[0] + i * step_m, origin_ne[1] + j * step_m)
                .unwrap_or(f64::NAN)
        })
        .collect();
    let known = values.iter().copied().filter(|v| v.is_finite());
    let lo = known.clone().fold(f64::INFINITY, f64::min);
    let hi = known.fold(f64::NEG_INFINITY, f64::max);
    let grid = GroundGrid {
        origin_ne,
        step_m,
        north_n,
        east_n,
        values,
    };
    let (step, levels) = skyplan_map::contour::contour_levels(lo, hi, 12.0);
    let interval_m = if levels.is_empty() {
        Value::Null
    } else {
        json!(step)
    };
    let contours: Vec<Value> = levels
        .into_iter()
        .map(|level| {
            let segments: Vec<[[f64; 2]; 2]> = contour_segments(&grid, level)
                .into_iter()
                .map(|s| s.map(|p| p.map(|x| (x * 100.0).round() / 100.0)))
                .collect();
            json!({ "level_m": level, "segments": segments })
        })
        .collect();
    json!({
        "home_ground_amsl_m": t.home_ground_amsl_m(),
        "lowest_m": if lo.is_finite() { json!(lo) } else { Value::Null },
        "highest_m": if hi.is_finite() { json!(hi) } else { Value::Null },
        "interval_m": interval_m,
        "contours": contours,
    })
}
