//! `--plot`: one picture for any plan — the 2D map with the route (and a roadmap), the 3D top
//! view and side profile, or a heat map of a navigation function's field.

use crate::exit::{Classify, Kind, Result, bad_input};
use skyplan_plan::{Plan, PlannerId, World};
use std::path::Path;

pub use skyplan_plot::plan_picture::PictureKind;

/// The picture kind for a path and a planner.
pub fn kind_for(path: &Path, planner: PlannerId) -> Result<PictureKind> {
    PictureKind::for_path(path, planner)
        .map_err(|why| bad_input(format!("--plot {}: {why}", path.display())))
}

/// Renders the picture of `plan`.
pub fn render(
    world: &World,
    plan: &Plan,
    kind: &PictureKind,
    flight: Option<&skyplan_plot::FlightLayers>,
) -> Result<Vec<u8>> {
    if matches!(kind, PictureKind::Heatmap) && plan.grid_used.is_none() {
        return Err(bad_input("--plot: a heat map needs a grid planner"));
    }
    skyplan_plot::plan_picture::plan_picture(world, plan, kind, flight).or_exit(Kind::Runtime)
}
