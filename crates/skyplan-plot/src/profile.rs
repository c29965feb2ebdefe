//! Pictures of a 3D route: a top view (buildings shaded by height, the route, optionally a
//! roadmap or tree) beside a side profile (horizontal distance along the route against altitude,
//! with the buildings under the route drawn as filled columns and the safety margin above them).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;
use skyplan_map::colliders::ObstacleBox;

use crate::text::{Label, TextMode, VAlign, draw_label, draw_tick, ensure_font};
use crate::trajectory::SpeedTrace;
use crate::{MAX_SIZE_PX, MIN_SIZE_PX, PlotError, PlotFormat};

const ROUTE_COLOR: RGBColor = RGBColor(31, 96, 196);
const RAW_COLOR: RGBColor = RGBColor(255, 127, 14);
const FLOWN_COLOR: RGBColor = RGBColor(20, 20, 20);
const EDGE_COLOR: RGBColor = RGBColor(170, 200, 235);
const MARGIN_COLOR: RGBColor = RGBColor(222, 224, 228);
const START_COLOR: RGBColor = RGBColor(0, 170, 60);
const GOAL_COLOR: RGBColor = RGBColor(222, 30, 30);
const FRAME_COLOR: RGBColor = RGBColor(40, 40, 40);
const GRID_COLOR: RGBColor = RGBColor(232, 232, 232);
const GROUND_COLOR: RGBColor = RGBColor(214, 196, 160);
const CONTOUR_COLOR: RGBColor = RGBColor(160, 120, 70);
const GROUND_LINE: RGBColor = RGBColor(140, 110, 60);

/// What a 3D route picture shows. Points are `[north_m, east_m, alt_m]`.
#[derive(Debug, Clone)]
pub struct Scene3d<'a> {
    /// Title above the picture.
    pub title: String,
    /// The map's obstacle boxes (not grown).
    pub obstacles: &'a [ObstacleBox],
    /// The safety margin, metres: drawn as a light band around the buildings in the profile.
    pub safety_m: f64,
    /// The route, start first (thick blue; start green, goal red).
    pub path: &'a [[f64; 3]],
    /// The route before post-processing (thin orange in the top view), or empty.
    pub raw_path: &'a [[f64; 3]],
    /// Legend text of `raw_path`.
    pub raw_label: &'a str,
    /// Roadmap or tree edges (faint, top view), or empty.
    pub edges: &'a [([f64; 3], [f64; 3])],
    /// Legend text of `edges` (for example `"PRM roadmap"`).
    pub edges_label: &'a str,
    /// The ground under the route, `[distance along the route (horizontal), altitude]` in
    /// metres, in order (over terrain; empty: flat ground at altitude 0). Drawn filled under
    /// the profile; buildings stand on it.
    pub ground: &'a [[f64; 2]],
    /// The ground around the route (over terrain), drawn as contours in the top view; `None`
    /// for flat ground.
    pub ground_grid: Option<&'a skyplan_map::contour::GroundGrid>,
    /// A flight's track, `[north_m, east_m, alt_m]` (`fly --plot`): drawn thin and dark over
    /// the route in the top view, and in the side profile at the distance along the route of
    /// its nearest point; empty for a plan.
    pub flown: &'a [[f64; 3]],
}

/// The ground's altitude at distance `d_m` along the route (0 without a ground profile).
fn ground_at(ground: &[[f64; 2]], d_m: f64) -> f64 {
    let k = ground.partition_point(|g| g[0] <= d_m);
    match (k.checked_sub(1).and_then(|i| ground.get(i)), ground.get(k)) {
        (Some(a), Some(b)) if b[0] > a[0] => a[1] + (b[1] - a[1]) * (d_m - a[0]) / (b[0] - a[0]),
        (Some(a), _) => a[1],
        (None, Some(b)) => b[1],
        (None, None) => 0.0,
    }
}

/// One column of the side profile: over horizontal distances `from_m..to_m` along the route the
/// tallest building reaches `top_m` (0 where there is none) and the tallest grown box
/// `margin_top_m`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfileColumn {
    /// Start of the run, metres along the route (horizontal).
    pub from_m: f64,
    /// End of the run, metres along the route.
    pub to_m: f64,
    /// Highest roof under the run, metres (0: open ground).
    pub top_m: f64,
    /// Highest roof + margin of any box whose footprint grown by the margin is under the run.
    pub margin_top_m: f64,
}

/// Samples the buildings under a route every `step_m` of horizontal distance and merges equal
/// neighbours into columns. Returns the columns and the route's horizontal length.
///
/// ```
/// use skyplan_map::colliders::ObstacleBox;
/// let b = ObstacleBox { north_m: 50.0, east_m: 0.0, up_m: 10.0, half_north_m: 5.0, half_east_m: 5.0, half_up_m: 10.0 };
/// let (cols, len) = skyplan_plot::profile_columns(&[b], 2.0, &[[0.0, 0.0, 5.0], [100.0, 0.0, 5.0]], 1.0);
/// assert_eq!(len, 100.0);
/// let roof: Vec<_> = cols.iter().filter(|c| c.top_m > 0.0).collect();
/// assert_eq!((roof[0].top_m, roof[0].margin_top_m), (20.0, 22.0));
/// assert!(roof[0].from_m >= 44.0 && roof[0].to_m <= 56.0);
/// ```
pub fn profile_columns(
    obstacles: &[ObstacleBox],
    safety_m: f64,
    path: &[[f64; 3]],
    step_m: f64,
) -> (Vec<ProfileColumn>, f64) {
    let total_m: f64 = path
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    let mut cols: Vec<ProfileColumn> = Vec::new();
    if path.len() < 2 || step_m.is_nan() || step_m <= 0.0 || total_m <= 0.0 {
        return (cols, total_m);
    }
    // Only boxes near the route matter.
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in path {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let near: Vec<&ObstacleBox> = obstacles
        .iter()
        .filter(|b| {
            let (b_lo, b_hi) = b.grown(safety_m);
            b_hi[0] >= lo[0] && b_lo[0] <= hi[0] && b_hi[1] >= lo[1] && b_lo[1] <= hi[1]
        })
        .collect();
    let n = ((total_m / step_m).ceil() as usize).max(1);
    let ds = total_m / n as f64;
    let mut seg = 0usize;
    let mut seg_start_m = 0.0;
    for s in 0..n {
        let d = (s as f64 + 0.5) * ds;
        // Advance to the segment holding distance d.
        let seg_len = |k: usize| (path[k + 1][0] - path[k][0]).hypot(path[k + 1][1] - path[k][1]);
        while seg + 1 < path.len() - 1 && seg_start_m + seg_len(seg) < d {
            seg_start_m += seg_len(seg);
            seg += 1;
        }
        let len = seg_len(seg);
        let t = if len > 0.0 {
            ((d - seg_start_m) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (path[seg], path[seg + 1]);
        let p = [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
        let (mut top, mut margin_top) = (0.0_f64, 0.0_f64);
        for o in &near {
            let dn = (p[0] - o.north_m).abs();
            let de = (p[1] - o.east_m).abs();
            if dn <= o.half_north_m + safety_m && de <= o.half_east_m + safety_m {
                margin_top = margin_top.max(o.top_m() + safety_m);
                if dn <= o.half_north_m && de <= o.half_east_m {
                    top = top.max(o.top_m());
                }
            }
        }
        let (from_m, to_m) = (s as f64 * ds, (s + 1) as f64 * ds);
        match cols.last_mut() {
            Some(c) if c.top_m == top && c.margin_top_m == margin_top => c.to_m = to_m,
            _ => cols.push(ProfileColumn {
                from_m,
                to_m,
                top_m: top,
                margin_top_m: margin_top,
            }),
        }
    }
    (cols, total_m)
}

/// Renders the top view and the side profile side by side, as PNG or SVG bytes.
///
/// ```
/// use skyplan_map::colliders::ObstacleBox;
/// use skyplan_plot::{PlotFormat, Scene3d, render_plan3d};
/// let b = ObstacleBox { north_m: 50.0, east_m: 0.0, up_m: 10.0, half_north_m: 5.0, half_east_m: 5.0, half_up_m: 10.0 };
/// let path = [[0.0, 0.0, 5.0], [40.0, 0.0, 25.0], [60.0, 0.0, 25.0], [100.0, 0.0, 5.0]];
/// let scene = Scene3d { title: "over the roof".into(), obstacles: &[b], safety_m: 2.0, path: &path,
///                       raw_path: &[], raw_label: "", edges: &[], edges_label: "", ground: &[],
///                       ground_grid: None, flown: &[] };
/// let png = render_plan3d(&scene, PlotFormat::Png, 1000, 600)?;
/// assert_eq!(&png[1..4], b"PNG");
/// let svg = String::from_utf8(render_plan3d(&scene, PlotFormat::Svg, 1000, 600)?)?;
/// assert!(svg.contains("ALTITUDE (m)") && svg.contains("NORTH (m)"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn render_plan3d(
    scene: &Scene3d,
    format: PlotFormat,
    width_px: u32,
    height_px: u32,
) -> Result<Vec<u8>, PlotError> {
    render_plan3d_traced(scene, None, format, width_px, height_px)
}

/// [`render_plan3d`], with a trajectory: its curve coloured by speed in the top view and its
/// scale in the legend, and a strip of speed and acceleration against time under the picture
/// (which grows by the strip's height).
pub(crate) fn render_plan3d_traced(
    scene: &Scene3d,
    trace: Option<&SpeedTrace>,
    format: PlotFormat,
    width_px: u32,
    map_height_px: u32,
) -> Result<Vec<u8>, PlotError> {
    let height_px = map_height_px + trace.map_or(0, |_| crate::trajectory::panel_height(width_px));
    for s in [width_px, map_height_px, height_px] {
        if !(MIN_SIZE_PX..=MAX_SIZE_PX).contains(&s) {
            return Err(PlotError::BadSize {
                width: width_px,
                height: height_px,
            });
        }
    }
    if scene.path.len() < 2 {
        return Err(PlotError::BadScene {
            what: "a 3D route needs at least two points",
        });
    }
    let finite = |p: &[f64; 3]| p.iter().all(|v| v.is_finite());
    if !scene.path.iter().all(finite) || !scene.raw_path.iter().all(finite) {
        return Err(PlotError::BadScene {
            what: "a route point is not finite",
        });
    }
    ensure_font()?;
    match format {
        PlotFormat::Png => {
            let mut rgb = vec![255_u8; width_px as usize * height_px as usize * 3];
            {
                let backend = BitMapBackend::<plotters::backend::RGBPixel>::with_buffer_and_format(
                    &mut rgb,
                    (width_px, height_px),
                )
                .map_err(err)?;
                let root = backend.into_drawing_area();
                draw_whole(&root, scene, trace, TextMode::Glyphs, map_height_px)?;
                root.present().map_err(err)?;
            }
            let mut out = Vec::new();
            let mut encoder = png::Encoder::new(&mut out, width_px, height_px);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            let enc = |e: png::EncodingError| PlotError::Encode(e.to_string());
            let mut writer = encoder.write_header().map_err(enc)?;
            writer.write_image_data(&rgb).map_err(enc)?;
            writer.finish().map_err(enc)?;
            Ok(out)
        }
        PlotFormat::Svg => {
            let mut svg = String::new();
            {
                let root =
                    SVGBackend::with_string(&mut svg, (width_px, height_px)).into_drawing_area();
                draw_whole(&root, scene, trace, TextMode::Strings, map_height_px)?;
                root.present().map_err(err)?;
            }
            Ok(svg.into_bytes())
        }
    }
}

/// The picture, and with a trace the time panels under its top `map_height_px` pixels.
fn draw_whole<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene3d,
    trace: Option<&SpeedTrace>,
    mode: TextMode,
    map_height_px: u32,
) -> Result<(), PlotError> {
    match trace {
        None => draw3d(root, scene, mode, None),
        Some(trace) => {
            let (top, strip) = root.split_vertically(map_height_px);
            draw3d(&top, scene, mode, Some(trace))?;
            let (w, h) = top.dim_in_pixel();
            let font = (f64::from(h.min(w)) / 50.0).clamp(10.0, 28.0);
            crate::trajectory::draw_panels(&strip, trace, mode, font)
        }
    }
}

fn err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// A 1-2-5 step giving about `n` intervals over `span`.
fn nice_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-9);
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * p)
}

fn ticks(lo: f64, hi: f64, n: f64) -> Vec<f64> {
    let s = nice_step(hi - lo, n);
    let mut v = (lo / s).ceil() * s;
    let mut out = Vec::new();
    while v <= hi + 1e-9 {
        out.push(if v.abs() < 1e-9 { 0.0 } else { v });
        v += s;
    }
    out
}

/// A panel: a pixel rectangle showing `x` and `y` ranges.
pub(crate) struct Panel {
    pub(crate) x0: i32,
    pub(crate) y0: i32,
    pub(crate) w: i32,
    pub(crate) h: i32,
    pub(crate) xr: (f64, f64),
    pub(crate) yr: (f64, f64),
}

impl Panel {
    pub(crate) fn px(&self, x: f64, y: f64) -> (i32, i32) {
        let fx = (x - self.xr.0) / (self.xr.1 - self.xr.0);
        let fy = (y - self.yr.0) / (self.yr.1 - self.yr.0);
        (
            self.x0 + (fx * f64::from(self.w)).round() as i32,
            self.y0 + self.h - (fy * f64::from(self.h)).round() as i32,
        )
    }

    /// Frame, grid lines, ticks and the axis titles.
    pub(crate) fn axes<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
        font: f64,
        (x_title, y_title): (&str, &str),
    ) -> Result<(), PlotError> {
        let (x1, y1) = (self.x0 + self.w, self.y0 + self.h);
        let tick = (font * 0.45).round() as i32;
        for x in ticks(self.xr.0, self.xr.1, f64::from(self.w) / (font * 6.0)) {
            let (px, _) = self.px(x, self.yr.0);
            let at = [(px, y1), (px, y1 + tick), (px, y1 + tick + 3)];
            let text = format!("{x:.0}");
            let anchor = (HPos::Center, VAlign::Top);
            draw_tick(root, mode, (at, FRAME_COLOR), (&text, font * 0.85), anchor)?;
        }
        for y in ticks(self.yr.0, self.yr.1, f64::from(self.h) / (font * 3.0)) {
            let (_, py) = self.px(self.xr.0, y);
            let at = [
                (self.x0 - tick, py),
                (self.x0, py),
                (self.x0 - tick - 4, py),
            ];
            let text = format!("{y:.0}");
            let anchor = (HPos::Right, VAlign::Middle);
            draw_tick(root, mode, (at, FRAME_COLOR), (&text, font * 0.85), anchor)?;
        }
        root.draw(&Rectangle::new([(self.x0, self.y0), (x1, y1)], FRAME_COLOR))
            .map_err(err)?;
        draw_label(
            root,
            mode,
            &Label {
                text: x_title,
                size: font,
                at: (self.x0 + self.w / 2, y1 + tick + (2.4 * font) as i32 + 4),
                h: HPos::Center,
                v: VAlign::Baseline,
                vertical: false,
            },
        )?;
        draw_label(
            root,
            mode,
            &Label {
                text: y_title,
                size: font,
                at: (self.x0 - tick - (3.2 * font) as i32, self.y0 + self.h / 2),
                h: HPos::Center,
                v: VAlign::Baseline,
                vertical: true,
            },
        )
    }

    pub(crate) fn grid<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        font: f64,
    ) -> Result<(), PlotError> {
        let (x1, y1) = (self.x0 + self.w, self.y0 + self.h);
        for x in ticks(self.xr.0, self.xr.1, f64::from(self.w) / (font * 6.0)) {
            let (px, _) = self.px(x, self.yr.0);
            root.draw(&PathElement::new(vec![(px, self.y0), (px, y1)], GRID_COLOR))
                .map_err(err)?;
        }
        for y in ticks(self.yr.0, self.yr.1, f64::from(self.h) / (font * 3.0)) {
            let (_, py) = self.px(self.xr.0, y);
            root.draw(&PathElement::new(vec![(self.x0, py), (x1, py)], GRID_COLOR))
                .map_err(err)?;
        }
        Ok(())
    }
}

/// Building shade by height: light grey-blue (low) to near black (tall).
fn building_color(top_m: f64, tallest_m: f64) -> RGBColor {
    let f = (top_m / tallest_m.max(1.0)).clamp(0.0, 1.0).sqrt();
    let lerp = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    RGBColor(lerp(178.0, 38.0), lerp(184.0, 42.0), lerp(196.0, 52.0))
}

/// What every part of the 3D picture is scaled by: the text mode, the font size and the
/// stroke scale.
#[derive(Clone, Copy)]
struct Look {
    mode: TextMode,
    font: f64,
    /// Stroke widths are given for an 18 px font and scaled by this.
    k: f64,
}

impl Look {
    /// A stroke width for an 18 px font, scaled to this picture's font (at least 1 px).
    fn stroke(&self, v: f64) -> u32 {
        (v * self.k).round().max(1.0) as u32
    }
}

fn draw3d<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene3d,
    mode: TextMode,
    trace: Option<&SpeedTrace>,
) -> Result<(), PlotError> {
    root.fill(&WHITE).map_err(err)?;
    let (w, h) = root.dim_in_pixel();
    let (w, h) = (w as i32, h as i32);
    let font = (f64::from(h.min(w)) / 50.0).clamp(10.0, 28.0);
    let look = Look {
        mode,
        font,
        k: font / 18.0,
    };
    let tallest = scene
        .obstacles
        .iter()
        .map(ObstacleBox::top_m)
        .fold(1.0, f64::max);
    let top = top_panel(scene, (w, h), font);
    draw_top_view(root, scene, &top, tallest, look, trace)?;
    let prof = draw_side_profile(root, scene, &top, w, tallest, look)?;
    draw_legend3d(root, scene, &prof, tallest, look, trace)?;
    draw_label(
        root,
        mode,
        &Label {
            text: &scene.title,
            size: font * 1.15,
            at: (w / 2, (0.7 * font) as i32),
            h: HPos::Center,
            v: VAlign::Top,
            vertical: false,
        },
    )
}

/// The square the top view shows around a route: its centre `[north, east]` and side, metres.
pub(crate) fn top_view_square(path: &[[f64; 3]], raw_path: &[[f64; 3]]) -> ([f64; 2], f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in path.iter().chain(raw_path) {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let side = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(20.0) * 1.2 + 40.0;
    ([(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0], side)
}

/// Contour levels of the ground: about a dozen, on a 1-2-5 step.
fn contour_levels(g: &skyplan_map::contour::GroundGrid) -> Vec<f64> {
    let known = g.values.iter().filter(|v| v.is_finite());
    let lo = known.clone().fold(f64::INFINITY, |a, &b| a.min(b));
    let hi = known.fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    skyplan_map::contour::contour_levels(lo, hi, 12.0).1
}

/// The top view's panel: the route's surroundings, equal scales, square, on the left.
fn top_panel(scene: &Scene3d, (w, h): (i32, i32), font: f64) -> Panel {
    let (centre, side) = top_view_square(scene.path, scene.raw_path);
    let title_h = (2.6 * font) as i32;
    let left = (4.6 * font) as i32;
    let bottom = (3.6 * font) as i32;
    let size = (h - title_h - bottom - (0.6 * font) as i32).min(w * 11 / 20 - left);
    Panel {
        x0: left,
        y0: title_h,
        w: size,
        h: size,
        xr: (centre[1] - side / 2.0, centre[1] + side / 2.0),
        yr: (centre[0] - side / 2.0, centre[0] + side / 2.0),
    }
}

/// The top view: buildings shaded by height (tallest drawn last), the roadmap's edges, the raw
/// and the final route, a trajectory over it, the axes and the start and goal markers.
fn draw_top_view<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene3d,
    top: &Panel,
    tallest: f64,
    look: Look,
    trace: Option<&SpeedTrace>,
) -> Result<(), PlotError> {
    top.grid(root, look.font)?;
    {
        let area = root
            .clone()
            .shrink((top.x0, top.y0), (top.w as u32, top.h as u32));
        let mut chart = ChartBuilder::on(&area)
            .build_cartesian_2d(top.xr.0..top.xr.1, top.yr.0..top.yr.1)
            .map_err(err)?;
        if let Some(g) = scene.ground_grid {
            for level in contour_levels(g) {
                chart
                    .draw_series(
                        skyplan_map::contour::contour_segments(g, level)
                            .into_iter()
                            .map(|s| {
                                PathElement::new(
                                    vec![(s[0][1], s[0][0]), (s[1][1], s[1][0])],
                                    CONTOUR_COLOR.stroke_width(1),
                                )
                            }),
                    )
                    .map_err(err)?;
            }
        }
        let mut boxes: Vec<&ObstacleBox> = scene.obstacles.iter().collect();
        boxes.sort_by(|a, b| a.top_m().total_cmp(&b.top_m()));
        chart
            .draw_series(boxes.iter().map(|o| {
                Rectangle::new(
                    [
                        (o.east_m - o.half_east_m, o.north_m + o.half_north_m),
                        (o.east_m + o.half_east_m, o.north_m - o.half_north_m),
                    ],
                    building_color(o.top_m(), tallest).filled(),
                )
            }))
            .map_err(err)?;
        let en = |p: &[f64; 3]| (p[1], p[0]);
        chart
            .draw_series(
                scene
                    .edges
                    .iter()
                    .map(|(a, b)| PathElement::new(vec![en(a), en(b)], EDGE_COLOR.stroke_width(1))),
            )
            .map_err(err)?;
        if scene.raw_path.len() > 1 {
            chart
                .draw_series(LineSeries::new(
                    scene.raw_path.iter().map(en),
                    RAW_COLOR.stroke_width(look.stroke(2.0)),
                ))
                .map_err(err)?;
        }
        chart
            .draw_series(LineSeries::new(
                scene.path.iter().map(en),
                ROUTE_COLOR.stroke_width(look.stroke(3.5)),
            ))
            .map_err(err)?;
        if scene.flown.len() > 1 {
            chart
                .draw_series(LineSeries::new(
                    scene.flown.iter().map(en),
                    FLOWN_COLOR.stroke_width(look.stroke(1.5)),
                ))
                .map_err(err)?;
        }
        if let Some(trace) = trace {
            crate::trajectory::draw_on_map(&mut chart, trace, look.stroke(3.0))?;
        }
    }
    top.axes(root, look.mode, look.font, ("EAST (m)", "NORTH (m)"))?;
    let r = look.stroke(7.0);
    let first = scene.path[0];
    let last = scene.path[scene.path.len() - 1];
    marker(root, top.px(first[1], first[0]), r, START_COLOR)?;
    marker(root, top.px(last[1], last[0]), r, GOAL_COLOR)
}

/// The side profile right of the top view: the buildings and their margins under the route,
/// the route's altitude against horizontal distance, and the axes. Returns its panel.
fn draw_side_profile<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene3d,
    top: &Panel,
    width_px: i32,
    tallest: f64,
    look: Look,
) -> Result<Panel, PlotError> {
    let font = look.font;
    let horizontal_m: f64 = scene
        .path
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    let (cols, total_m) = profile_columns(
        scene.obstacles,
        scene.safety_m,
        scene.path,
        (horizontal_m / 1500.0).max(0.05),
    );
    let base = |c: &ProfileColumn| ground_at(scene.ground, (c.from_m + c.to_m) / 2.0);
    let max_alt = scene
        .path
        .iter()
        .map(|p| p[2])
        .chain(cols.iter().map(|c| c.margin_top_m + base(c)))
        .chain(scene.ground.iter().map(|g| g[1]))
        .fold(10.0, f64::max);
    let min_alt = scene.ground.iter().map(|g| g[1]).fold(0.0, f64::min);
    let pad = 0.08 * (max_alt - min_alt);
    let px0 = top.x0 + top.w + (6.0 * font) as i32;
    let prof = Panel {
        x0: px0,
        y0: top.y0,
        w: width_px - px0 - (1.4 * font) as i32,
        h: top.w * 11 / 20,
        xr: (-0.02 * total_m.max(1.0), 1.02 * total_m.max(1.0)),
        yr: if scene.ground.is_empty() {
            (0.0, max_alt * 1.15)
        } else {
            (min_alt - pad, max_alt + pad)
        },
    };
    prof.grid(root, font)?;
    draw_ground(root, &prof, scene.ground)?;
    draw_columns(root, &prof, &cols, tallest, scene.ground)?;
    draw_profile_route(root, &prof, scene.path, look)?;
    if scene.flown.len() > 1 {
        let pts: Vec<(i32, i32)> = (scene.flown.iter())
            .map(|p| prof.px(along_route_m(scene.path, [p[0], p[1]]), p[2]))
            .collect();
        root.draw(&PathElement::new(
            pts,
            FLOWN_COLOR.stroke_width(look.stroke(1.5)),
        ))
        .map_err(err)?;
    }
    prof.axes(
        root,
        look.mode,
        font,
        ("DISTANCE ALONG THE ROUTE (m)", "ALTITUDE (m)"),
    )?;
    Ok(prof)
}

/// The horizontal distance along `path` of its point nearest to `ne` (north, east).
pub(crate) fn along_route_m(path: &[[f64; 3]], ne: [f64; 2]) -> f64 {
    let (mut best, mut best_d2, mut at) = (0.0, f64::INFINITY, 0.0);
    for w in path.windows(2) {
        let (a, b) = ([w[0][0], w[0][1]], [w[1][0], w[1][1]]);
        let (dn, de) = (b[0] - a[0], b[1] - a[1]);
        let len2 = dn * dn + de * de;
        let t = if len2 > 0.0 {
            (((ne[0] - a[0]) * dn + (ne[1] - a[1]) * de) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (pn, pe) = (a[0] + t * dn - ne[0], a[1] + t * de - ne[1]);
        let d2 = pn * pn + pe * pe;
        if d2 < best_d2 {
            (best_d2, best) = (d2, at + t * len2.sqrt());
        }
        at += len2.sqrt();
    }
    best
}

/// The ground under the route, filled down to the panel's floor.
fn draw_ground<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    prof: &Panel,
    ground: &[[f64; 2]],
) -> Result<(), PlotError> {
    let (Some(first), Some(last)) = (ground.first(), ground.last()) else {
        return Ok(());
    };
    let floor = prof.yr.0;
    let mut pts: Vec<(i32, i32)> = vec![prof.px(first[0], floor)];
    pts.extend(ground.iter().map(|g| prof.px(g[0], g[1])));
    pts.push(prof.px(last[0], floor));
    root.draw(&Polygon::new(pts, GROUND_COLOR.filled()))
        .map_err(err)?;
    let line: Vec<(i32, i32)> = ground.iter().map(|g| prof.px(g[0], g[1])).collect();
    root.draw(&PathElement::new(line, GROUND_LINE.stroke_width(2)))
        .map_err(err)?;
    Ok(())
}

/// The profile's columns: every margin first, then every building over it (standing on the
/// ground where there is one).
fn draw_columns<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    prof: &Panel,
    cols: &[ProfileColumn],
    tallest: f64,
    ground: &[[f64; 2]],
) -> Result<(), PlotError> {
    for (color, top_of) in [
        (
            MARGIN_COLOR,
            (|c: &ProfileColumn| c.margin_top_m) as fn(&ProfileColumn) -> f64,
        ),
        (RGBColor(0, 0, 0), |c: &ProfileColumn| c.top_m),
    ] {
        for c in cols {
            let t = top_of(c);
            if t <= 0.0 {
                continue;
            }
            let fill = if color == MARGIN_COLOR {
                MARGIN_COLOR
            } else {
                building_color(t, tallest)
            };
            let g = ground_at(ground, (c.from_m + c.to_m) / 2.0);
            let a = prof.px(c.from_m, g);
            let b = prof.px(c.to_m, (g + t).min(prof.yr.1));
            root.draw(&Rectangle::new(
                [(a.0, b.1), (b.0.max(a.0 + 1), a.1)],
                fill.filled(),
            ))
            .map_err(err)?;
        }
    }
    Ok(())
}

/// The route against horizontal distance: its line, a ring at each inner waypoint, the start
/// and goal markers.
fn draw_profile_route<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    prof: &Panel,
    path: &[[f64; 3]],
    look: Look,
) -> Result<(), PlotError> {
    let mut d = 0.0;
    let mut pts = Vec::with_capacity(path.len());
    for (i, p) in path.iter().enumerate() {
        if i > 0 {
            let q = path[i - 1];
            d += (p[0] - q[0]).hypot(p[1] - q[1]);
        }
        pts.push(prof.px(d, p[2]));
    }
    root.draw(&PathElement::new(
        pts.clone(),
        ROUTE_COLOR.stroke_width(look.stroke(3.5)),
    ))
    .map_err(err)?;
    for &p in &pts[1..pts.len() - 1] {
        root.draw(&Circle::new(p, look.stroke(4.0), ROUTE_COLOR.filled()))
            .map_err(err)?;
        root.draw(&Circle::new(p, look.stroke(2.0), WHITE.filled()))
            .map_err(err)?;
    }
    let r = look.stroke(7.0);
    marker(root, pts[0], r, START_COLOR)?;
    marker(root, pts[pts.len() - 1], r, GOAL_COLOR)
}

/// The legend under the profile: route, raw route, markers, three building heights, the
/// margin and the roadmap's edges.
fn draw_legend3d<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene3d,
    prof: &Panel,
    tallest: f64,
    look: Look,
    trace: Option<&SpeedTrace>,
) -> Result<(), PlotError> {
    let font = look.font;
    let trace_text = trace.map(SpeedTrace::legend_text);
    let mut entries: Vec<(&str, Swatch)> = vec![
        ("route", Swatch::Line(ROUTE_COLOR, 3.5)),
        ("start", Swatch::Dot(START_COLOR)),
        ("goal", Swatch::Dot(GOAL_COLOR)),
    ];
    if scene.flown.len() > 1 {
        entries.push(("flown track", Swatch::Line(FLOWN_COLOR, 1.5)));
    }
    let heights: Vec<(String, f64)> = [0.1, 0.35, 1.0]
        .iter()
        .map(|f| {
            let t = (tallest * f / 5.0).round().max(1.0) * 5.0;
            (format!("building {t:.0} m tall"), t)
        })
        .collect();
    if !scene.obstacles.is_empty() {
        for (text, t) in &heights {
            entries.push((text, Swatch::Fill(building_color(*t, tallest))));
        }
        entries.push(("safety margin (profile)", Swatch::Fill(MARGIN_COLOR)));
    }
    if !scene.ground.is_empty() {
        entries.push(("ground (DEM)", Swatch::Fill(GROUND_COLOR)));
    }
    let contour_text = scene.ground_grid.and_then(|g| {
        let levels = contour_levels(g);
        (levels.len() > 1).then(|| {
            format!(
                "ground contours every {} m (top view)",
                levels[1] - levels[0]
            )
        })
    });
    if let Some(text) = &contour_text {
        entries.push((text, Swatch::Line(CONTOUR_COLOR, 1.0)));
    }
    if scene.raw_path.len() > 1 && !scene.raw_label.is_empty() {
        entries.insert(1, (scene.raw_label, Swatch::Line(RAW_COLOR, 2.0)));
    }
    if !scene.edges.is_empty() && !scene.edges_label.is_empty() {
        entries.push((scene.edges_label, Swatch::Line(EDGE_COLOR, 1.0)));
    }
    if let (Some(text), Some(trace)) = (&trace_text, trace) {
        entries.insert(1, (text, Swatch::Speed(trace)));
    }
    let r = look.stroke(7.0);
    let line_h = (1.7 * font) as i32;
    let lx = prof.x0;
    let mut ly = prof.y0 + prof.h + (5.2 * font) as i32;
    let sw = (2.4 * font) as i32;
    for (text, swatch) in entries {
        match swatch {
            Swatch::Line(c, width) => root.draw(&PathElement::new(
                vec![(lx, ly), (lx + sw, ly)],
                c.stroke_width(look.stroke(width)),
            )),
            Swatch::Dot(c) => {
                marker(root, (lx + sw / 2, ly), r, c)?;
                Ok(())
            }
            Swatch::Speed(trace) => {
                let hs = (0.3 * font) as i32;
                root.draw(&Rectangle::new(
                    [(lx, ly - hs - 1), (lx + sw, ly + hs + 1)],
                    FRAME_COLOR.filled(),
                ))
                .map_err(err)?;
                crate::trajectory::draw_scale_sample(root, trace, (lx + 1, ly), (sw - 1, hs))?;
                Ok(())
            }
            Swatch::Fill(c) => {
                let hs = (0.45 * font) as i32;
                root.draw(&Rectangle::new(
                    [(lx, ly - hs), (lx + sw, ly + hs)],
                    c.filled(),
                ))
            }
        }
        .map_err(err)?;
        draw_label(
            root,
            look.mode,
            &Label {
                text,
                size: font * 0.9,
                at: (lx + sw + (0.7 * font) as i32, ly),
                h: HPos::Left,
                v: VAlign::Middle,
                vertical: false,
            },
        )?;
        ly += line_h;
    }
    Ok(())
}

enum Swatch<'a> {
    /// A trajectory's speed scale.
    Speed(&'a SpeedTrace),
    Line(RGBColor, f64),
    Dot(RGBColor),
    Fill(RGBColor),
}

fn marker<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    r: u32,
    color: RGBColor,
) -> Result<(), PlotError> {
    root.draw(&Circle::new(at, r, FRAME_COLOR.filled()))
        .map_err(err)?;
    root.draw(&Circle::new(at, r.saturating_sub(2).max(1), color.filled()))
        .map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn along_route_is_the_distance_to_the_nearest_point_of_the_route() {
        let path = [[0.0, 0.0, 5.0], [100.0, 0.0, 5.0], [100.0, 50.0, 5.0]];
        assert_eq!(along_route_m(&path, [40.0, 7.0]), 40.0);
        assert_eq!(along_route_m(&path, [90.0, 30.0]), 130.0);
        assert_eq!(along_route_m(&path, [-20.0, 0.0]), 0.0);
        assert_eq!(along_route_m(&path, [130.0, 80.0]), 150.0);
    }

    /// The flown track is drawn where it was flown: a track 20 m east of the route is dark in
    /// the top view where the route's picture alone is not.
    #[test]
    fn a_flown_track_is_drawn_beside_the_route_in_the_top_view() {
        let path = [[0.0, 0.0, 10.0], [100.0, 0.0, 10.0]];
        let flown = [[0.0, 20.0, 10.0], [100.0, 20.0, 10.0]];
        let scene = |flown: &'static [[f64; 3]]| Scene3d {
            title: "t".into(),
            obstacles: &[],
            safety_m: 2.0,
            path: Box::leak(Box::new(path)),
            raw_path: &[],
            raw_label: "",
            edges: &[],
            edges_label: "",
            ground: &[],
            ground_grid: None,
            flown,
        };
        let (w, h) = (1000u32, 600u32);
        let pixel = |s: &Scene3d| {
            let png = render_plan3d_traced(s, None, PlotFormat::Png, w, h).unwrap();
            let mut reader = png::Decoder::new(std::io::Cursor::new(png))
                .read_info()
                .unwrap();
            let mut buf = vec![0; reader.output_buffer_size().unwrap()];
            reader.next_frame(&mut buf).unwrap();
            let font = (f64::from(h.min(w)) / 50.0).clamp(10.0, 28.0);
            let top = top_panel(s, (w as i32, h as i32), font);
            // The darkest of the pixels within 2 of where the track's middle is.
            let (x, y) = top.px(20.0, 50.3);
            (x - 2..=x + 2)
                .map(|x| {
                    let i = (y as usize * w as usize + x as usize) * 3;
                    u16::from(buf[i]) + u16::from(buf[i + 1]) + u16::from(buf[i + 2])
                })
                .min()
                .unwrap()
        };
        let with = pixel(&scene(Box::leak(Box::new(flown))));
        let without = pixel(&scene(&[]));
        assert!(with < 3 * 80, "{with}");
        assert!(without > 3 * 200, "{without}");
    }
}
