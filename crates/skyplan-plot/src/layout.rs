//! Where everything goes: plot area with equal scales, axis labels, ticks, title and legend.

use crate::text::{CAP, DESCENT, ensure_font, text_width};
use crate::{MAX_SIZE_PX, MIN_SIZE_PX, PlotError, Scene};

/// Where things go on a picture of a given size: the plot area and its world extent.
///
/// The plot area has equal scales on both axes (a metre north is as long as a metre east).
/// [`PlotLayout::pixel_of_ne`] maps a world point to the pixel the renderer draws it at.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotLayout {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Plot area: left, top, width, height in pixels.
    pub(crate) plot: (i32, i32, u32, u32),
    pub(crate) east_m: (f64, f64),
    pub(crate) north_m: (f64, f64),
    pub(crate) fonts: Fonts,
    pub(crate) x_ticks: Vec<f64>,
    pub(crate) y_ticks: Vec<f64>,
    pub(crate) decimals: usize,
    /// Tick mark length and the gap between a tick and its label, pixels.
    pub(crate) tick_len: i32,
    pub(crate) tick_gap: i32,
    /// Baseline of the x axis title (y) and of the rotated y axis title (x), pixels.
    pub(crate) x_desc_baseline: i32,
    pub(crate) y_desc_baseline: i32,
    /// Top of the capitals of the title, pixels.
    pub(crate) title_top: i32,
    /// Centre of the title, pixels.
    pub(crate) title_x: i32,
    /// The title as drawn (shortened when the picture is too narrow for it).
    pub(crate) title: String,
    pub(crate) legend: LegendLayout,
}

/// Font sizes (plotters sizes, pixels) and the overall scale `k` (1 for an 800 px picture).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Fonts {
    pub k: f64,
    pub title: f64,
    pub desc: f64,
    pub tick: f64,
    pub legend: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LegendLayout {
    pub entries: Vec<LegendEntry>,
    /// Left end and vertical centre of each entry's sample, pixels.
    pub origins: Vec<(i32, i32)>,
    /// Box: left, top, width, height (all zero without entries).
    pub frame: (i32, i32, u32, u32),
    pub sample_w: i32,
    pub text_gap: i32,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LegendEntry {
    pub kind: LegendKind,
    pub text: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LegendKind {
    CSpace,
    Obstacle,
    Graph,
    Connector,
    Raw,
    Pruned,
    Start,
    Goal,
    Hidden,
    Learned,
    Replanned,
    Track,
    /// A fleet's accepted routes (a colour each) and refused ones (grey).
    Fleet,
    FleetRefused,
    /// Heat maps: blocked cells (drawn black), a colour of the scale, cells without a value,
    /// and the scale's caption (no sample).
    HeatBlocked,
    Heat(u8),
    NoValue,
    Caption,
    /// A trajectory's speed scale (a gradient sample).
    SpeedScale,
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
        (self.east_m.1 - self.east_m.0) / f64::from(self.plot.2 - 1)
    }

    /// The east values with a labelled tick, metres.
    pub fn east_ticks_m(&self) -> &[f64] {
        &self.x_ticks
    }

    /// The north values with a labelled tick, metres.
    pub fn north_ticks_m(&self) -> &[f64] {
        &self.y_ticks
    }

    /// The pixel (x to the right, y down) at which a local (north, east) point is drawn.
    ///
    /// ```
    /// use skyplan_cspace::Grid2;
    /// use skyplan_plot::{Scene, layout};
    /// let grid = Grid2::from_ascii("....\n....")?;
    /// let scene = Scene {
    ///     title: String::new(), grid: &grid, obstacles: &[], footprints: &[], raw_path_ne: &[],
    ///     pruned_path_ne: &[], start_ne: None, goal_ne: None, graph_ne: &[], connectors_ne: &[], flight: None, zones: &[], fleet: &[],
    /// };
    /// let l = layout(&scene, 800, 600)?;
    /// let (x0, y0, _w, h) = l.plot_area();
    /// // The south-west corner of the grid is the bottom-left pixel of the plot area.
    /// assert_eq!(l.pixel_of_ne(0.0, 0.0), (x0, y0 + h as i32 - 1));
    /// // North is up.
    /// assert!(l.pixel_of_ne(2.0, 0.0).1 < l.pixel_of_ne(0.0, 0.0).1);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn pixel_of_ne(&self, north_m: f64, east_m: f64) -> (i32, i32) {
        // The arithmetic of plotters' linear f64 axes, which draw the data.
        let (x0, y0, w, h) = self.plot;
        let lx = (east_m - self.east_m.0) / (self.east_m.1 - self.east_m.0);
        let ly = (north_m - self.north_m.0) / (self.north_m.1 - self.north_m.0);
        let x = x0 + (f64::from(w - 1) * lx + 1e-3).floor() as i32;
        let y = y0 + h as i32 - 1 - (f64::from(h - 1) * ly + 1e-3).floor() as i32;
        (x, y)
    }

    /// A tick value as its label.
    pub(crate) fn tick_label(&self, v: f64) -> String {
        fmt_metres(v, self.decimals)
    }
}

/// Decimals needed to tell ticks `step` apart.
fn decimals_for_step(step: f64) -> usize {
    if step >= 1.0 {
        0
    } else {
        ((-step.log10()) - 1e-9).ceil().clamp(0.0, 9.0) as usize
    }
}

pub(crate) fn fmt_metres(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    // No "-0".
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// The smallest 1, 2 or 5 × 10ⁿ at least `raw`.
fn nice_step(raw: f64) -> f64 {
    let p = 10_f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|&s| s >= raw * (1.0 - 1e-9))
        .unwrap_or(10.0 * p)
}

/// Multiples of a nice step within `[lo, hi]`, at least `min_m` apart.
fn ticks(lo: f64, hi: f64, min_m: f64) -> (Vec<f64>, f64) {
    let step = nice_step(min_m.max((hi - lo) * 1e-9).max(f64::MIN_POSITIVE));
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    ((first..=last).map(|i| i as f64 * step).collect(), step)
}

/// World extent of a scene: the grid and everything drawn, (east min, east max, north min, north max).
fn world_bounds(scene: &Scene) -> Result<(f64, f64, f64, f64), PlotError> {
    let f = scene.grid.frame();
    if !(f.origin_north_m.is_finite() && f.origin_east_m.is_finite()) {
        return Err(PlotError::BadScene {
            what: "the grid's origin is not finite",
        });
    }
    if !(f.cell_m.is_finite() && f.cell_m > 0.0) {
        return Err(PlotError::BadScene {
            what: "the grid's cell size is not a positive finite number",
        });
    }
    let add = |b: &mut (f64, f64, f64, f64), n: f64, e: f64| {
        *b = (b.0.min(e), b.1.max(e), b.2.min(n), b.3.max(n));
    };
    let mut b = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
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
            return Err(PlotError::BadScene {
                what: "a path point, the start or the goal is not finite",
            });
        }
        outside |= b.0.is_finite() && (e < b.0 || e > b.1 || n < b.2 || n > b.3);
        add(&mut b, n, e);
    }
    for o in scene.obstacles {
        if ![o.north_m, o.east_m, o.half_north_m, o.half_east_m]
            .iter()
            .all(|x| x.is_finite())
        {
            return Err(PlotError::BadScene {
                what: "an obstacle's position or size is not finite",
            });
        }
        if scene.grid.is_empty() {
            add(&mut b, o.north_m - o.half_north_m, o.east_m - o.half_east_m);
            add(&mut b, o.north_m + o.half_north_m, o.east_m + o.half_east_m);
        }
    }
    for f in scene.footprints {
        if !f.rings.iter().flatten().flatten().all(|x| x.is_finite()) {
            return Err(PlotError::BadScene {
                what: "a footprint's vertex is not finite",
            });
        }
        if scene.grid.is_empty() {
            let (lo, hi) = f.bbox_ne();
            add(&mut b, lo[0], lo[1]);
            add(&mut b, hi[0], hi[1]);
        }
    }
    if !b.0.is_finite() {
        b = (0.0, 1.0, 0.0, 1.0);
    }
    // Points beyond the grid, or no grid at all: leave a little room around everything.
    if outside || scene.grid.is_empty() {
        let pad = 0.03 * (b.1 - b.0).max(b.3 - b.2).max(1.0);
        b = (b.0 - pad, b.1 + pad, b.2 - pad, b.3 + pad);
    }
    if b.1 - b.0 < 1e-6 {
        b = (b.0 - 0.5, b.1 + 0.5, b.2, b.3);
    }
    if b.3 - b.2 < 1e-6 {
        b = (b.0, b.1, b.2 - 0.5, b.3 + 0.5);
    }
    Ok(b)
}

fn legend_entries(scene: &Scene) -> Vec<LegendEntry> {
    let mut v = Vec::new();
    // An entry for each layer the picture shows.
    let mut push = |shown: bool, kind, text: String| {
        if shown {
            v.push(LegendEntry { kind, text });
        }
    };
    let blocked = scene.grid.blocked_cells().iter().any(|&b| b);
    push(
        blocked,
        LegendKind::CSpace,
        "obstacle + safety margin".into(),
    );
    let obstacles = !scene.obstacles.is_empty() || !scene.footprints.is_empty();
    push(obstacles, LegendKind::Obstacle, "obstacle".into());
    let points = |n: usize| {
        if n == 1 {
            "1 point".to_string()
        } else {
            format!("{n} points")
        }
    };
    let (graph, connectors) = (scene.graph_ne.len(), scene.connectors_ne.len());
    push(
        graph > 0,
        LegendKind::Graph,
        format!("roadmap ({graph} edges)"),
    );
    let text = format!("connectors ({connectors})");
    push(connectors > 0, LegendKind::Connector, text);
    let (raw, pruned) = (scene.raw_path_ne.len(), scene.pruned_path_ne.len());
    let what = if graph == 0 {
        "grid path"
    } else {
        "graph route"
    };
    push(
        raw > 0,
        LegendKind::Raw,
        format!("{what} ({})", points(raw)),
    );
    let text = format!("waypoints ({})", points(pruned));
    push(pruned > 0, LegendKind::Pruned, text);
    if let Some(f) = scene.flight {
        let (hidden, learned) = (f.hidden.len(), f.learned_ne.len());
        let text = format!("hidden obstacles ({hidden})");
        push(hidden > 0, LegendKind::Hidden, text);
        let text = format!("learned cells ({learned})");
        push(learned > 0, LegendKind::Learned, text);
        let replanned = f.replanned_ne.len();
        let text = format!("replanned routes ({replanned})");
        push(replanned > 0, LegendKind::Replanned, text);
        let track = !f.track_ne.is_empty();
        push(track, LegendKind::Track, "flown track".into());
    }
    let accepted = scene.fleet.iter().filter(|f| f.accepted).count();
    let refused = scene.fleet.len() - accepted;
    let text = format!("accepted flights ({accepted}, a colour each)");
    push(accepted > 0, LegendKind::Fleet, text);
    let text = format!("refused flights ({refused})");
    push(refused > 0, LegendKind::FleetRefused, text);
    push(scene.start_ne.is_some(), LegendKind::Start, "start".into());
    push(scene.goal_ne.is_some(), LegendKind::Goal, "goal".into());
    v
}

#[derive(Clone, Copy, PartialEq)]
enum Place {
    Nowhere,
    Right,
    Below,
}

/// Computes where everything goes on a `width_px` × `height_px` picture of `scene`.
///
/// The renderers use exactly this layout, so [`PlotLayout::pixel_of_ne`] tells where a point
/// of the scene lands on the picture.
pub fn layout(scene: &Scene, width_px: u32, height_px: u32) -> Result<PlotLayout, PlotError> {
    layout_with(scene, width_px, height_px, None)
}

impl Fonts {
    /// The font sizes at scale `k` (1 for an 800 px picture), before the title is fitted.
    fn at_scale(k: f64) -> Self {
        Fonts {
            k,
            title: even(21.0 * k),
            desc: even(16.0 * k),
            tick: even(13.5 * k),
            legend: even(13.5 * k),
        }
    }
}

/// A length in pixels, rounded.
fn px(v: f64) -> i32 {
    v.round() as i32
}

/// A font size rounded to an even number of pixels: plotters' rasteriser then puts every glyph
/// on the same baseline.
fn even(v: f64) -> f64 {
    2.0 * (v / 2.0).round()
}

/// The room the axes take: tick marks, their labels and the axis titles, pixels.
struct AxisRoom {
    /// Width of the widest east tick label.
    widest_x: f64,
    tick_len: i32,
    tick_gap: i32,
    /// From the plot's left edge to the baseline of the (rotated) y axis title.
    y_desc_off: f64,
    /// Width of the y axis labels and title.
    y_label_w: i32,
    /// From the plot's bottom edge to the baseline of the x axis title.
    x_desc_off: f64,
    /// Height of the x axis labels and title.
    x_label_h: i32,
}

/// Room for the widest tick label either axis may need, and for the axis titles.
fn axis_room((e0, e1, n0, n1): (f64, f64, f64, f64), fonts: &Fonts) -> AxisRoom {
    let k = fonts.k;
    let est_decimals = decimals_for_step(nice_step((e1 - e0).min(n1 - n0) / 20.0));
    let widest = |lo: f64, hi: f64| {
        [lo, hi, 0.5 * (lo + hi)]
            .iter()
            .map(|&v| text_width(&fmt_metres(v, est_decimals), fonts.tick))
            .fold(0.0, f64::max)
    };
    let (widest_x, widest_y) = (widest(e0, e1), widest(n0, n1));
    let tick_len = px(5.0 * k);
    let tick_gap = px(4.0 * k);
    let y_desc_off = f64::from(tick_len + tick_gap) + widest_y + 0.6 * fonts.desc;
    let x_desc_off =
        f64::from(tick_len + tick_gap) + CAP * fonts.tick + 0.8 * fonts.desc + CAP * fonts.desc;
    AxisRoom {
        widest_x,
        tick_len,
        tick_gap,
        y_desc_off,
        y_label_w: px(y_desc_off + 0.8 * fonts.desc),
        x_desc_off,
        x_label_h: px(x_desc_off + DESCENT * fonts.desc),
    }
}

/// The title as drawn and its font size: a title wider than `room` pixels is set smaller,
/// down to 10 px, then shortened with an ellipsis.
fn fit_title(title: &str, size: f64, room: f64) -> (String, f64) {
    let mut title = title.to_string();
    let fitted = even(size * room / text_width(&title, size).max(1.0) - 1.0);
    let size = size.min(fitted).max(10.0);
    while !title.is_empty() && text_width(&title, size) > room {
        title.pop();
        while title.ends_with(' ') {
            title.pop();
        }
        if text_width(&format!("{title}…"), size) <= room {
            title.push('…');
            break;
        }
    }
    (title, size)
}

/// The room around the plot area, pixels.
struct Margins {
    /// The picture's width and height.
    wi: i32,
    hi: i32,
    /// Kept clear at the picture's edges.
    outer: i32,
    /// Height of the title.
    title_h: i32,
    /// Width of the y axis labels, height of the x axis labels.
    y_label_w: i32,
    x_label_h: i32,
    /// Right of the plot when no legend is there.
    right_pad: i32,
    /// Between the plot and a legend.
    legend_gap: i32,
}

/// The legend's measures before it is placed: one column beside the plot, or a grid of
/// columns under it.
struct LegendShape {
    entries: Vec<LegendEntry>,
    sample_w: i32,
    text_gap: i32,
    row_h: i32,
    pad: i32,
    /// Between the columns of the grid under the plot.
    entry_sep: i32,
    /// Width and height of the single column.
    column: (i32, i32),
    /// The grid under the plot: its column widths, width and height (`None`: no entries).
    below: Option<(Vec<i32>, i32, i32)>,
    /// A heat map's colour scale reads top to bottom: its legend is a column beside the plot.
    column_only: bool,
}

/// The legend's entries (the heat map's scale after the scene's) and its measures, with a grid
/// under the plot as wide as `room_w` pixels at most.
fn legend_shape(
    scene: &Scene,
    heat_legend: Option<Vec<LegendEntry>>,
    extra: Vec<LegendEntry>,
    fonts: &Fonts,
    room_w: i32,
) -> LegendShape {
    let k = fonts.k;
    let mut entries = legend_entries(scene);
    entries.extend(extra);
    let column_only = heat_legend.is_some();
    if let Some(heat) = heat_legend {
        for e in &mut entries {
            if e.kind == LegendKind::CSpace {
                e.kind = LegendKind::HeatBlocked;
            }
        }
        entries.extend(heat);
    }
    let sample_w = px(32.0 * k);
    let text_gap = px(8.0 * k);
    let row_h = px(1.75 * fonts.legend);
    let pad = px(10.0 * k);
    let entry_w: Vec<i32> = entries
        .iter()
        .map(|e| sample_w + text_gap + text_width(&e.text, fonts.legend).ceil() as i32)
        .collect();
    let n = entries.len() as i32;
    let column = (
        2 * pad + entry_w.iter().copied().max().unwrap_or(0),
        2 * pad + n * row_h - row_h / 3,
    );
    // Under the plot: as many columns as fit across the picture.
    let entry_sep = px(20.0 * k);
    let grid_of = |cols: usize| -> (Vec<i32>, i32, i32) {
        let mut widths = vec![0; cols];
        for (i, w) in entry_w.iter().enumerate() {
            widths[i % cols] = widths[i % cols].max(*w);
        }
        let rows = entry_w.len().div_ceil(cols) as i32;
        let width = 2 * pad + widths.iter().sum::<i32>() + entry_sep * (cols as i32 - 1);
        (widths, width, 2 * pad + rows * row_h - row_h / 3)
    };
    // The fewest rows that fit, then as few columns as those rows need.
    let below = (1..=entries.len())
        .rev()
        .find(|&c| grid_of(c).1 <= room_w)
        .map(|c| grid_of(entries.len().div_ceil(entries.len().div_ceil(c))));
    LegendShape {
        entries,
        sample_w,
        text_gap,
        row_h,
        pad,
        entry_sep,
        column,
        below,
        column_only,
    }
}

/// The scale (pixels per metre) an `aw` × `ah` plot area allows for the spans (0: too small).
fn fit(aw: i32, ah: i32, (espan, nspan): (f64, f64)) -> f64 {
    if aw < 20 || ah < 20 {
        0.0
    } else {
        (f64::from(aw - 1) / espan).min(f64::from(ah - 1) / nspan)
    }
}

/// Where the legend goes and the plot area's room there: the placement allowing the largest
/// scale; no legend on a picture too small for one beside or under the plot.
fn choose_place(legend: &LegendShape, m: &Margins, spans: (f64, f64)) -> (Place, i32, i32) {
    let base_w = m.wi - m.outer - m.y_label_w - m.right_pad;
    let base_h = m.hi - m.outer - m.title_h - m.x_label_h - m.outer;
    let mut candidates = vec![];
    if legend.entries.is_empty() {
        candidates.push((Place::Nowhere, base_w, base_h));
    } else {
        candidates.push((
            Place::Right,
            base_w + m.right_pad - m.legend_gap.max(m.right_pad) - legend.column.0 - m.outer,
            base_h,
        ));
        if let Some((_, _, h)) = legend.below.as_ref().filter(|_| !legend.column_only) {
            candidates.push((Place::Below, base_w, base_h - m.legend_gap - h));
        }
    }
    let best = candidates
        .iter()
        .copied()
        .max_by(|a, b| fit(a.1, a.2, spans).total_cmp(&fit(b.1, b.2, spans)));
    match best {
        Some(c) if fit(c.1, c.2, spans) >= 0.5 * fit(base_w, base_h, spans) => c,
        _ => (Place::Nowhere, base_w, base_h),
    }
}

/// A pixel rectangle: left, top, width, height.
type PixelRect = (i32, i32, u32, u32);

/// The legend's entry origins and frame for a plot area (left, top, width, height).
fn place_legend(
    legend: &LegendShape,
    place: Place,
    m: &Margins,
    (plot_x, plot_y, pw, ph): (i32, i32, i32, i32),
) -> (Vec<(i32, i32)>, PixelRect) {
    let (pad, row_h) = (legend.pad, legend.row_h);
    let mut origins = Vec::new();
    let frame = match place {
        Place::Nowhere => (0, 0, 0, 0),
        Place::Right => {
            let n = legend.entries.len() as i32;
            let (lx, ly) = (plot_x + pw + m.legend_gap.max(m.right_pad), plot_y);
            origins.extend((0..n).map(|i| (lx + pad, ly + pad + i * row_h + row_h / 3)));
            (lx, ly, legend.column.0 as u32, legend.column.1 as u32)
        }
        Place::Below => {
            let (widths, gw, gh) = legend.below.clone().unwrap_or_default();
            let lx = (plot_x + (pw - gw) / 2).clamp(m.outer, (m.wi - m.outer - gw).max(m.outer));
            let ly = plot_y + ph + m.x_label_h + m.legend_gap;
            let cols = widths.len().max(1);
            for i in 0..legend.entries.len() {
                let x = lx
                    + pad
                    + widths[..i % cols]
                        .iter()
                        .map(|w| w + legend.entry_sep)
                        .sum::<i32>();
                origins.push((x, ly + pad + (i / cols) as i32 * row_h + row_h / 3));
            }
            (lx, ly, gw as u32, gh as u32)
        }
    };
    (origins, frame)
}

/// The top-left corner of the group (title, axis labels, plot, legend) centred on the picture,
/// for a `pw` × `ph` plot area.
fn centre_group(
    m: &Margins,
    legend: &LegendShape,
    place: Place,
    (pw, ph): (i32, i32),
) -> (i32, i32) {
    let group_w = m.y_label_w
        + pw
        + if place == Place::Right {
            m.legend_gap.max(m.right_pad) + legend.column.0
        } else {
            m.right_pad
        };
    let group_h = m.title_h
        + ph
        + m.x_label_h
        + match (place, &legend.below) {
            (Place::Below, Some((_, _, h))) => m.legend_gap + h,
            _ => 0,
        };
    let gx = ((m.wi - group_w) / 2).max(m.outer);
    let gy = ((m.hi - group_h) / 2).max(m.outer);
    (gx, gy)
}

/// [`layout`] for a heat map: blocked cells are drawn black, and the colour scale's entries
/// follow the scene's in the legend.
pub(crate) fn layout_with(
    scene: &Scene,
    width_px: u32,
    height_px: u32,
    heat_legend: Option<Vec<LegendEntry>>,
) -> Result<PlotLayout, PlotError> {
    layout_full(scene, width_px, height_px, heat_legend, Vec::new())
}

/// [`layout_with`] with `extra` legend entries after the scene's own (a trajectory's scale).
pub(crate) fn layout_full(
    scene: &Scene,
    width_px: u32,
    height_px: u32,
    heat_legend: Option<Vec<LegendEntry>>,
    extra: Vec<LegendEntry>,
) -> Result<PlotLayout, PlotError> {
    let size_ok = |v: u32| (MIN_SIZE_PX..=MAX_SIZE_PX).contains(&v);
    if !size_ok(width_px) || !size_ok(height_px) {
        return Err(PlotError::BadSize {
            width: width_px,
            height: height_px,
        });
    }
    ensure_font()?;
    let bounds = world_bounds(scene)?;
    let (e0, e1, n0, n1) = bounds;
    let (wi, hi) = (width_px as i32, height_px as i32);
    let k = (f64::from(width_px.min(height_px)) / 800.0).clamp(0.75, 4.0);
    let mut fonts = Fonts::at_scale(k);
    let axes = axis_room(bounds, &fonts);
    let outer = px(14.0 * k);
    let (title, title_font) = fit_title(&scene.title, fonts.title, f64::from(wi - 2 * outer));
    fonts.title = title_font;
    let m = Margins {
        wi,
        hi,
        outer,
        title_h: if title.is_empty() {
            px(0.5 * fonts.tick)
        } else {
            px((CAP + 0.85) * fonts.title)
        },
        y_label_w: axes.y_label_w,
        x_label_h: axes.x_label_h,
        right_pad: px(0.5 * axes.widest_x + 6.0 * k).max(outer),
        legend_gap: px(16.0 * k),
    };
    let mut legend = legend_shape(scene, heat_legend, extra, &fonts, wi - 2 * outer);
    let (espan, nspan) = (e1 - e0, n1 - n0);
    let (place, aw, ah) = choose_place(&legend, &m, (espan, nspan));
    if place == Place::Nowhere {
        legend.entries = Vec::new();
    }
    let s = fit(aw, ah, (espan, nspan));
    if s <= 0.0 {
        return Err(PlotError::BadSize {
            width: width_px,
            height: height_px,
        });
    }
    let pw = (espan * s).floor() as i32 + 1;
    let ph = (nspan * s).floor() as i32 + 1;
    let east_m = (e0, e0 + f64::from(pw - 1) / s);
    let north_m = (n0, n0 + f64::from(ph - 1) / s);

    let (gx, gy) = centre_group(&m, &legend, place, (pw, ph));
    let (plot_x, plot_y) = (gx + m.y_label_w, gy + m.title_h);
    let title_half_w = (0.5 * text_width(&title, fonts.title)).ceil() as i32;
    let (origins, frame) = place_legend(&legend, place, &m, (plot_x, plot_y, pw, ph));

    // Ticks: labels never closer than their own size allows, about ten per axis at most.
    let x_min_m = (axes.widest_x + 2.5 * fonts.tick).max(f64::from(pw) / 10.0) / s;
    let (x_ticks, x_step) = ticks(east_m.0, east_m.1, x_min_m);
    let y_min_m = (3.0 * fonts.tick).max(f64::from(ph) / 10.0) / s;
    let (y_ticks, y_step) = ticks(north_m.0, north_m.1, y_min_m);
    Ok(PlotLayout {
        width: width_px,
        height: height_px,
        plot: (plot_x, plot_y, pw as u32, ph as u32),
        east_m,
        north_m,
        fonts,
        x_ticks,
        y_ticks,
        decimals: decimals_for_step(x_step.min(y_step)),
        tick_len: axes.tick_len,
        tick_gap: axes.tick_gap,
        x_desc_baseline: plot_y + ph + px(axes.x_desc_off),
        y_desc_baseline: plot_x - px(axes.y_desc_off),
        title_top: gy,
        title_x: (plot_x + pw / 2).clamp(
            outer + title_half_w,
            (wi - outer - title_half_w).max(outer + title_half_w),
        ),
        title,
        legend: LegendLayout {
            entries: legend.entries,
            origins,
            frame,
            sample_w: legend.sample_w,
            text_gap: legend.text_gap,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps_and_ticks() {
        assert_eq!(nice_step(0.7), 1.0);
        assert_eq!(nice_step(1.0), 1.0);
        assert_eq!(nice_step(1.2), 2.0);
        assert_eq!(nice_step(37.0), 50.0);
        assert_eq!(nice_step(51.0), 100.0);
        let (t, step) = ticks(-316.0, 605.0, 90.0);
        assert_eq!(step, 100.0);
        assert_eq!(
            t,
            vec![
                -300.0, -200.0, -100.0, 0.0, 100.0, 200.0, 300.0, 400.0, 500.0, 600.0
            ]
        );
        assert_eq!(decimals_for_step(0.2), 1);
        assert_eq!(decimals_for_step(0.05), 2);
        assert_eq!(decimals_for_step(5.0), 0);
        assert_eq!(fmt_metres(-0.0001, 1), "0.0");
        assert_eq!(fmt_metres(-2.5, 1), "-2.5");
    }
}
