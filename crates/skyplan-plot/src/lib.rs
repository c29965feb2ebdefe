//! Pictures of a planned path over a configuration space, rendered to bytes.
//!
//! A [`Scene`] gathers what one picture shows: the configuration-space grid (obstacles grown by
//! the safety margin, light grey), the obstacle footprints (dark grey), the raw grid path (thin
//! orange line), the pruned waypoints (thick blue line with a circle at each waypoint), the start
//! (green circle) and the goal (red star). The picture follows the FCND convention: the x axis is
//! EAST and the y axis NORTH, both in metres, north up, with equal scales on both axes.
//!
//! [`render_png`] and [`render_svg`] return the picture in memory; this crate never touches the
//! file system nor prints anything. The text uses DejaVu Sans, embedded in the library.
//! [`layout`] tells where each world point lands on the picture.
//!
//! The configuration space is drawn as [`blocked_rects`]: runs of blocked cells merged along rows
//! and then across identical rows, so the 921 × 921 FCND city grid (about 519 000 blocked cells)
//! takes under a thousand rectangles.
//!
//! ```
//! use skyplan_cspace::{Grid2, GridFrame};
//! use skyplan_plot::{Scene, render_png, render_svg};
//!
//! let mut blocked = vec![false; 20 * 30];
//! blocked[10 * 30 + 15] = true;
//! let frame = GridFrame { origin_north_m: -10.0, origin_east_m: -15.0, cell_m: 1.0 };
//! let grid = Grid2::new(20, 30, blocked, frame)?;
//! let path = [(-5.0, -10.0), (0.0, 0.0), (5.0, 10.0)];
//! let scene = Scene {
//!     title: "example".into(),
//!     grid: &grid,
//!     obstacles: &[],
//!     footprints: &[],
//!     raw_path_ne: &path,
//!     pruned_path_ne: &[path[0], path[2]],
//!     start_ne: Some(path[0]),
//!     goal_ne: Some(path[2]),
//!     graph_ne: &[],
//!     connectors_ne: &[],
//!     flight: None,
//!     zones: &[],
//!     fleet: &[],
//! };
//! let png = render_png(&scene, 640, 480)?;
//! assert_eq!(&png[1..4], b"PNG");
//! let svg = render_svg(&scene, 640, 480)?;
//! assert!(svg.contains("EAST (m)") && svg.contains("NORTH (m)"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod draw;
mod heatmap;
mod layout;
pub mod plan_picture;
mod profile;
mod rects;
mod text;
mod trajectory;

use std::path::Path;

use plotters::backend::RGBPixel;
use plotters::prelude::*;
use skyplan_cspace::Grid2;
use skyplan_map::colliders::ObstacleBox;
use skyplan_map::footprints::Footprint;

use crate::draw::draw;
pub use crate::heatmap::{Heatmap, normalise_0_255, render_heatmap_png};
pub use crate::layout::{PlotLayout, layout};
pub use crate::profile::{ProfileColumn, Scene3d, profile_columns, render_plan3d};
pub use crate::rects::{CellRect, blocked_rects};
use crate::text::TextMode;
use crate::trajectory::SpeedTrace;
pub use crate::trajectory::speed_color;

/// Smallest picture edge accepted, pixels.
pub const MIN_SIZE_PX: u32 = 200;
/// Largest picture edge accepted, pixels.
pub const MAX_SIZE_PX: u32 = 8_192;

/// What one picture shows. All positions are local (north, east) metres.
#[derive(Debug, Clone)]
pub struct Scene<'a> {
    /// Title above the plot, for example `"colliders.csv at 5 m, margin 5 m"`.
    pub title: String,
    /// Configuration space: blocked cells are obstacles grown by the safety margin.
    pub grid: &'a Grid2,
    /// Footprints of the obstacles that count at this altitude, drawn darker over the grid.
    pub obstacles: &'a [ObstacleBox],
    /// Building footprints that count at this altitude, drawn as their polygons (holes
    /// open), dark grey like the boxes.
    pub footprints: &'a [Footprint],
    /// The raw grid path, as (north, east) points.
    pub raw_path_ne: &'a [(f64, f64)],
    /// The pruned (shortcut) waypoints, as (north, east) points.
    pub pruned_path_ne: &'a [(f64, f64)],
    /// The start, if any.
    pub start_ne: Option<(f64, f64)>,
    /// The goal, if any.
    pub goal_ne: Option<(f64, f64)>,
    /// Edges of a roadmap (e.g. a Voronoi graph), drawn thin and light under everything else;
    /// empty for none. With edges, the raw path is labelled as the graph route.
    pub graph_ne: &'a [Segment],
    /// Connectors from the start and the goal to the roadmap, drawn thin; empty for none.
    pub connectors_ne: &'a [Segment],
    /// What a flight added (hidden obstacles, learned cells, replanned routes, the flown
    /// track), for `skyplan fly --plot`; `None` for a plan.
    pub flight: Option<&'a FlightLayers<'a>>,
    /// No-fly zones (local metres), drawn over the map: exclusion zones outlined red and
    /// hatched, inclusion boundaries outlined green without hatching, each labelled with its
    /// number and band; empty for none.
    pub zones: &'a [skyplan_map::nofly::Zone],
    /// The routes of a fleet of flights (`skyplan fleet --plot`): each accepted one in a
    /// colour of its own, refused ones thin grey; empty for none.
    pub fleet: &'a [FleetRoute],
}

/// One flight of a fleet in a picture.
#[derive(Debug, Clone, PartialEq)]
pub struct FleetRoute {
    /// Its route, (north, east) metres.
    pub route_ne: Vec<(f64, f64)>,
    /// Whether its intent was accepted.
    pub accepted: bool,
}

/// A flight drawn over its plan: what the map did not show and what the vehicle did about it.
#[derive(Debug, Clone, Default)]
pub struct FlightLayers<'a> {
    /// Obstacles present in the (simulated) world but absent from the map, drawn dark red.
    pub hidden: &'a [ObstacleBox],
    /// Centres of the cells the vehicle learned as occupied, (north, east).
    pub learned_ne: &'a [(f64, f64)],
    /// Each replanned route, (north, east) points from where the vehicle was to the goal.
    pub replanned_ne: &'a [Vec<(f64, f64)>],
    /// The flown track, (north, east).
    pub track_ne: &'a [(f64, f64)],
    /// The flown track's altitudes above home, one per point of `track_ne` (the 3D picture's
    /// side profile draws them); empty if unknown.
    pub track_alt_m: &'a [f64],
}

/// A segment between two (north, east) points, metres.
pub type Segment = ((f64, f64), (f64, f64));

impl<'a> Scene<'a> {
    /// `grid` alone, untitled, nothing drawn on it (the base of a struct update).
    pub fn of_grid(grid: &'a Grid2) -> Self {
        Scene {
            title: String::new(),
            grid,
            obstacles: &[],
            footprints: &[],
            raw_path_ne: &[],
            pruned_path_ne: &[],
            start_ne: None,
            goal_ne: None,
            graph_ne: &[],
            connectors_ne: &[],
            flight: None,
            zones: &[],
            fleet: &[],
        }
    }

    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.raw_path_ne
            .iter()
            .chain(self.pruned_path_ne)
            .copied()
            .chain(self.start_ne)
            .chain(self.goal_ne)
            .chain(
                self.graph_ne
                    .iter()
                    .chain(self.connectors_ne)
                    .flat_map(|&(a, b)| [a, b]),
            )
            .chain(self.flight.into_iter().flat_map(|f| {
                f.track_ne
                    .iter()
                    .chain(f.learned_ne)
                    .chain(f.replanned_ne.iter().flatten())
                    .copied()
            }))
            .chain(self.fleet.iter().flat_map(|f| f.route_ne.iter().copied()))
    }
}

/// Why a picture could not be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlotError {
    /// A picture size outside [`MIN_SIZE_PX`]..=[`MAX_SIZE_PX`].
    #[error(
        "picture size {width} × {height} px: each edge must be within {MIN_SIZE_PX}..={MAX_SIZE_PX} px"
    )]
    BadSize {
        /// Width asked for, pixels.
        width: u32,
        /// Height asked for, pixels.
        height: u32,
    },
    /// A scene that cannot be drawn, such as one with a NaN coordinate.
    #[error("cannot draw the scene: {what}")]
    BadScene {
        /// What is wrong with it.
        what: &'static str,
    },
    /// The embedded font could not be loaded.
    #[error("the embedded DejaVu Sans font could not be registered")]
    Font,
    /// The drawing library failed.
    #[error("drawing failed: {0}")]
    Draw(String),
    /// The PNG encoder failed.
    #[error("PNG encoding failed: {0}")]
    Encode(String),
}

/// Output format of a picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlotFormat {
    /// Portable Network Graphics (raster).
    Png,
    /// Scalable Vector Graphics (text).
    Svg,
}

impl PlotFormat {
    /// The format named by a file extension (`png` or `svg`, any case, without the dot).
    pub fn from_extension(ext: &str) -> Option<Self> {
        if ext.eq_ignore_ascii_case("png") {
            Some(Self::Png)
        } else if ext.eq_ignore_ascii_case("svg") {
            Some(Self::Svg)
        } else {
            None
        }
    }

    /// The format of a file path, from its extension.
    ///
    /// ```
    /// use skyplan_plot::PlotFormat;
    /// assert_eq!(PlotFormat::from_path("out/city.PNG"), Some(PlotFormat::Png));
    /// assert_eq!(PlotFormat::from_path("city.svg"), Some(PlotFormat::Svg));
    /// assert_eq!(PlotFormat::from_path("city.jpg"), None);
    /// ```
    pub fn from_path(path: impl AsRef<Path>) -> Option<Self> {
        path.as_ref()
            .extension()
            .and_then(|e| e.to_str())
            .and_then(Self::from_extension)
    }

    /// The usual file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Png => "png",
            Self::Svg => "svg",
        }
    }
}

/// Renders a scene in the given format; SVG comes back as its UTF-8 bytes.
pub fn render(
    scene: &Scene,
    format: PlotFormat,
    width_px: u32,
    height_px: u32,
) -> Result<Vec<u8>, PlotError> {
    match format {
        PlotFormat::Png => render_png(scene, width_px, height_px),
        PlotFormat::Svg => render_svg(scene, width_px, height_px).map(String::into_bytes),
    }
}

/// Renders a scene as a PNG file (8-bit RGB) in memory.
pub fn render_png(scene: &Scene, width_px: u32, height_px: u32) -> Result<Vec<u8>, PlotError> {
    let layout = layout(scene, width_px, height_px)?;
    let mut rgb = vec![255_u8; width_px as usize * height_px as usize * 3];
    {
        let backend =
            BitMapBackend::<RGBPixel>::with_buffer_and_format(&mut rgb, (width_px, height_px))
                .map_err(|e| PlotError::Draw(e.to_string()))?;
        let root = backend.into_drawing_area();
        draw(&root, scene, &layout, TextMode::Glyphs, None, None)?;
        root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
    }
    crate::heatmap::encode_rgb_png(&rgb, width_px, height_px)
}

/// Renders a scene as an SVG document.
///
/// The text names the `sans-serif` family; the layout was measured with DejaVu Sans.
pub fn render_svg(scene: &Scene, width_px: u32, height_px: u32) -> Result<String, PlotError> {
    let layout = layout(scene, width_px, height_px)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width_px, height_px)).into_drawing_area();
        draw(&root, scene, &layout, TextMode::Strings, None, None)?;
        root.present().map_err(|e| PlotError::Draw(e.to_string()))?;
    }
    Ok(svg)
}

/// Renders a scene with a trajectory: the map (`width_px` × `map_height_px`) with the curve
/// coloured by speed and the scale in the legend, above a strip of speed and acceleration
/// against time.
pub(crate) fn render_traced(
    scene: &Scene,
    trace: &SpeedTrace,
    format: PlotFormat,
    width_px: u32,
    map_height_px: u32,
) -> Result<Vec<u8>, PlotError> {
    let extra = vec![crate::layout::LegendEntry {
        kind: crate::layout::LegendKind::SpeedScale,
        text: trace.legend_text(),
    }];
    let layout = crate::layout::layout_full(scene, width_px, map_height_px, None, extra)?;
    let height_px = map_height_px + trajectory::panel_height(width_px);
    if height_px > MAX_SIZE_PX {
        return Err(PlotError::BadSize {
            width: width_px,
            height: height_px,
        });
    }
    match format {
        PlotFormat::Png => {
            let mut rgb = vec![255_u8; width_px as usize * height_px as usize * 3];
            {
                let backend = BitMapBackend::<RGBPixel>::with_buffer_and_format(
                    &mut rgb,
                    (width_px, height_px),
                )
                .map_err(|e| PlotError::Draw(e.to_string()))?;
                let root = backend.into_drawing_area();
                draw_traced(
                    &root,
                    scene,
                    &layout,
                    trace,
                    TextMode::Glyphs,
                    map_height_px,
                )?;
            }
            crate::heatmap::encode_rgb_png(&rgb, width_px, height_px)
        }
        PlotFormat::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (width_px, height_px));
                let root = root.into_drawing_area();
                draw_traced(
                    &root,
                    scene,
                    &layout,
                    trace,
                    TextMode::Strings,
                    map_height_px,
                )?;
            }
            Ok(svg.into_bytes())
        }
    }
}

/// The map with a trajectory over its top `map_height_px` pixels, the time panels under it.
fn draw_traced<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    scene: &Scene,
    layout: &PlotLayout,
    trace: &SpeedTrace,
    mode: TextMode,
    map_height_px: u32,
) -> Result<(), PlotError> {
    let (map, strip) = root.split_vertically(map_height_px);
    draw(&map, scene, layout, mode, None, Some(trace))?;
    trajectory::draw_panels(&strip, trace, mode, layout.fonts.desc)?;
    root.present().map_err(|e| PlotError::Draw(e.to_string()))
}
