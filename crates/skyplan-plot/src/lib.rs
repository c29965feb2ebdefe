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
//!     raw_path_ne: &path,
//!     pruned_path_ne: &[path[0], path[2]],
//!     start_ne: Some(path[0]),
//!     goal_ne: Some(path[2]),
//! };
//! let png = render_png(&scene, 640, 480)?;
//! assert_eq!(&png[1..4], b"PNG");
//! let svg = render_svg(&scene, 640, 480)?;
//! assert!(svg.contains("EAST (m)") && svg.contains("NORTH (m)"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use std::path::Path;
use std::sync::OnceLock;

use plotters::backend::RGBPixel;
use plotters::coord::Shift;
use plotters::element::ComposedElement;
use plotters::prelude::*;
use plotters::style::register_font;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use skyplan_cspace::Grid2;
use skyplan_map::colliders::ObstacleBox;

/// Smallest picture edge accepted, pixels.
pub const MIN_SIZE_PX: u32 = 200;
/// Largest picture edge accepted, pixels.
pub const MAX_SIZE_PX: u32 = 16_384;

/// Font family under which the embedded DejaVu Sans is registered with plotters.
const FAMILY: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

const CSPACE_COLOR: RGBColor = RGBColor(206, 209, 214);
const OBSTACLE_COLOR: RGBColor = RGBColor(96, 98, 104);
const RAW_COLOR: RGBColor = RGBColor(255, 127, 14);
const PRUNED_COLOR: RGBColor = RGBColor(31, 96, 196);
const START_COLOR: RGBColor = RGBColor(0, 170, 60);
const GOAL_COLOR: RGBColor = RGBColor(220, 30, 30);
const MESH_COLOR: RGBColor = RGBColor(232, 232, 232);
const FRAME_COLOR: RGBColor = RGBColor(40, 40, 40);

/// What one picture shows. All positions are local (north, east) metres.
#[derive(Debug, Clone)]
pub struct Scene<'a> {
    /// Title above the plot, for example `"colliders.csv at 5 m, margin 5 m"`.
    pub title: String,
    /// Configuration space: blocked cells are obstacles grown by the safety margin.
    pub grid: &'a Grid2,
    /// Footprints of the obstacles that count at this altitude, drawn darker over the grid.
    pub obstacles: &'a [ObstacleBox],
    /// The raw grid path, as (north, east) points.
    pub raw_path_ne: &'a [(f64, f64)],
    /// The pruned (shortcut) waypoints, as (north, east) points.
    pub pruned_path_ne: &'a [(f64, f64)],
    /// The start, if any.
    pub start_ne: Option<(f64, f64)>,
    /// The goal, if any.
    pub goal_ne: Option<(f64, f64)>,
}

impl Scene<'_> {
    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.raw_path_ne
            .iter()
            .chain(self.pruned_path_ne)
            .copied()
            .chain(self.start_ne)
            .chain(self.goal_ne)
    }
}

/// Why a picture could not be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PlotError {
    /// A picture size outside [`MIN_SIZE_PX`]..=[`MAX_SIZE_PX`].
    #[error("picture size {width} × {height} px: each edge must be within {MIN_SIZE_PX}..={MAX_SIZE_PX} px")]
    BadSize {
        /// Width asked for, pixels.
        width: u32,
        /// Height asked for, pixels.
        height: u32,
    },
    /// A non-finite coordinate in the scene.
    #[error("the scene holds a non-finite coordinate ({what})")]
    NonFinite {
        /// Which part of the scene.
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
        path.as_ref().extension().and_then(|e| e.to_str()).and_then(Self::from_extension)
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
pub fn render(scene: &Scene, format: PlotFormat, width_px: u32, height_px: u32) -> Result<Vec<u8>, PlotError> {
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
        let backend = BitMapBackend::<RGBPixel>::with_buffer_and_format(&mut rgb, (width_px, height_px))
            .map_err(|e| PlotError::Draw(e.to_string()))?;
        let root = backend.into_drawing_area();
        draw(&root, scene, &layout)?;
        root.present().map_err(draw_err)?;
    }
    let mut out = Vec::with_capacity(rgb.len() / 8);
    let mut encoder = png::Encoder::new(&mut out, width_px, height_px);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let enc_err = |e: png::EncodingError| PlotError::Encode(e.to_string());
    let mut writer = encoder.write_header().map_err(enc_err)?;
    writer.write_image_data(&rgb).map_err(enc_err)?;
    writer.finish().map_err(enc_err)?;
    Ok(out)
}

/// Renders a scene as an SVG document.
///
/// The text names the `sans-serif` family; the layout was measured with DejaVu Sans.
pub fn render_svg(scene: &Scene, width_px: u32, height_px: u32) -> Result<String, PlotError> {
    let layout = layout(scene, width_px, height_px)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width_px, height_px)).into_drawing_area();
        draw(&root, scene, &layout)?;
        root.present().map_err(draw_err)?;
    }
    Ok(svg)
}

fn draw_err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

fn ensure_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| register_font(FAMILY, FontStyle::Normal, FONT_BYTES).is_ok());
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// A rectangle of grid cells: rows `row..row + rows`, columns `col..col + cols`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CellRect {
    /// First (southernmost) row.
    pub row: u32,
    /// First (westernmost) column.
    pub col: u32,
    /// Number of rows (≥ 1).
    pub rows: u32,
    /// Number of columns (≥ 1).
    pub cols: u32,
}

/// The blocked cells of a grid as disjoint rectangles that cover them exactly.
///
/// Each row is cut into maximal runs of blocked cells, and a run is stacked with the identical
/// runs of the rows above it, so buildings grown by a margin come out as a few rectangles each.
///
/// ```
/// use skyplan_cspace::Grid2;
/// use skyplan_plot::{CellRect, blocked_rects};
/// let grid = Grid2::from_ascii("##..\n##.#\n...#")?;
/// assert_eq!(
///     blocked_rects(&grid),
///     vec![CellRect { row: 0, col: 0, rows: 2, cols: 2 }, CellRect { row: 1, col: 3, rows: 2, cols: 1 }]
/// );
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn blocked_rects(grid: &Grid2) -> Vec<CellRect> {
    let cols = grid.cols() as usize;
    let mut out = Vec::new();
    if cols == 0 {
        return out;
    }
    // Runs of the previous row, (start col, end col exclusive, first row), sorted by start.
    let mut open: Vec<(u32, u32, u32)> = Vec::new();
    let mut next: Vec<(u32, u32, u32)> = Vec::new();
    for (r, line) in grid.blocked_cells().chunks_exact(cols).enumerate() {
        let r = r as u32;
        next.clear();
        let mut prev = open.iter().peekable();
        let mut c = 0;
        while c < cols {
            if !line[c] {
                c += 1;
                continue;
            }
            let start = c;
            while c < cols && line[c] {
                c += 1;
            }
            let (c0, c1) = (start as u32, c as u32);
            // Close the previous row's runs that end before this one starts or differ from it.
            let mut first_row = r;
            while let Some(&&(p0, p1, pr)) = prev.peek() {
                if p0 > c0 {
                    break;
                }
                prev.next();
                if (p0, p1) == (c0, c1) {
                    first_row = pr;
                } else {
                    out.push(CellRect { row: pr, col: p0, rows: r - pr, cols: p1 - p0 });
                }
            }
            next.push((c0, c1, first_row));
        }
        for &(p0, p1, pr) in prev {
            out.push(CellRect { row: pr, col: p0, rows: r - pr, cols: p1 - p0 });
        }
        std::mem::swap(&mut open, &mut next);
    }
    let end = grid.rows();
    out.extend(open.iter().map(|&(p0, p1, pr)| CellRect { row: pr, col: p0, rows: end - pr, cols: p1 - p0 }));
    out.sort_unstable();
    out
}

/// Where things go on a picture of a given size: the plot area and its world extent.
///
/// The plot area has equal scales on both axes (a metre north is as long as a metre east).
/// [`PlotLayout::pixel_of_ne`] maps a world point to the pixel the renderer draws it at.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotLayout {
    width: u32,
    height: u32,
    /// Plot area: left, top, width, height in pixels.
    plot: (i32, i32, u32, u32),
    east_m: (f64, f64),
    north_m: (f64, f64),
    fonts: Fonts,
    legend: LegendLayout,
    x_labels: usize,
    y_labels: usize,
    decimals: usize,
    y_label_w: u32,
    x_label_h: u32,
    title_y: i32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Fonts {
    k: f64,
    title: f64,
    desc: f64,
    tick: f64,
    legend: f64,
}

#[derive(Debug, Clone, PartialEq)]
struct LegendLayout {
    entries: Vec<LegendEntry>,
    /// Top-left of each entry's sample, pixels.
    origins: Vec<(i32, i32)>,
    /// Box: left, top, width, height.
    frame: (i32, i32, u32, u32),
}

#[derive(Debug, Clone, PartialEq)]
struct LegendEntry {
    kind: LegendKind,
    text: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LegendKind {
    CSpace,
    Obstacle,
    Raw,
    Pruned,
    Start,
    Goal,
}

impl PlotLayout {
    /// Picture size, pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The plot area as (left, top, width, height) in pixels.
    pub fn plot_area(&self) -> (i32, i32, u32, u32) {
        self.plot
    }

    /// East extent shown, metres (left and right edges of the plot area).
    pub fn east_range_m(&self) -> (f64, f64) {
        self.east_m
    }

    /// North extent shown, metres (bottom and top edges of the plot area).
    pub fn north_range_m(&self) -> (f64, f64) {
        self.north_m
    }

    /// Metres per pixel, the same along both axes.
    pub fn metres_per_px(&self) -> f64 {
        (self.east_m.1 - self.east_m.0) / f64::from(self.plot.2.saturating_sub(1).max(1))
    }

    /// The pixel (x to the right, y down) at which a local (north, east) point is drawn.
    ///
    /// ```
    /// use skyplan_cspace::Grid2;
    /// use skyplan_plot::{Scene, layout};
    /// let grid = Grid2::from_ascii("....\n....")?;
    /// let scene = Scene {
    ///     title: String::new(), grid: &grid, obstacles: &[], raw_path_ne: &[],
    ///     pruned_path_ne: &[], start_ne: None, goal_ne: None,
    /// };
    /// let l = layout(&scene, 800, 600)?;
    /// let (x0, y0, w, h) = l.plot_area();
    /// // The south-west corner is the bottom-left pixel of the plot area.
    /// assert_eq!(l.pixel_of_ne(0.0, 0.0), (x0, y0 + h as i32 - 1));
    /// // North is up.
    /// assert!(l.pixel_of_ne(2.0, 0.0).1 < l.pixel_of_ne(0.0, 0.0).1);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn pixel_of_ne(&self, north_m: f64, east_m: f64) -> (i32, i32) {
        // The same arithmetic as plotters' linear f64 axes.
        let (x0, y0, w, h) = self.plot;
        let lx = (east_m - self.east_m.0) / (self.east_m.1 - self.east_m.0);
        let ly = (north_m - self.north_m.0) / (self.north_m.1 - self.north_m.0);
        let x = x0 + (f64::from(w - 1) * lx + 1e-3).floor() as i32;
        let y = y0 + h as i32 - 1 - (f64::from(h - 1) * ly + 1e-3).floor() as i32;
        (x, y)
    }
}

fn text_size(text: &str, size: f64) -> (u32, u32) {
    (FAMILY, size).into_font().box_size(text).unwrap_or((text.chars().count() as u32 * size as u32 / 2, size as u32))
}

fn fmt_metres(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    // Avoid "-0".
    if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') { format!("{:.decimals$}", 0.0) } else { s }
}

/// World extent of a scene: the grid and everything drawn, (east min, east max, north min, north max).
fn world_bounds(scene: &Scene) -> Result<(f64, f64, f64, f64), PlotError> {
    let f = scene.grid.frame();
    if !(f.origin_north_m.is_finite() && f.origin_east_m.is_finite() && f.cell_m.is_finite()) {
        return Err(PlotError::NonFinite { what: "grid frame" });
    }
    let mut b = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    let add = |b: &mut (f64, f64, f64, f64), n: f64, e: f64| {
        *b = (b.0.min(e), b.1.max(e), b.2.min(n), b.3.max(n));
    };
    if !scene.grid.is_empty() {
        add(&mut b, f.origin_north_m, f.origin_east_m);
        add(
            &mut b,
            f.origin_north_m + f64::from(scene.grid.rows()) * f.cell_m,
            f.origin_east_m + f64::from(scene.grid.cols()) * f.cell_m,
        );
    }
    let mut outside = false;
    for (n, e) in scene.points() {
        if !(n.is_finite() && e.is_finite()) {
            return Err(PlotError::NonFinite { what: "path, start or goal" });
        }
        outside |= b.0.is_finite() && (e < b.0 || e > b.1 || n < b.2 || n > b.3);
        add(&mut b, n, e);
    }
    for o in scene.obstacles {
        let v = [o.north_m, o.east_m, o.half_north_m, o.half_east_m];
        if !v.iter().all(|x| x.is_finite()) {
            return Err(PlotError::NonFinite { what: "obstacle" });
        }
        if scene.grid.is_empty() {
            add(&mut b, o.north_m - o.half_north_m, o.east_m - o.half_east_m);
            add(&mut b, o.north_m + o.half_north_m, o.east_m + o.half_east_m);
        }
    }
    if !b.0.is_finite() {
        b = (0.0, 1.0, 0.0, 1.0);
    }
    // Points beyond the grid, or a grid without cells: leave a little room around them.
    if outside || scene.grid.is_empty() {
        let pad = 0.03 * (b.1 - b.0).max(b.3 - b.2).max(1.0);
        b = (b.0 - pad, b.1 + pad, b.2 - pad, b.3 + pad);
    }
    if b.1 - b.0 < 1e-9 {
        b = (b.0 - 0.5, b.1 + 0.5, b.2, b.3);
    }
    if b.3 - b.2 < 1e-9 {
        b = (b.0, b.1, b.2 - 0.5, b.3 + 0.5);
    }
    Ok(b)
}

fn legend_entries(scene: &Scene) -> Vec<LegendEntry> {
    let mut v = Vec::new();
    let mut push = |kind, text: String| v.push(LegendEntry { kind, text });
    if scene.grid.blocked_cells().iter().any(|&b| b) {
        push(LegendKind::CSpace, "obstacle + safety margin".into());
    }
    if !scene.obstacles.is_empty() {
        push(LegendKind::Obstacle, "obstacle".into());
    }
    if !scene.raw_path_ne.is_empty() {
        push(LegendKind::Raw, format!("grid path ({} points)", scene.raw_path_ne.len()));
    }
    if !scene.pruned_path_ne.is_empty() {
        push(LegendKind::Pruned, format!("waypoints ({} points)", scene.pruned_path_ne.len()));
    }
    if scene.start_ne.is_some() {
        push(LegendKind::Start, "start".into());
    }
    if scene.goal_ne.is_some() {
        push(LegendKind::Goal, "goal".into());
    }
    v
}

/// Computes where everything goes on a `width_px` × `height_px` picture of `scene`.
///
/// The renderers use exactly this layout, so [`PlotLayout::pixel_of_ne`] tells where a point
/// of the scene lands on the picture.
pub fn layout(scene: &Scene, width_px: u32, height_px: u32) -> Result<PlotLayout, PlotError> {
    let size_ok = |v: u32| (MIN_SIZE_PX..=MAX_SIZE_PX).contains(&v);
    if !size_ok(width_px) || !size_ok(height_px) {
        return Err(PlotError::BadSize { width: width_px, height: height_px });
    }
    ensure_font()?;
    let (e0, e1, n0, n1) = world_bounds(scene)?;
    let (w, h) = (f64::from(width_px), f64::from(height_px));
    let k = (w.min(h) / 800.0).clamp(0.6, 4.0);
    let fonts = Fonts { k, title: 22.0 * k, desc: 17.0 * k, tick: 14.0 * k, legend: 14.0 * k };
    let px = |v: f64| v.round() as i32;

    // Tick labels: decimals from the span, widths from the widest end value.
    let span = (e1 - e0).max(n1 - n0);
    let decimals = if span >= 20.0 {
        0
    } else {
        ((-(span / 10.0).log10()).ceil().max(0.0) as usize + 1).min(6)
    };
    let widest = [e0, e1, n0, n1]
        .iter()
        .map(|&v| text_size(&fmt_metres(v, decimals), fonts.tick).0)
        .max()
        .unwrap_or(0);
    let tick_h = text_size("0", fonts.tick).1;
    let desc_h = text_size("NORTH (m)", fonts.desc).1;
    let tick_mark = 5; // plotters' default tick length; labels sit 2× that from the axis.
    let y_label_w = widest + 2 * tick_mark as u32 + px(1.8 * f64::from(desc_h)) as u32;
    let x_label_h = tick_h + 2 * tick_mark as u32 + px(2.0 * f64::from(desc_h)) as u32;
    let outer = px(14.0 * k);
    let title_h = if scene.title.is_empty() { 0 } else { px(1.9 * fonts.title) };
    let right_pad = (widest as i32 / 2 + px(6.0 * k)).max(outer);

    // Legend geometry (entries stacked in a column, or in a row under the plot).
    let entries = legend_entries(scene);
    let sample_w = px(34.0 * k);
    let row_h = px(1.7 * fonts.legend);
    let pad = px(10.0 * k);
    let text_gap = px(8.0 * k);
    let entry_w: Vec<i32> =
        entries.iter().map(|e| sample_w + text_gap + text_size(&e.text, fonts.legend).0 as i32).collect();
    let n = entries.len() as i32;
    let column = (
        2 * pad + entry_w.iter().copied().max().unwrap_or(0),
        2 * pad + n * row_h - (row_h - px(fonts.legend)).max(0) / 2,
    );
    let entry_sep = px(22.0 * k);
    let row_w = 2 * pad + entry_w.iter().sum::<i32>() + entry_sep * (n - 1).max(0);
    let row = (row_w, 2 * pad + px(fonts.legend));
    let legend_gap = px(18.0 * k);

    // Available plot area for each placement, and the scale it allows.
    let espan = e1 - e0;
    let nspan = n1 - n0;
    let fit = |aw: i32, ah: i32| -> f64 {
        if aw < 20 || ah < 20 { 0.0 } else { (f64::from(aw - 1) / espan).min(f64::from(ah - 1) / nspan) }
    };
    let top = outer + title_h;
    let base_w = width_px as i32 - outer - y_label_w as i32 - right_pad;
    let base_h = height_px as i32 - top - x_label_h as i32 - outer;
    #[derive(Clone, Copy, PartialEq)]
    enum Place {
        None,
        Right,
        Below,
    }
    let candidates: Vec<(Place, i32, i32)> = if entries.is_empty() {
        vec![(Place::None, base_w, base_h)]
    } else {
        let mut c = vec![(Place::Right, base_w - legend_gap - column.0, base_h)];
        if row.0 <= width_px as i32 - 2 * outer {
            c.push((Place::Below, base_w, base_h - legend_gap - row.1));
        }
        c
    };
    let (place, aw, ah) = candidates
        .iter()
        .copied()
        .max_by(|a, b| fit(a.1, a.2).total_cmp(&fit(b.1, b.2)))
        .unwrap_or((Place::None, base_w, base_h));
    let s = fit(aw, ah);
    if s <= 0.0 {
        return Err(PlotError::BadSize { width: width_px, height: height_px });
    }
    let pw = (espan * s).floor() as i32 + 1;
    let ph = (nspan * s).floor() as i32 + 1;
    let east_m = (e0, e0 + f64::from(pw - 1) / s);
    let north_m = (n0, n0 + f64::from(ph - 1) / s);

    // Centre the whole group (labels, plot, legend) on the picture.
    let group_w = y_label_w as i32
        + pw
        + match place {
            Place::Right => right_pad.max(legend_gap) + column.0,
            _ => right_pad,
        };
    let group_h = title_h
        + ph
        + x_label_h as i32
        + match place {
            Place::Below => legend_gap + row.1,
            _ => 0,
        };
    let gx = ((width_px as i32 - group_w) / 2).max(outer);
    let gy = ((height_px as i32 - group_h) / 2).max(outer);
    let plot_x = gx + y_label_w as i32;
    let plot_y = gy + title_h;

    let mut origins = Vec::new();
    let frame = match place {
        Place::None => (0, 0, 0, 0),
        Place::Right => {
            let lx = plot_x + pw + right_pad.max(legend_gap);
            let ly = plot_y;
            for i in 0..n {
                origins.push((lx + pad, ly + pad + i * row_h));
            }
            (lx, ly, column.0 as u32, column.1 as u32)
        }
        Place::Below => {
            let lx = plot_x + (pw - row.0) / 2;
            let lx = lx.clamp(outer, (width_px as i32 - outer - row.0).max(outer));
            let ly = plot_y + ph + x_label_h as i32 + legend_gap;
            let mut x = lx + pad;
            for wdt in &entry_w {
                origins.push((x, ly + pad));
                x += wdt + entry_sep;
            }
            (lx, ly, row.0 as u32, row.1 as u32)
        }
    };

    let x_labels = ((pw as f64) / (f64::from(widest) + 45.0 * k)).floor().max(2.0) as usize;
    let y_labels = ((ph as f64) / (f64::from(tick_h) * 3.5)).floor().max(2.0) as usize;
    Ok(PlotLayout {
        width: width_px,
        height: height_px,
        plot: (plot_x, plot_y, pw as u32, ph as u32),
        east_m,
        north_m,
        fonts,
        legend: LegendLayout { entries, origins, frame },
        x_labels,
        y_labels,
        decimals,
        y_label_w,
        x_label_h,
        title_y: gy + px(0.35 * fonts.title),
    })
}

fn font(size: f64) -> TextStyle<'static> {
    TextStyle::from((FAMILY, size).into_font()).color(&BLACK)
}

fn stroke(k: f64, base: f64) -> u32 {
    (base * k).round().max(1.0) as u32
}

/// Draws the scene on any plotters backend; `root` is the whole picture.
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, scene: &Scene, l: &PlotLayout) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(draw_err)?;
    let (px, py, pw, ph) = l.plot;
    let k = l.fonts.k;
    let chart_area = root.clone().shrink(
        (px - l.y_label_w as i32, py),
        (pw + l.y_label_w, ph + l.x_label_h),
    );
    let mut chart = ChartBuilder::on(&chart_area)
        .x_label_area_size(l.x_label_h)
        .y_label_area_size(l.y_label_w)
        .build_cartesian_2d(l.east_m.0..l.east_m.1, l.north_m.0..l.north_m.1)
        .map_err(draw_err)?;
    let decimals = l.decimals;
    let fmt = move |v: &f64| fmt_metres(*v, decimals);
    chart
        .configure_mesh()
        .x_desc("EAST (m)")
        .y_desc("NORTH (m)")
        .x_labels(l.x_labels)
        .y_labels(l.y_labels)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .label_style(font(l.fonts.tick))
        .axis_desc_style(font(l.fonts.desc))
        .bold_line_style(MESH_COLOR.stroke_width(1))
        .light_line_style(TRANSPARENT)
        .axis_style(FRAME_COLOR.stroke_width(1))
        .draw()
        .map_err(draw_err)?;

    // Configuration space, then the obstacles themselves.
    let f = scene.grid.frame();
    let rects = blocked_rects(scene.grid);
    chart
        .draw_series(rects.iter().map(|r| {
            let e0 = f.origin_east_m + f64::from(r.col) * f.cell_m;
            let n0 = f.origin_north_m + f64::from(r.row) * f.cell_m;
            let e1 = e0 + f64::from(r.cols) * f.cell_m;
            let n1 = n0 + f64::from(r.rows) * f.cell_m;
            Rectangle::new([(e0, n1), (e1, n0)], CSPACE_COLOR.filled())
        }))
        .map_err(draw_err)?;
    chart
        .draw_series(scene.obstacles.iter().map(|o| {
            Rectangle::new(
                [(o.east_m - o.half_east_m, o.north_m + o.half_north_m), (o.east_m + o.half_east_m, o.north_m - o.half_north_m)],
                OBSTACLE_COLOR.filled(),
            )
        }))
        .map_err(draw_err)?;

    // Paths: the raw grid path thin, the pruned one thick with its waypoints.
    let en = |&(n, e): &(f64, f64)| (e, n);
    if scene.raw_path_ne.len() > 1 {
        chart
            .draw_series(LineSeries::new(scene.raw_path_ne.iter().map(en), RAW_COLOR.stroke_width(stroke(k, 1.5))))
            .map_err(draw_err)?;
    }
    let r_wp = stroke(k, 4.0);
    if scene.pruned_path_ne.len() > 1 {
        chart
            .draw_series(LineSeries::new(
                scene.pruned_path_ne.iter().map(en),
                PRUNED_COLOR.stroke_width(stroke(k, 3.0)),
            ))
            .map_err(draw_err)?;
    }
    chart
        .draw_series(scene.pruned_path_ne.iter().map(|p| waypoint_marker(en(p), r_wp)))
        .map_err(draw_err)?;
    let r_end = stroke(k, 8.0);
    if let Some(p) = scene.start_ne {
        chart.draw_series(std::iter::once(start_marker(en(&p), r_end))).map_err(draw_err)?;
    }
    if let Some(p) = scene.goal_ne {
        chart.draw_series(std::iter::once(goal_marker(en(&p), r_end))).map_err(draw_err)?;
    }

    // Frame around the plot area, title, legend.
    root.draw(&Rectangle::new([(px, py), (px + pw as i32 - 1, py + ph as i32 - 1)], FRAME_COLOR.stroke_width(1)))
        .map_err(draw_err)?;
    if !scene.title.is_empty() {
        let style = font(l.fonts.title).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(scene.title.clone(), (px + pw as i32 / 2, l.title_y), style)).map_err(draw_err)?;
    }
    draw_legend(root, l, r_wp, r_end)
}

type Dot = Circle<(i32, i32), u32>;
type TwoDots<C, DB> = ComposedElement<C, DB, Dot, Dot>;

/// A waypoint: a white disc ringed in the pruned path's blue.
fn waypoint_marker<C, DB: DrawingBackend>(at: C, r: u32) -> TwoDots<C, DB> {
    EmptyElement::at(at)
        + Circle::new((0, 0), r, PRUNED_COLOR.filled())
        + Circle::new((0, 0), r.saturating_sub((f64::from(r) * 0.45).round() as u32).max(1), WHITE.filled())
}

/// The start: a green disc with a dark rim.
fn start_marker<C, DB: DrawingBackend>(at: C, r: u32) -> TwoDots<C, DB> {
    EmptyElement::at(at) + Circle::new((0, 0), r, FRAME_COLOR.filled()) + Circle::new((0, 0), r - 1, START_COLOR.filled())
}

/// The goal: a red five-pointed star with a dark outline.
fn goal_marker<C, DB: DrawingBackend>(at: C, r: u32) -> ComposedElement<C, DB, Polygon<(i32, i32)>, PathElement<(i32, i32)>> {
    let r_out = f64::from(r) * 1.3;
    let r_in = r_out * 0.45;
    let pts: Vec<(i32, i32)> = (0..10)
        .map(|i| {
            let a = std::f64::consts::PI * (f64::from(i) / 5.0 - 0.5);
            let rr = if i % 2 == 0 { r_out } else { r_in };
            ((rr * a.cos()).round() as i32, (rr * a.sin()).round() as i32)
        })
        .collect();
    let mut outline = pts.clone();
    outline.push(pts[0]);
    EmptyElement::at(at) + Polygon::new(pts, GOAL_COLOR.filled()) + PathElement::new(outline, FRAME_COLOR.stroke_width(1))
}

fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    l: &PlotLayout,
    r_wp: u32,
    r_end: u32,
) -> Result<(), PlotError>
where
    DB::ErrorType: 'static,
{
    let legend = &l.legend;
    if legend.entries.is_empty() {
        return Ok(());
    }
    let k = l.fonts.k;
    let (lx, ly, lw, lh) = legend.frame;
    let corner = (lx + lw as i32 - 1, ly + lh as i32 - 1);
    root.draw(&Rectangle::new([(lx, ly), corner], WHITE.filled())).map_err(draw_err)?;
    root.draw(&Rectangle::new([(lx, ly), corner], RGBColor(170, 170, 170).stroke_width(1))).map_err(draw_err)?;
    let sample_w = (34.0 * k).round() as i32;
    let text_gap = (8.0 * k).round() as i32;
    let lh_px = l.fonts.legend.round() as i32;
    for (entry, &(x, y)) in legend.entries.iter().zip(&legend.origins) {
        let cy = y + lh_px / 2;
        let cx = x + sample_w / 2;
        let swatch = |color: RGBColor| {
            let hs = (lh_px / 2).max(3);
            Rectangle::new([(x + 2, cy - hs), (x + sample_w - 2, cy + hs)], color.filled())
        };
        let res = match entry.kind {
            LegendKind::CSpace => root.draw(&swatch(CSPACE_COLOR)),
            LegendKind::Obstacle => root.draw(&swatch(OBSTACLE_COLOR)),
            LegendKind::Raw => {
                root.draw(&PathElement::new(vec![(x, cy), (x + sample_w, cy)], RAW_COLOR.stroke_width(stroke(k, 1.5))))
            }
            LegendKind::Pruned => root
                .draw(&PathElement::new(vec![(x, cy), (x + sample_w, cy)], PRUNED_COLOR.stroke_width(stroke(k, 3.0))))
                .and_then(|()| root.draw(&waypoint_marker((cx, cy), r_wp))),
            LegendKind::Start => root.draw(&start_marker((cx, cy), r_end)),
            LegendKind::Goal => root.draw(&goal_marker((cx, cy), r_end)),
        };
        res.map_err(draw_err)?;
        let style = font(l.fonts.legend).pos(Pos::new(HPos::Left, VPos::Center));
        root.draw(&Text::new(entry.text.clone(), (x + sample_w + text_gap, cy), style)).map_err(draw_err)?;
    }
    Ok(())
}
