//! One picture for any plan of the planning API (`skyplan plan --plot`, `fly --plot`,
//! `navigate --plot`): the 2D map with the route (and a roadmap), the 3D top view and side
//! profile, or a heat map of a navigation function's field.
//!
//! A plan with a trajectory (`Plan::trajectory`) shows it over the map or the top view, sampled
//! every 0.05 s and coloured by speed from rest to the speed limit ([`crate::speed_color`], its
//! scale in the legend), above a strip of speed and acceleration against time with both limits
//! dashed; the title gives its duration. Without one, the picture is the same as ever.

use crate::trajectory::SpeedTrace;
use crate::{FlightLayers, PlotError, PlotFormat};
use skyplan_cspace::{Cell, Grid2};
use skyplan_plan::{Geometry, Plan, Ride, World};
use std::path::Path;

/// What the picture of a plan is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PictureKind {
    /// The map and the route, in this format.
    Scene(PlotFormat),
    /// A PNG heat map of the planner's field.
    Heatmap,
}

impl PictureKind {
    /// The picture a file name asks for, for `planner`: a PNG heat map of the field for the
    /// planners whose route comes with one (the navigation functions: wavefront, costmap), else
    /// the map and the route in the file's format (.png or .svg). `Err` says which file names
    /// would do.
    ///
    /// ```
    /// use skyplan_plan::PlannerId;
    /// use skyplan_plot::{PlotFormat, plan_picture::PictureKind};
    /// use std::path::Path;
    ///
    /// let svg = PictureKind::for_path(Path::new("route.svg"), PlannerId::AnyAngle);
    /// assert_eq!(svg, Ok(PictureKind::Scene(PlotFormat::Svg)));
    /// assert_eq!(PictureKind::for_path(Path::new("f.png"), PlannerId::Wavefront), Ok(PictureKind::Heatmap));
    /// assert!(PictureKind::for_path(Path::new("f.svg"), PlannerId::Costmap).is_err());
    /// ```
    pub fn for_path(path: &Path, planner: skyplan_plan::PlannerId) -> Result<Self, &'static str> {
        match (planner.has_field(), PlotFormat::from_path(path)) {
            (true, Some(PlotFormat::Png)) => Ok(PictureKind::Heatmap),
            (true, _) => Err("wavefront and costmap draw PNG heat maps; use a .png file name"),
            (false, Some(f)) => Ok(PictureKind::Scene(f)),
            (false, None) => Err("expected a .png or .svg file name"),
        }
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

/// The picture of `plan` on `world`: a heat map of its field (a grid planner's), the 2D map
/// with the route (and what the planner built; `flight` adds what a flight saw), or the 3D
/// top view and side profile.
pub fn plan_picture(
    world: &World,
    plan: &Plan,
    kind: &PictureKind,
    flight: Option<&FlightLayers>,
) -> Result<Vec<u8>, PlotError> {
    plan_picture_with_zones(world, plan, kind, flight, &[])
}

/// As [`plan_picture`], with the no-fly `zones` (local metres about the map's home) drawn on
/// the 2D map: exclusion zones hatched, inclusion boundaries outlined, each labelled with its
/// band (other pictures do not show them).
pub fn plan_picture_with_zones(
    world: &World,
    plan: &Plan,
    kind: &PictureKind,
    flight: Option<&FlightLayers>,
    zones: &[skyplan_map::nofly::Zone],
) -> Result<Vec<u8>, PlotError> {
    let geometry = plan.geometry.clone().unwrap_or_default();
    let map = short_name(world.name());
    match (kind, plan.grid_used.as_deref()) {
        (PictureKind::Heatmap, Some(grid)) => field_picture(plan, &geometry, grid, map),
        (PictureKind::Scene(format), Some(grid))
            if plan.planner.info().dims == 2 && world.terrain().is_none() =>
        {
            let picture = MapPicture {
                plan,
                geometry: &geometry,
                grid,
                map,
                flight,
                zones,
            };
            picture.render(*format)
        }
        (PictureKind::Scene(format), _) => {
            picture3d(world, plan, &geometry, (map, flight), *format)
        }
        (PictureKind::Heatmap, None) => Err(PlotError::BadScene {
            what: "a heat map needs a grid planner",
        }),
    }
}

/// The heat map of a grid planner's field (distance, steps or cost to the goal) with its path.
fn field_picture(
    plan: &Plan,
    geometry: &Geometry,
    grid: &Grid2,
    map: &str,
) -> Result<Vec<u8>, PlotError> {
    let cell = |p: &[f64]| grid.cell_at_ne(p[0], p[1]);
    let path: Vec<Cell> = geometry.raw_path.iter().filter_map(|p| cell(p)).collect();
    let zeros;
    let values: &[f64] = match &geometry.field {
        Some(v) if v.len() == grid.len() => v,
        _ => {
            zeros = vec![0.0; grid.len()];
            &zeros
        }
    };
    let measure = match plan.planner {
        skyplan_plan::PlannerId::Costmap => "cost-to-go (cells of length + weight × cost)",
        _ if plan.details.get("field").and_then(|v| v.as_str()) == Some("steps") => {
            "steps to the goal"
        }
        _ => "distance to the goal (cells)",
    };
    let heat = crate::Heatmap {
        title: format!(
            "{map}, {}{}: {:.1} m, field of {measure}",
            plan.planner.info().label,
            grid_at(plan),
            plan.cost_m
        ),
        grid,
        values,
        measure,
        path: &path,
        start: plan.start.cell.map(|[r, c]| Cell::new(r, c)),
        goal: plan.goal.cell.map(|[r, c]| Cell::new(r, c)),
    };
    crate::render_heatmap_png(&heat, 1000)
}

/// What the 2D map picture of a plan shows.
struct MapPicture<'a> {
    plan: &'a Plan,
    geometry: &'a Geometry,
    grid: &'a Grid2,
    /// The map's short name, for the title.
    map: &'a str,
    flight: Option<&'a FlightLayers<'a>>,
    zones: &'a [skyplan_map::nofly::Zone],
}

impl MapPicture<'_> {
    /// The 2D map with the grid path, the waypoints and a roadmap's edges and connectors.
    fn render(&self, format: PlotFormat) -> Result<Vec<u8>, PlotError> {
        let (plan, geometry) = (self.plan, self.geometry);
        let ne = |p: &[f64]| (p[0], p[1]);
        let raw: Vec<_> = geometry.raw_path.iter().map(|p| ne(p)).collect();
        let waypoints: Vec<_> = plan.waypoints.iter().map(|w| ne(w)).collect();
        let seg = |s: &[[f64; 3]; 2]| (ne(&s[0]), ne(&s[1]));
        let graph: Vec<_> = geometry.edges.iter().map(seg).collect();
        let connectors: Vec<_> = geometry.connectors.iter().map(seg).collect();
        let how = match plan.details.get("fallback") {
            Some(v) if !v.is_null() => "grid fallback".to_string(),
            _ => plan.planner.info().label.to_string(),
        };
        let at = grid_at(plan);
        let title = match self.flight {
            // A flight: what was flown, not what was planned.
            Some(f) => {
                let flown_m: f64 = (f.track_ne.windows(2))
                    .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
                    .sum();
                format!(
                    "{}, flight{at}: {flown_m:.1} m flown over the ground, {} replans, {} hidden obstacles",
                    self.map,
                    f.replanned_ne.len(),
                    f.hidden.len()
                )
            }
            // A plan: the length of the route to fly, and the planner's own path when it differs
            // (a grid path before shortcutting).
            None => {
                let own = if (plan.cost_m - plan.mission_length_m).abs() > 0.05 {
                    format!(" ({how} path {:.1} m)", plan.cost_m)
                } else {
                    String::new()
                };
                format!(
                    "{}, {how}{at}: {:.1} m to fly in {} waypoints{own}",
                    self.map,
                    plan.mission_length_m,
                    waypoints.len()
                )
            }
        };
        let trace = plan.trajectory.as_ref().map(SpeedTrace::of).transpose()?;
        let title = title + &trajectory_title(trace.as_ref());
        let scene = crate::Scene {
            title,
            grid: self.grid,
            obstacles: &geometry.active_boxes,
            footprints: &geometry.active_footprints,
            raw_path_ne: &raw,
            pruned_path_ne: &waypoints,
            start_ne: Some((plan.start.north_m, plan.start.east_m)),
            goal_ne: Some((plan.goal.north_m, plan.goal.east_m)),
            graph_ne: &graph,
            connectors_ne: &connectors,
            flight: self.flight,
            zones: self.zones,
            fleet: &[],
        };
        match &trace {
            None => crate::render(&scene, format, 1000, 1000),
            Some(trace) => crate::render_traced(&scene, trace, format, 1000, 1000),
        }
    }
}

/// The 3D top view and side profile of a plan on the world's buildings (and of a flight's
/// track, when the flight layers carry its altitudes).
fn picture3d(
    world: &World,
    plan: &Plan,
    geometry: &Geometry,
    (map, flight): (&str, Option<&FlightLayers>),
    format: PlotFormat,
) -> Result<Vec<u8>, PlotError> {
    let flown: Vec<[f64; 3]> = match flight {
        Some(f) if f.track_alt_m.len() == f.track_ne.len() => (f.track_ne.iter())
            .zip(f.track_alt_m)
            .map(|(&(n, e), &a)| [n, e, a])
            .collect(),
        _ => Vec::new(),
    };
    let boxes = world
        .colliders()
        .map(|m| m.boxes.as_slice())
        .unwrap_or_default();
    let points = plan.points_nea();
    let edges: Vec<_> = geometry.edges.iter().map(|s| (s[0], s[1])).collect();
    let safety_m = plan.spec.safety_m;
    let trace = plan.trajectory.as_ref().map(SpeedTrace::of).transpose()?;
    let ground = world
        .terrain()
        .map(|t| ground_profile(t, &points))
        .unwrap_or_default();
    let ground_grid = world
        .terrain()
        .map(|t| ground_grid(t, &points, &geometry.raw_path));
    let scene = crate::Scene3d {
        title: format!(
            "{map}: {}, {:.0} m, margin {safety_m} m{}",
            plan.planner.info().name,
            plan.cost_m,
            trajectory_title(trace.as_ref())
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
        ground: &ground,
        ground_grid: ground_grid.as_ref(),
        flown: &flown,
    };
    crate::profile::render_plan3d_traced(&scene, trace.as_ref(), format, 1500, 900)
}

/// The ground over the top view's square, 160 samples a side (unknown where the DEM does not
/// reach), for its contours.
fn ground_grid(
    terrain: &skyplan_map::terrain::Terrain,
    points: &[[f64; 3]],
    raw_path: &[[f64; 3]],
) -> skyplan_map::contour::GroundGrid {
    let (centre, side) = crate::profile::top_view_square(points, raw_path);
    let n = 160;
    let step_m = side / (n - 1) as f64;
    let origin_ne = [centre[0] - side / 2.0, centre[1] - side / 2.0];
    let values = (0..n * n)
        .map(|k| {
            let (i, j) = ((k / n) as f64, (k % n) as f64);
            terrain
                .ground_m(origin_ne[0] + i * step_m, origin_ne[1] + j * step_m)
                .unwrap_or(f64::NAN)
        })
        .collect();
    skyplan_map::contour::GroundGrid {
        origin_ne,
        step_m,
        north_n: n,
        east_n: n,
        values,
    }
}

/// The ground under a route every ~1/600 of its horizontal length: `[distance, altitude above
/// home]` (points the terrain cannot place are left out).
fn ground_profile(terrain: &skyplan_map::terrain::Terrain, points: &[[f64; 3]]) -> Vec<[f64; 2]> {
    let total: f64 = points
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    let step = (total / 600.0).max(0.5);
    let mut out = Vec::new();
    let mut d0 = 0.0;
    for w in points.windows(2) {
        let len = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
        let n = (len / step).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let (north, east) = (
                w[0][0] + (w[1][0] - w[0][0]) * t,
                w[0][1] + (w[1][1] - w[0][1]) * t,
            );
            if let Ok(g) = terrain.ground_m(north, east) {
                out.push([d0 + len * t, g]);
            }
        }
        d0 += len;
    }
    out
}

/// The title's words for a trajectory (nothing without one).
fn trajectory_title(trace: Option<&SpeedTrace>) -> String {
    trace.map_or_else(String::new, |t| {
        format!(", trajectory {:.1} s", t.duration_s)
    })
}

fn grid_at(plan: &Plan) -> String {
    match (&plan.grid, plan.obstacles) {
        (Some(g), Some(_)) => format!(" at {} m altitude, {} m margin", g.alt_m, g.safety_m),
        _ => String::new(),
    }
}

/// The normalised cost map of a ride with its trace, as a PNG heat map.
pub fn ride_heatmap_png(ride: &Ride) -> Result<Vec<u8>, PlotError> {
    // The targets that changed mid-ride, in the title (the star marks the last target).
    let changes: String = (ride.legs.iter().filter(|l| l.replaced))
        .map(|l| {
            format!(
                "; target N {:.1}, E {:.1} replaced at step {}",
                l.target.north_m, l.target.east_m, l.to_step
            )
        })
        .collect();
    let heat = crate::Heatmap {
        title: format!(
            "navigation over the inflated cost map: {} steps{changes}",
            ride.trace.len().saturating_sub(1)
        ),
        grid: &ride.grid,
        values: &ride.costs,
        measure: "Nav2 cost (0 free to 254 lethal)",
        path: &ride.trace,
        start: Some(ride.ends.0),
        goal: Some(ride.ends.1),
    };
    crate::render_heatmap_png(&heat, 1000)
}
