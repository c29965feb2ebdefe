//! `--plot`: one picture for any plan — the 2D map with the route (and a roadmap), the 3D top
//! view and side profile, or a heat map of a navigation function's field.

use crate::exit::{Classify, Kind, Result, bad_input};
use skyplan_cspace::Cell;
use skyplan_plan::{Family, Plan, World};
use skyplan_plot::PlotFormat;
use std::path::Path;

/// What the picture will be, checked before planning.
pub enum PictureKind {
    Scene(PlotFormat),
    Heatmap,
}

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

fn short_name(name: &str) -> &str {
    if name == skyplan_plan::FCND_CITY_NAME {
        return "FCND city map";
    }
    Path::new(name)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(name)
}

/// Renders the picture of `plan` (which was planned with `geometry`).
pub fn render(
    world: &World,
    plan: &Plan,
    kind: &PictureKind,
    flight: Option<&skyplan_plot::FlightLayers>,
) -> Result<Vec<u8>> {
    let geometry = plan.geometry.clone().unwrap_or_default();
    let info = plan.planner.info();
    let grid = plan.grid_used.as_deref();
    let map = short_name(world.name());
    match (kind, grid) {
        (PictureKind::Heatmap, Some(grid)) => {
            let cell = |p: &[f64]| grid.cell_at_ne(p[0], p[1]);
            let path: Vec<Cell> = geometry.raw_path.iter().filter_map(|p| cell(p)).collect();
            let values = match geometry.field {
                Some(v) if v.len() == grid.len() => v,
                _ => vec![0.0; grid.len()],
            };
            let measure = match plan.planner {
                skyplan_plan::PlannerId::Costmap => "cost-to-go (cells of length + weight × cost)",
                _ if plan.details.get("field").and_then(|v| v.as_str()) == Some("steps") => {
                    "steps to the goal"
                }
                _ => "distance to the goal (cells)",
            };
            let heat = skyplan_plot::Heatmap {
                title: format!(
                    "{map}, {}{}: {:.1} m, field of {measure}",
                    info.label,
                    grid_at(plan),
                    plan.cost_m
                ),
                grid,
                values: &values,
                measure,
                path: &path,
                start: plan.start.cell.map(|[r, c]| Cell::new(r, c)),
                goal: plan.goal.cell.map(|[r, c]| Cell::new(r, c)),
            };
            skyplan_plot::render_heatmap_png(&heat, 1000).or_exit(Kind::Runtime)
        }
        (PictureKind::Scene(format), Some(grid)) if info.dims == 2 => {
            let ne = |p: &[f64]| (p[0], p[1]);
            let raw: Vec<_> = geometry.raw_path.iter().map(|p| ne(p)).collect();
            let waypoints: Vec<_> = plan.waypoints.iter().map(|w| ne(w)).collect();
            let seg = |s: &[[f64; 3]; 2]| (ne(&s[0]), ne(&s[1]));
            let graph: Vec<_> = geometry.edges.iter().map(seg).collect();
            let connectors: Vec<_> = geometry.connectors.iter().map(seg).collect();
            let how = match plan.details.get("fallback") {
                Some(v) if !v.is_null() => "grid fallback".to_string(),
                _ => info.label.to_string(),
            };
            let at = grid_at(plan);
            let scene = skyplan_plot::Scene {
                title: format!(
                    "{map}, {how}{at}: {:.1} m, {} waypoints",
                    plan.cost_m,
                    waypoints.len()
                ),
                grid,
                obstacles: &geometry.active_boxes,
                raw_path_ne: &raw,
                pruned_path_ne: &waypoints,
                start_ne: Some((plan.start.north_m, plan.start.east_m)),
                goal_ne: Some((plan.goal.north_m, plan.goal.east_m)),
                graph_ne: &graph,
                connectors_ne: &connectors,
                flight,
            };
            skyplan_plot::render(&scene, *format, 1000, 1000).or_exit(Kind::Runtime)
        }
        (PictureKind::Scene(format), _) => {
            let boxes = world
                .colliders()
                .map(|m| m.boxes.as_slice())
                .unwrap_or_default();
            let points = plan.points_nea();
            let edges: Vec<_> = geometry.edges.iter().map(|s| (s[0], s[1])).collect();
            let safety_m = plan
                .details
                .get("safety_m")
                .and_then(|v| v.as_f64())
                .unwrap_or(0.0);
            let scene = skyplan_plot::Scene3d {
                title: format!(
                    "{map}: {}, {:.0} m, margin {safety_m} m",
                    info.name, plan.cost_m
                ),
                obstacles: boxes,
                safety_m,
                path: &points,
                raw_path: &geometry.raw_path,
                raw_label: if plan.planner == skyplan_plan::PlannerId::Voxel {
                    "voxel path"
                } else {
                    "before shortcutting"
                },
                edges: &edges,
                edges_label: &geometry.edges_label,
            };
            skyplan_plot::render_plan3d(&scene, *format, 1500, 900).or_exit(Kind::Runtime)
        }
        (PictureKind::Heatmap, None) => Err(bad_input("--plot: a heat map needs a grid planner")),
    }
}

fn grid_at(plan: &Plan) -> String {
    match (&plan.grid, plan.obstacles) {
        (Some(g), Some(_)) => format!(" at {} m altitude, {} m margin", g.alt_m, g.safety_m),
        _ => String::new(),
    }
}
