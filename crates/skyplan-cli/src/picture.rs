//! `--plot`: one picture for any plan — the 2D map with the route (and a roadmap), the 3D top
//! view and side profile, or a heat map of a navigation function's field.

use crate::exit::{Classify, Kind, Result, bad_input};
use skyplan_plan::{Family, Plan, World};
use skyplan_plot::PlotFormat;
use std::path::Path;

pub use skyplan_plot::plan_picture::PictureKind;

/// The picture kind for a path and a planner's family.
pub fn kind_for(path: &Path, family: Family) -> Result<PictureKind> {
    let heat = matches!(family, Family::Wavefront | Family::Costmap);
    let format = PlotFormat::from_path(path);
    match (heat, format) {
        (true, Some(PlotFormat::Png)) => Ok(PictureKind::Heatmap),
        (true, _) => Err(bad_input(format!(
            "--plot {}: wavefront and costmap draw PNG heat maps; use a .png file name",
            path.display()
        ))),
        (false, Some(f)) => Ok(PictureKind::Scene(f)),
        (false, None) => Err(bad_input(format!(
            "--plot {}: expected a .png or .svg file name",
            path.display()
        ))),
    }
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
