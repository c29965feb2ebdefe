//! The drawing itself, written once for every plotters backend.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::ComposedElement;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use crate::layout::{LegendKind, PlotLayout};
use crate::rects::blocked_rects;
use crate::text::{Label, TextMode, VAlign, draw_label, draw_tick};
use crate::trajectory::SpeedTrace;
use crate::{PlotError, Scene};

const CSPACE_COLOR: RGBColor = RGBColor(204, 207, 212);
const OBSTACLE_COLOR: RGBColor = RGBColor(92, 95, 102);
const GRAPH_COLOR: RGBColor = RGBColor(120, 175, 225);
const CONNECTOR_COLOR: RGBColor = RGBColor(160, 60, 190);
const RAW_COLOR: RGBColor = RGBColor(255, 127, 14);
const PRUNED_COLOR: RGBColor = RGBColor(31, 96, 196);
const START_COLOR: RGBColor = RGBColor(0, 170, 60);
const GOAL_COLOR: RGBColor = RGBColor(222, 30, 30);
const GRID_LINE_COLOR: RGBColor = RGBColor(230, 230, 230);
const FRAME_COLOR: RGBColor = RGBColor(40, 40, 40);
const LEGEND_BORDER_COLOR: RGBColor = RGBColor(175, 175, 175);
const HIDDEN_COLOR: RGBColor = RGBColor(150, 30, 40);
const LEARNED_COLOR: RGBColor = RGBColor(230, 60, 150);
const REPLANNED_COLOR: RGBColor = RGBColor(140, 70, 200);
const TRACK_COLOR: RGBColor = RGBColor(20, 20, 20);
const REFUSED_COLOR: RGBColor = RGBColor(150, 150, 150);

/// The colour of a fleet's k-th accepted flight: hues a golden angle apart.
fn fleet_color(k: usize) -> HSLColor {
    HSLColor((k as f64 * 0.618_034).fract(), 0.8, 0.42)
}
/// An exclusion zone: outline and hatching.
pub(crate) const ZONE_COLOR: RGBColor = RGBColor(214, 40, 40);
/// An inclusion boundary's outline.
pub(crate) const INCLUSION_COLOR: RGBColor = RGBColor(0, 150, 80);
/// Pixels between two hatching lines.
const HATCH_PX: f64 = 7.0;
const HEAT_BLOCKED_COLOR: RGBColor = RGBColor(0, 0, 0);
const NO_VALUE_COLOR: RGBColor = RGBColor(200, 200, 200);

fn err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

fn px(v: f64) -> u32 {
    v.round().max(1.0) as u32
}

/// The plot area's chart: east right, north up, metres.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Line styles and marker radii, scaled to the picture (`k`: 1 for an 800 px picture).
struct Styles {
    graph: ShapeStyle,
    connector: ShapeStyle,
    raw: ShapeStyle,
    pruned: ShapeStyle,
    replanned: ShapeStyle,
    track: ShapeStyle,
    /// Width of a fleet's routes, pixels.
    fleet_w: u32,
    /// Width of a trajectory's curve, pixels.
    trajectory: u32,
    /// Radii of a waypoint, of the start and goal markers, of a learned cell's dot.
    r_wp: u32,
    r_end: u32,
    r_learned: u32,
}

impl Styles {
    fn new(k: f64) -> Self {
        Styles {
            graph: GRAPH_COLOR.stroke_width(px(1.0 * k)),
            connector: CONNECTOR_COLOR.stroke_width(px(2.0 * k)),
            raw: RAW_COLOR.stroke_width(px(1.6 * k)),
            pruned: PRUNED_COLOR.stroke_width(px(3.0 * k)),
            replanned: REPLANNED_COLOR.stroke_width(px(2.4 * k)),
            track: TRACK_COLOR.stroke_width(px(1.4 * k)),
            trajectory: px(3.0 * k),
            fleet_w: px(1.8 * k),
            r_wp: px(4.5 * k),
            r_end: px(8.0 * k),
            r_learned: px(2.5 * k),
        }
    }
}

/// Draws the scene on the whole picture `root`; with `heat`, its colours (one level per cell,
/// row-major from the southern row; `None`: no value) fill the grid instead of the
/// configuration space, blocked cells black; with `trace`, a trajectory coloured by speed goes
/// over the route.
pub(crate) fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene,
    l: &PlotLayout,
    mode: TextMode,
    heat: Option<&[Option<u8>]>,
    trace: Option<&SpeedTrace>,
) -> Result<(), PlotError> {
    root.fill(&WHITE).map_err(err)?;
    let (x0, y0, w, h) = l.plot;
    let styles = Styles::new(l.fonts.k);
    draw_grid_lines(root, l)?;
    let area = root.clone().shrink((x0, y0), (w, h));
    let mut chart = ChartBuilder::on(&area)
        .build_cartesian_2d(l.east_m.0..l.east_m.1, l.north_m.0..l.north_m.1)
        .map_err(err)?;
    if let Some(levels) = heat {
        draw_heat(root, scene, l, levels)?;
    }
    draw_obstacles(&mut chart, scene, heat.is_none())?;
    draw_zones(root, &mut chart, scene, l, mode)?;
    draw_roadmap(&mut chart, scene, &styles)?;
    draw_routes(&mut chart, scene, &styles, trace)?;
    draw_axes(root, l, mode)?;
    draw_legend(root, l, mode, &styles, trace)
}

/// Light grid lines at the ticks, under everything else.
fn draw_grid_lines<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    l: &PlotLayout,
) -> Result<(), PlotError> {
    let (x0, y0, w, h) = l.plot;
    let (x1, y1) = (x0 + w as i32 - 1, y0 + h as i32 - 1);
    for &e in &l.x_ticks {
        let x = l.pixel_of_ne(l.north_m.0, e).0;
        root.draw(&PathElement::new(vec![(x, y0), (x, y1)], GRID_LINE_COLOR))
            .map_err(err)?;
    }
    for &n in &l.y_ticks {
        let y = l.pixel_of_ne(n, l.east_m.0).1;
        root.draw(&PathElement::new(vec![(x0, y), (x1, y)], GRID_LINE_COLOR))
            .map_err(err)?;
    }
    Ok(())
}

/// The configuration space (with `cspace`; a heat map shows it instead), then the obstacles
/// themselves.
fn draw_obstacles<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    scene: &Scene,
    cspace: bool,
) -> Result<(), PlotError> {
    let f = scene.grid.frame();
    let cspace = if cspace {
        blocked_rects(scene.grid)
    } else {
        Vec::new()
    };
    chart
        .draw_series(cspace.into_iter().map(|r| {
            let e0 = f.origin_east_m + f64::from(r.col) * f.cell_m;
            let n0 = f.origin_north_m + f64::from(r.row) * f.cell_m;
            let e1 = e0 + f64::from(r.cols) * f.cell_m;
            let n1 = n0 + f64::from(r.rows) * f.cell_m;
            Rectangle::new([(e0, n1), (e1, n0)], CSPACE_COLOR.filled())
        }))
        .map_err(err)?;
    chart
        .draw_series(scene.obstacles.iter().map(|o| footprint(o, OBSTACLE_COLOR)))
        .map_err(err)?;
    chart
        .draw_series(
            (scene.footprints.iter())
                .map(|f| Polygon::new(keyhole_ring(&f.rings), OBSTACLE_COLOR.filled())),
        )
        .map_err(err)?;
    Ok(())
}

/// Twice the signed area of a ring of `[north, east]` points (positive counter-clockwise
/// with east right and north up).
fn signed_area2(ring: &[[f64; 2]]) -> f64 {
    (0..ring.len())
        .map(|i| {
            let ([n0, e0], [n1, e1]) = (ring[i], ring[(i + 1) % ring.len()]);
            e0 * n1 - e1 * n0
        })
        .sum()
}

/// A polygon with holes as one closed `(east, north)` outline that fills right under both fill
/// rules (even-odd in the bitmap backend, non-zero in SVG): the outer ring, then each hole
/// reached from the outer ring's first point and walked the other way round, back to that point.
/// Each bridge is walked once each way, so it adds nothing to either rule's count.
fn keyhole_ring(rings: &[Vec<[f64; 2]>]) -> Vec<(f64, f64)> {
    let Some(outer) = rings.first().filter(|r| !r.is_empty()) else {
        return Vec::new();
    };
    let en = |p: &[f64; 2]| (p[1], p[0]);
    let outer_sign = signed_area2(outer).signum();
    let mut out: Vec<(f64, f64)> = outer.iter().map(en).collect();
    out.push(en(&outer[0]));
    for hole in rings[1..].iter().filter(|h| !h.is_empty()) {
        let against = signed_area2(hole).signum() != outer_sign;
        let walk: Vec<(f64, f64)> = if against {
            hole.iter().map(en).collect()
        } else {
            hole.iter().rev().map(en).collect()
        };
        out.extend_from_slice(&walk);
        out.push(walk[0]);
        out.push(en(&outer[0]));
    }
    out
}

/// The rings of a zone as `(east, north)` points (a circle as a 96-gon).
fn zone_rings(z: &skyplan_map::nofly::Zone) -> Vec<Vec<(f64, f64)>> {
    use skyplan_map::nofly::ZoneShape;
    match &z.shape {
        ZoneShape::Polygon(rings) => rings
            .iter()
            .map(|r| r.iter().map(|p| (p[1], p[0])).collect())
            .collect(),
        ZoneShape::Circle { centre, radius_m } => {
            let ring = (0..96)
                .map(|k| {
                    let a = std::f64::consts::TAU * f64::from(k) / 96.0;
                    (
                        centre[1] + radius_m * a.sin(),
                        centre[0] + radius_m * a.cos(),
                    )
                })
                .collect();
            vec![ring]
        }
    }
}

/// The hatching of rings `(east, north)`: segments of the lines east − north = c, every
/// `step_m`, inside the rings (even-odd: holes stay clear).
pub(crate) fn hatch_segments(
    rings: &[Vec<(f64, f64)>],
    step_m: f64,
) -> Vec<((f64, f64), (f64, f64))> {
    let pts = rings.iter().flatten();
    let (lo, hi) = pts.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(e, n)| {
        (lo.min(e - n), hi.max(e - n))
    });
    let mut out = Vec::new();
    if !(step_m > 0.0 && lo.is_finite() && hi.is_finite()) {
        return out;
    }
    let mut c = (lo / step_m).ceil() * step_m;
    while c <= hi && out.len() < 100_000 {
        // Along the line (e, n) = (c + t, t): where each edge crosses it, by t.
        let mut ts = Vec::new();
        for ring in rings {
            for k in 0..ring.len() {
                let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
                let (fa, fb) = (a.0 - a.1 - c, b.0 - b.1 - c);
                if (fa > 0.0) != (fb > 0.0) {
                    let s = fa / (fa - fb);
                    ts.push(a.1 + s * (b.1 - a.1));
                }
            }
        }
        ts.sort_by(f64::total_cmp);
        for pair in ts.chunks_exact(2) {
            out.push(((c + pair[0], pair[0]), (c + pair[1], pair[1])));
        }
        c += step_m;
    }
    out
}

/// The no-fly zones: exclusion zones outlined and hatched in red, inclusion boundaries outlined
/// in green, each labelled "zone N, F–C m" (an inclusion "zone N inside, …") at its northern
/// edge.
fn draw_zones<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &mut Chart<'_, DB>,
    scene: &Scene,
    l: &PlotLayout,
    mode: TextMode,
) -> Result<(), PlotError> {
    let width = (1.5 * l.fonts.k).round().max(1.0) as u32;
    for z in scene.zones {
        let rings = zone_rings(z);
        let color = if z.inclusion {
            INCLUSION_COLOR
        } else {
            ZONE_COLOR
        };
        if !z.inclusion {
            let step_m = HATCH_PX * l.metres_per_px();
            chart
                .draw_series(
                    hatch_segments(&rings, step_m)
                        .into_iter()
                        .map(|(a, b)| PathElement::new(vec![a, b], color.stroke_width(1))),
                )
                .map_err(err)?;
        }
        for ring in &rings {
            let mut closed = ring.clone();
            closed.extend(ring.first().copied());
            chart
                .draw_series(std::iter::once(PathElement::new(
                    closed,
                    color.stroke_width(width),
                )))
                .map_err(err)?;
        }
        let band = if z.ceiling_m.is_finite() {
            format!("{:.0}–{:.0} m", z.floor_m, z.ceiling_m)
        } else {
            format!("from {:.0} m", z.floor_m)
        };
        let text = if z.inclusion {
            format!("zone {} inside, {band}", z.feature)
        } else {
            format!("zone {}, {band}", z.feature)
        };
        let (lo, hi) = z.bbox_ne();
        let at = l.pixel_of_ne(hi[0], 0.5 * (lo[1] + hi[1]));
        let label = Label {
            text: &text,
            size: l.fonts.legend,
            at: (at.0, at.1 - 3),
            h: HPos::Center,
            v: VAlign::Baseline,
            vertical: false,
        };
        draw_label(root, mode, &label)?;
    }
    Ok(())
}

/// A roadmap's edges thin and light, its connectors a little stronger.
fn draw_roadmap<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    scene: &Scene,
    styles: &Styles,
) -> Result<(), PlotError> {
    for (segments, style) in [
        (scene.graph_ne, styles.graph),
        (scene.connectors_ne, styles.connector),
    ] {
        chart
            .draw_series(
                segments
                    .iter()
                    .map(|&((n0, e0), (n1, e1))| PathElement::new(vec![(e0, n0), (e1, n1)], style)),
            )
            .map_err(err)?;
    }
    Ok(())
}

/// The routes: a flight's hidden obstacles and learned cells, the raw grid path thin, the
/// pruned one thick, a trajectory over it, a circle at each waypoint, the flight's replanned
/// routes and track, then the start and goal markers.
fn draw_routes<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    scene: &Scene,
    styles: &Styles,
    trace: Option<&SpeedTrace>,
) -> Result<(), PlotError> {
    let en = |&(n, e): &(f64, f64)| (e, n);
    if let Some(f) = scene.flight {
        // The learned cells first, then the hidden buildings over them: a hidden building
        // stays visible where the vehicle learned its cells.
        let r = styles.r_learned;
        chart
            .draw_series(
                f.learned_ne
                    .iter()
                    .map(|p| Circle::new(en(p), r, LEARNED_COLOR.filled())),
            )
            .map_err(err)?;
        chart
            .draw_series(f.hidden.iter().map(|o| footprint(o, HIDDEN_COLOR)))
            .map_err(err)?;
    }
    for f in scene.fleet.iter().filter(|f| !f.accepted) {
        chart
            .draw_series(LineSeries::new(
                f.route_ne.iter().map(en),
                REFUSED_COLOR.stroke_width(styles.fleet_w.div_ceil(2)),
            ))
            .map_err(err)?;
    }
    for (k, f) in scene.fleet.iter().filter(|f| f.accepted).enumerate() {
        chart
            .draw_series(LineSeries::new(
                f.route_ne.iter().map(en),
                fleet_color(k).stroke_width(styles.fleet_w),
            ))
            .map_err(err)?;
    }
    if scene.raw_path_ne.len() > 1 {
        chart
            .draw_series(LineSeries::new(
                scene.raw_path_ne.iter().map(en),
                styles.raw,
            ))
            .map_err(err)?;
    }
    if scene.pruned_path_ne.len() > 1 {
        chart
            .draw_series(LineSeries::new(
                scene.pruned_path_ne.iter().map(en),
                styles.pruned,
            ))
            .map_err(err)?;
    }
    if let Some(trace) = trace {
        crate::trajectory::draw_on_map(chart, trace, styles.trajectory)?;
    }
    chart
        .draw_series(
            scene
                .pruned_path_ne
                .iter()
                .map(|p| waypoint_marker(en(p), styles.r_wp)),
        )
        .map_err(err)?;
    if let Some(f) = scene.flight {
        for route in f.replanned_ne {
            chart
                .draw_series(LineSeries::new(route.iter().map(en), styles.replanned))
                .map_err(err)?;
        }
        chart
            .draw_series(LineSeries::new(f.track_ne.iter().map(en), styles.track))
            .map_err(err)?;
    }
    if let Some(p) = scene.start_ne {
        chart
            .draw_series(std::iter::once(start_marker(en(&p), styles.r_end)))
            .map_err(err)?;
    }
    if let Some(p) = scene.goal_ne {
        chart
            .draw_series(std::iter::once(goal_marker(en(&p), styles.r_end)))
            .map_err(err)?;
    }
    Ok(())
}

/// The plot's frame, outward ticks and their labels, the axis titles and the picture's title.
fn draw_axes<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    l: &PlotLayout,
    mode: TextMode,
) -> Result<(), PlotError> {
    let (x0, y0, w, h) = l.plot;
    let (x1, y1) = (x0 + w as i32 - 1, y0 + h as i32 - 1);
    root.draw(&Rectangle::new(
        [(x0, y0), (x1, y1)],
        FRAME_COLOR.stroke_width(1),
    ))
    .map_err(err)?;
    let tick_size = l.fonts.tick;
    for &e in &l.x_ticks {
        let x = l.pixel_of_ne(l.north_m.0, e).0;
        let at = [
            (x, y1),
            (x, y1 + l.tick_len),
            (x, y1 + l.tick_len + l.tick_gap),
        ];
        let text = l.tick_label(e);
        let anchor = (HPos::Center, VAlign::Top);
        draw_tick(root, mode, (at, FRAME_COLOR), (&text, tick_size), anchor)?;
    }
    for &n in &l.y_ticks {
        let y = l.pixel_of_ne(n, l.east_m.0).1;
        let at = [
            (x0 - l.tick_len, y),
            (x0, y),
            (x0 - l.tick_len - l.tick_gap, y),
        ];
        let text = l.tick_label(n);
        let anchor = (HPos::Right, VAlign::Middle);
        draw_tick(root, mode, (at, FRAME_COLOR), (&text, tick_size), anchor)?;
    }
    let desc = l.fonts.desc;
    let x_mid = x0 + w as i32 / 2;
    let at = (x_mid, l.x_desc_baseline);
    draw_label(
        root,
        mode,
        &Label {
            text: "EAST (m)",
            size: desc,
            at,
            h: HPos::Center,
            v: VAlign::Baseline,
            vertical: false,
        },
    )?;
    let at = (l.y_desc_baseline, y0 + h as i32 / 2);
    draw_label(
        root,
        mode,
        &Label {
            text: "NORTH (m)",
            size: desc,
            at,
            h: HPos::Center,
            v: VAlign::Baseline,
            vertical: true,
        },
    )?;
    if !l.title.is_empty() {
        let at = (l.title_x, l.title_top);
        draw_label(
            root,
            mode,
            &Label {
                text: &l.title,
                size: l.fonts.title,
                at,
                h: HPos::Center,
                v: VAlign::Top,
                vertical: false,
            },
        )?;
    }
    Ok(())
}

/// Paints every pixel of the plot area with the colour of the cell under its centre.
fn draw_heat<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &Scene,
    l: &PlotLayout,
    levels: &[Option<u8>],
) -> Result<(), PlotError> {
    let (x0, y0, w, h) = l.plot;
    let grid = scene.grid;
    let (de, dn) = (l.east_m.1 - l.east_m.0, l.north_m.1 - l.north_m.0);
    for py in 0..h {
        let north = l.north_m.1 - (f64::from(py) + 0.5) / f64::from(h) * dn;
        for px in 0..w {
            let east = l.east_m.0 + (f64::from(px) + 0.5) / f64::from(w) * de;
            let Some(cell) = grid.cell_at_ne(north, east) else {
                continue;
            };
            let i = cell.row as usize * grid.cols() as usize + cell.col as usize;
            let color = if grid.blocked_cells()[i] {
                HEAT_BLOCKED_COLOR
            } else {
                levels[i].map_or(NO_VALUE_COLOR, heat_color)
            };
            root.draw_pixel((x0 + px as i32, y0 + py as i32), &color)
                .map_err(err)?;
        }
    }
    Ok(())
}

fn heat_color(level: u8) -> RGBColor {
    let [r, g, b] = crate::heatmap::viridis(level);
    RGBColor(r, g, b)
}

fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    l: &PlotLayout,
    mode: TextMode,
    styles: &Styles,
    trace: Option<&SpeedTrace>,
) -> Result<(), PlotError> {
    let legend = &l.legend;
    if legend.entries.is_empty() {
        return Ok(());
    }
    let (lx, ly, lw, lh) = legend.frame;
    let corner = (lx + lw as i32 - 1, ly + lh as i32 - 1);
    root.draw(&Rectangle::new([(lx, ly), corner], WHITE.filled()))
        .map_err(err)?;
    root.draw(&Rectangle::new(
        [(lx, ly), corner],
        LEGEND_BORDER_COLOR.stroke_width(1),
    ))
    .map_err(err)?;
    let sw = legend.sample_w;
    for (entry, &(x, cy)) in legend.entries.iter().zip(&legend.origins) {
        let cx = x + sw / 2;
        let swatch = |color: RGBColor| {
            let hs = (0.45 * l.fonts.legend).round() as i32;
            Rectangle::new([(x + 1, cy - hs), (x + sw - 1, cy + hs)], color.filled())
        };
        let line = |style: ShapeStyle| PathElement::new(vec![(x, cy), (x + sw, cy)], style);
        match entry.kind {
            LegendKind::CSpace => root.draw(&swatch(CSPACE_COLOR)),
            LegendKind::Obstacle => root.draw(&swatch(OBSTACLE_COLOR)),
            LegendKind::Graph => root.draw(&line(styles.graph)),
            LegendKind::Connector => root.draw(&line(styles.connector)),
            LegendKind::Raw => root.draw(&line(styles.raw)),
            LegendKind::Pruned => root
                .draw(&line(styles.pruned))
                .and_then(|()| root.draw(&waypoint_marker((cx, cy), styles.r_wp))),
            LegendKind::Start => root.draw(&start_marker((cx, cy), styles.r_end)),
            LegendKind::Goal => root.draw(&goal_marker((cx, cy), styles.r_end)),
            LegendKind::Hidden => root.draw(&swatch(HIDDEN_COLOR)),
            LegendKind::Learned => root.draw(&Circle::new(
                (cx, cy),
                styles.r_learned,
                LEARNED_COLOR.filled(),
            )),
            LegendKind::Replanned => root.draw(&line(styles.replanned)),
            LegendKind::Track => root.draw(&line(styles.track)),
            LegendKind::Fleet => (0..3).try_for_each(|k| {
                let third = sw / 3;
                let (a, b) = (x + k * third, x + (k + 1) * third);
                root.draw(&PathElement::new(
                    vec![(a, cy), (b, cy)],
                    fleet_color(k as usize).stroke_width(styles.fleet_w),
                ))
            }),
            LegendKind::FleetRefused => root.draw(&line(
                REFUSED_COLOR.stroke_width(styles.fleet_w.div_ceil(2)),
            )),
            LegendKind::HeatBlocked => root.draw(&swatch(HEAT_BLOCKED_COLOR)),
            LegendKind::Heat(level) => root.draw(&swatch(heat_color(level))),
            LegendKind::NoValue => root.draw(&swatch(NO_VALUE_COLOR)),
            LegendKind::Caption => Ok(()),
            LegendKind::SpeedScale => {
                if let Some(trace) = trace {
                    let hs = (0.3 * l.fonts.legend).round() as i32;
                    let casing = Rectangle::new(
                        [(x, cy - hs - 1), (x + sw - 1, cy + hs + 1)],
                        FRAME_COLOR.filled(),
                    );
                    root.draw(&casing).map_err(err)?;
                    crate::trajectory::draw_scale_sample(root, trace, (x + 1, cy), (sw - 2, hs))?;
                }
                Ok(())
            }
        }
        .map_err(err)?;
        let at = (x + sw + legend.text_gap, cy);
        let label = Label {
            text: &entry.text,
            size: l.fonts.legend,
            at,
            h: HPos::Left,
            v: VAlign::Middle,
            vertical: false,
        };
        draw_label(root, mode, &label)?;
    }
    Ok(())
}

type Dot = Circle<(i32, i32), u32>;
type TwoDots<C, DB> = ComposedElement<C, DB, Dot, Dot>;
type Star<C, DB> = ComposedElement<C, DB, Polygon<(i32, i32)>, PathElement<(i32, i32)>>;

/// A box's footprint (east right, north up), filled.
fn footprint(o: &skyplan_map::colliders::ObstacleBox, color: RGBColor) -> Rectangle<(f64, f64)> {
    let nw = (o.east_m - o.half_east_m, o.north_m + o.half_north_m);
    let se = (o.east_m + o.half_east_m, o.north_m - o.half_north_m);
    Rectangle::new([nw, se], color.filled())
}

/// A waypoint: a white disc ringed in the pruned path's blue.
fn waypoint_marker<C, DB: DrawingBackend>(at: C, r: u32) -> TwoDots<C, DB> {
    let inner = r - (f64::from(r) * 0.45).round().max(1.0) as u32;
    EmptyElement::at(at)
        + Circle::new((0, 0), r, PRUNED_COLOR.filled())
        + Circle::new((0, 0), inner.max(1), WHITE.filled())
}

/// The start: a green disc with a dark rim.
fn start_marker<C, DB: DrawingBackend>(at: C, r: u32) -> TwoDots<C, DB> {
    EmptyElement::at(at)
        + Circle::new((0, 0), r, FRAME_COLOR.filled())
        + Circle::new((0, 0), r - 1, START_COLOR.filled())
}

/// The goal: a red five-pointed star with a dark outline.
fn goal_marker<C, DB: DrawingBackend>(at: C, r: u32) -> Star<C, DB> {
    let r_out = f64::from(r) * 1.35;
    let r_in = r_out * 0.45;
    let points: Vec<(i32, i32)> = (0..10)
        .map(|i| {
            let a = std::f64::consts::PI * (f64::from(i) / 5.0 - 0.5);
            let rr = if i % 2 == 0 { r_out } else { r_in };
            (
                (rr * a.cos()).round() as i32,
                (rr * a.sin()).round() as i32 + 1,
            )
        })
        .collect();
    let mut outline = points.clone();
    outline.push(points[0]);
    EmptyElement::at(at)
        + Polygon::new(points, GOAL_COLOR.filled())
        + PathElement::new(outline, FRAME_COLOR.stroke_width(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Winding number of the closed outline `ring` (`(east, north)`) about `p`.
    fn winding((e, n): (f64, f64), ring: &[(f64, f64)]) -> i32 {
        let mut w = 0;
        for i in 0..ring.len() {
            let ((e0, n0), (e1, n1)) = (ring[i], ring[(i + 1) % ring.len()]);
            let cross = (e1 - e0) * (n - n0) - (e - e0) * (n1 - n0);
            if n0 <= n && n1 > n && cross > 0.0 {
                w += 1;
            } else if n0 > n && n1 <= n && cross < 0.0 {
                w -= 1;
            }
        }
        w
    }

    /// Crossings of a ray going east from `p` (the even-odd rule's count).
    fn crossings((e, n): (f64, f64), ring: &[(f64, f64)]) -> usize {
        (0..ring.len())
            .filter(|&i| {
                let ((e0, n0), (e1, n1)) = (ring[i], ring[(i + 1) % ring.len()]);
                (n0 <= n) != (n1 <= n) && e0 + (n - n0) / (n1 - n0) * (e1 - e0) > e
            })
            .count()
    }

    #[test]
    fn a_keyhole_outline_fills_the_ring_and_leaves_the_holes_under_both_rules() {
        let square = |n0: f64, e0: f64, n1: f64, e1: f64, ccw: bool| {
            let mut r = vec![[n0, e0], [n0, e1], [n1, e1], [n1, e0]];
            if !ccw {
                r.reverse();
            }
            r
        };
        // Holes in both orientations, the outer ring in both.
        for outer_ccw in [true, false] {
            let rings = vec![
                square(-15.0, -25.0, 15.0, 25.0, outer_ccw),
                square(-5.0, -10.0, 5.0, 10.0, true),
                square(8.0, 15.0, 12.0, 20.0, false),
            ];
            let outline = keyhole_ring(&rings);
            // (north, east) probes: in the ring, in each hole, outside.
            for ((n, e), inside) in [
                ((-10.0, 0.3), true),
                ((13.1, 17.3), true),
                ((0.1, 0.3), false),
                ((10.1, 17.3), false),
                ((18.0, 0.3), false),
                ((0.1, 30.3), false),
            ] {
                let p = (e, n);
                assert_eq!(winding(p, &outline) != 0, inside, "non-zero at {n}, {e}");
                assert_eq!(
                    crossings(p, &outline) % 2 == 1,
                    inside,
                    "even-odd at {n}, {e}"
                );
            }
        }
        assert!(keyhole_ring(&[]).is_empty());
    }
}
