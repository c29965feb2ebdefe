//! `--plot`: one picture for any plan — the 2D map with the route (and a roadmap), the 3D top
//! view and side profile, or a heat map of a navigation function's field.

use crate::exit::{Classify, Kind, Result, bad_input};
use skyplan_map::nofly::Zone;
use skyplan_plan::{Plan, PlannerId, World};
use std::path::Path;

pub use skyplan_plot::plan_picture::PictureKind;

/// The picture kind for a path and a planner.
pub fn kind_for(path: &Path, planner: PlannerId) -> Result<PictureKind> {
    PictureKind::for_path(path, planner)
        .map_err(|why| bad_input(format!("--plot {}: {why}", path.display())))
}

/// The request's no-fly zones in the map's frame, to draw (none without zones or a geodetic
/// home; the plan has already refused zones it cannot place).
pub fn zones_of(world: &World, request: &skyplan_plan::PlanRequest) -> Vec<Zone> {
    let (Some(text), Some(frame)) = (request.no_fly.as_deref(), world.frame()) else {
        return Vec::new();
    };
    let home = skyplan_map::colliders::GeodeticHome {
        lat_deg: frame.home().lat_deg,
        lon_deg: frame.home().lon_deg,
    };
    skyplan_map::nofly::parse_no_fly(text)
        .and_then(|z| z.project(home, world.terrain().map(|t| t.home_ground_amsl_m())))
        .unwrap_or_default()
}

/// Renders the picture of `plan`, with the no-fly `zones` on a 2D map.
pub fn render(
    world: &World,
    plan: &Plan,
    kind: &PictureKind,
    flight: Option<&skyplan_plot::FlightLayers>,
    zones: &[Zone],
) -> Result<Vec<u8>> {
    if matches!(kind, PictureKind::Heatmap) && plan.grid_used.is_none() {
        return Err(bad_input("--plot: a heat map needs a grid planner"));
    }
    skyplan_plot::plan_picture::plan_picture_with_zones(world, plan, kind, flight, zones)
        .or_exit(Kind::Runtime)
}

/// `fleet --plot`: the map's configuration-space grid at the run's slice and every flight's
/// route, accepted ones a colour each, refused ones grey.
pub fn fleet_picture(
    world: &World,
    base: &skyplan_plan::PlanRequest,
    records: &[skyplan_fleet::FlightRecord],
    path: &Path,
) -> Result<Vec<u8>> {
    let format = skyplan_plot::PlotFormat::from_path(path).ok_or_else(|| {
        bad_input(format!(
            "--plot {}: expected a .png or .svg file name",
            path.display()
        ))
    })?;
    let spec = base.spec()?;
    let grid =
        skyplan_plan::Session::new(world.clone()).grid(spec.alt_m, spec.safety_m, spec.cell_m)?;
    let fleet: Vec<skyplan_plot::FleetRoute> = records
        .iter()
        .filter(|r| r.route_ne.len() > 1)
        .map(|r| skyplan_plot::FleetRoute {
            route_ne: r.route_ne.clone(),
            accepted: r.status == skyplan_fleet::Status::Accepted,
        })
        .collect();
    let accepted = fleet.iter().filter(|f| f.accepted).count();
    let scene = skyplan_plot::Scene {
        title: format!(
            "{}, fleet at {} m: {accepted} of {} flights accepted",
            world.name(),
            spec.alt_m,
            records.len()
        ),
        fleet: &fleet,
        ..skyplan_plot::Scene::of_grid(&grid)
    };
    skyplan_plot::render(&scene, format, 1000, 1000).or_exit(Kind::Runtime)
}
