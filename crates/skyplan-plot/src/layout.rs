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
    /// Heat maps: blocked cells (drawn black), a colour of the scale, cells without a value,
    /// and the scale's caption (no sample).
    HeatBlocked,
    Heat(u8),
    NoValue,
    Caption,
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
    ///     title: String::new(), grid: &grid, obstacles: &[], raw_path_ne: &[],
    ///     pruned_path_ne: &[], start_ne: None, goal_ne: None, graph_ne: &[], connectors_ne: &[], flight: None,
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
    let obstacles = !scene.obstacles.is_empty();
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

/// [`layout`] for a heat map: blocked cells are drawn black, and the colour scale's entries
/// follow the scene's in the legend.
pub(crate) fn layout_with(
    scene: &Scene,
    width_px: u32,
    height_px: u32,
    heat_legend: Option<Vec<LegendEntry>>,
) -> Result<PlotLayout, PlotError> {
    let size_ok = |v: u32| (MIN_SIZE_PX..=MAX_SIZE_PX).contains(&v);
    if !size_ok(width_px) || !size_ok(height_px) {
        return Err(PlotError::BadSize {
            width: width_px,
            height: height_px,
        });
    }
    ensure_font()?;
    let (e0, e1, n0, n1) = world_bounds(scene)?;
    let (wi, hi) = (width_px as i32, height_px as i32);
    let k = (f64::from(width_px.min(height_px)) / 800.0).clamp(0.75, 4.0);
    // Even sizes: plotters' rasteriser then puts every glyph on the same baseline.
    let even = |v: f64| 2.0 * (v / 2.0).round();
    let mut fonts = Fonts {
        k,
        title: even(21.0 * k),
        desc: even(16.0 * k),
        tick: even(13.5 * k),
        legend: even(13.5 * k),
    };
    let px = |v: f64| v.round() as i32;

    // Axis labels: room for the widest tick label either axis may need.
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
    // From the plot's edge to the baseline of the axis title.
    let y_desc_off = f64::from(tick_len + tick_gap) + widest_y + 0.6 * fonts.desc;
    let y_label_w = px(y_desc_off + 0.8 * fonts.desc);
    let x_desc_off =
        f64::from(tick_len + tick_gap) + CAP * fonts.tick + 0.8 * fonts.desc + CAP * fonts.desc;
    let x_label_h = px(x_desc_off + DESCENT * fonts.desc);
    let outer = px(14.0 * k);
    // A title wider than the picture is set smaller, down to 10 px, then shortened.
    let room = f64::from(wi - 2 * outer);
    let mut title = scene.title.clone();
    let fitted = even(fonts.title * room / text_width(&title, fonts.title).max(1.0) - 1.0);
    fonts.title = fonts.title.min(fitted).max(10.0);
    while !title.is_empty() && text_width(&title, fonts.title) > room {
        title.pop();
        while title.ends_with(' ') {
            title.pop();
        }
        if text_width(&format!("{title}…"), fonts.title) <= room {
            title.push('…');
            break;
        }
    }
    let title_h = if title.is_empty() {
        px(0.5 * fonts.tick)
    } else {
        px((CAP + 0.85) * fonts.title)
    };
    let right_pad = px(0.5 * widest_x + 6.0 * k).max(outer);

    // Legend: a column beside the plot or a row under it.
    let mut entries = legend_entries(scene);
    // A heat map's colour scale reads top to bottom: its legend is a column beside the plot.
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
        .find(|&c| grid_of(c).1 <= wi - 2 * outer)
        .map(|c| grid_of(entries.len().div_ceil(entries.len().div_ceil(c))));
    let legend_gap = px(16.0 * k);

    // The scale each placement allows; keep the best.
    let (espan, nspan) = (e1 - e0, n1 - n0);
    let fit = |aw: i32, ah: i32| -> f64 {
        if aw < 20 || ah < 20 {
            0.0
        } else {
            (f64::from(aw - 1) / espan).min(f64::from(ah - 1) / nspan)
        }
    };
    let base_w = wi - outer - y_label_w - right_pad;
    let base_h = hi - outer - title_h - x_label_h - outer;
    let mut candidates = vec![];
    if entries.is_empty() {
        candidates.push((Place::Nowhere, base_w, base_h));
    } else {
        candidates.push((
            Place::Right,
            base_w + right_pad - legend_gap.max(right_pad) - column.0 - outer,
            base_h,
        ));
        if let Some((_, _, h)) = below.as_ref().filter(|_| !column_only) {
            candidates.push((Place::Below, base_w, base_h - legend_gap - h));
        }
    }
    let best = candidates
        .iter()
        .copied()
        .max_by(|a, b| fit(a.1, a.2).total_cmp(&fit(b.1, b.2)));
    // A picture too small for a legend beside or under the plot goes without.
    let (place, aw, ah) = match best {
        Some(c) if fit(c.1, c.2) >= 0.5 * fit(base_w, base_h) => c,
        _ => (Place::Nowhere, base_w, base_h),
    };
    let entries = if place == Place::Nowhere {
        Vec::new()
    } else {
        entries
    };
    let s = fit(aw, ah);
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

    // Centre the group (axis labels, plot, legend) on the picture.
    let legend_sep = legend_gap.max(right_pad);
    let group_w = y_label_w
        + pw
        + if place == Place::Right {
            legend_sep + column.0
        } else {
            right_pad
        };
    let group_h = title_h
        + ph
        + x_label_h
        + match (place, &below) {
            (Place::Below, Some((_, _, h))) => legend_gap + h,
            _ => 0,
        };
    let gx = ((wi - group_w) / 2).max(outer);
    let gy = ((hi - group_h) / 2).max(outer);
    let (plot_x, plot_y) = (gx + y_label_w, gy + title_h);
    let title_half_w = (0.5 * text_width(&title, fonts.title)).ceil() as i32;

    let mut origins = Vec::new();
    let frame = match place {
        Place::Nowhere => (0, 0, 0, 0),
        Place::Right => {
            let (lx, ly) = (plot_x + pw + legend_sep, plot_y);
            origins.extend((0..n).map(|i| (lx + pad, ly + pad + i * row_h + row_h / 3)));
            (lx, ly, column.0 as u32, column.1 as u32)
        }
        Place::Below => {
            let (widths, gw, gh) = below.unwrap_or_default();
            let lx = (plot_x + (pw - gw) / 2).clamp(outer, (wi - outer - gw).max(outer));
            let ly = plot_y + ph + x_label_h + legend_gap;
            let cols = widths.len().max(1);
            for i in 0..entries.len() {
                let x = lx
                    + pad
                    + widths[..i % cols]
                        .iter()
                        .map(|w| w + entry_sep)
                        .sum::<i32>();
                origins.push((x, ly + pad + (i / cols) as i32 * row_h + row_h / 3));
            }
            (lx, ly, gw as u32, gh as u32)
        }
    };

    // Ticks: labels never closer than their own size allows, about ten per axis at most.
    let (x_ticks, x_step) = ticks(
        east_m.0,
        east_m.1,
        (widest_x + 2.5 * fonts.tick).max(f64::from(pw) / 10.0) / s,
    );
    let (y_ticks, y_step) = ticks(
        north_m.0,
        north_m.1,
        (3.0 * fonts.tick).max(f64::from(ph) / 10.0) / s,
    );
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
        tick_len,
        tick_gap,
        x_desc_baseline: plot_y + ph + px(x_desc_off),
        y_desc_baseline: plot_x - px(y_desc_off),
        title_top: gy,
        title_x: (plot_x + pw / 2).clamp(
            outer + title_half_w,
            (wi - outer - title_half_w).max(outer + title_half_w),
        ),
        title,
        legend: LegendLayout {
            entries,
            origins,
            frame,
            sample_w,
            text_gap,
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
