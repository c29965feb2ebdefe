//! A plan's trajectory in its pictures: the flown curve coloured by speed over the map, and a
//! panel of speed and acceleration against time with the limits as dashed lines.

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::HPos;

use crate::PlotError;
use crate::profile::Panel;
use crate::text::{Label, TextMode, VAlign, draw_label};

/// The trajectory is sampled this often for pictures, seconds.
pub(crate) const TRACE_STEP_S: f64 = 0.05;
/// Levels of the speed scale a drawn run of the curve keeps one colour over.
const RUN_LEVELS: f64 = 64.0;
/// The casing drawn under the coloured curve, so that its light end reads on white.
const CASING_COLOR: RGBColor = RGBColor(30, 30, 30);
const LIMIT_COLOR: RGBColor = RGBColor(222, 30, 30);
const ACCEL_COLOR: RGBColor = RGBColor(214, 96, 20);

/// The colour of `speed_m_s` on the trajectory's speed scale, which runs from 0 (viridis' dark
/// blue-purple) to `max_speed_m_s` (its yellow); speeds are clamped to the scale.
///
/// ```
/// use skyplan_plot::speed_color;
/// assert_eq!(speed_color(0.0, 10.0), [68, 1, 84]);
/// assert_eq!(speed_color(10.0, 10.0), [253, 231, 37]);
/// assert_eq!(speed_color(12.0, 10.0), speed_color(10.0, 10.0));
/// ```
pub fn speed_color(speed_m_s: f64, max_speed_m_s: f64) -> [u8; 3] {
    let f = if max_speed_m_s > 0.0 {
        (speed_m_s / max_speed_m_s).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let f = if f.is_nan() { 0.0 } else { f };
    crate::heatmap::viridis((f * 255.0).round() as u8)
}

fn rgb([r, g, b]: [u8; 3]) -> RGBColor {
    RGBColor(r, g, b)
}

/// One sample of the trajectory.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TracePoint {
    pub t_s: f64,
    pub north_m: f64,
    pub east_m: f64,
    pub speed_m_s: f64,
    pub accel_m_s2: f64,
}

/// The trajectory sampled densely, with the limits the picture draws.
#[derive(Debug, Clone)]
pub(crate) struct SpeedTrace {
    pub points: Vec<TracePoint>,
    pub duration_s: f64,
    pub max_speed_m_s: f64,
    pub max_accel_m_s2: f64,
}

impl SpeedTrace {
    /// The report's trajectory sampled every [`TRACE_STEP_S`] and at its end.
    pub(crate) fn of(report: &skyplan_plan::TrajectoryReport) -> Result<Self, PlotError> {
        let traj = &report.trajectory;
        let duration_s = traj.duration_s();
        let limits = &traj.limits;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let ok = duration_s.is_finite()
            && duration_s >= 0.0
            && positive(limits.max_speed_m_s)
            && positive(limits.max_accel_m_s2);
        if !ok {
            return Err(PlotError::BadScene {
                what: "the trajectory's duration or limits are not positive finite numbers",
            });
        }
        let n = (duration_s / TRACE_STEP_S).ceil() as usize;
        let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let points: Vec<TracePoint> = (0..=n)
            .map(|i| {
                let s = traj.state_at((i as f64 * TRACE_STEP_S).min(duration_s));
                TracePoint {
                    t_s: s.t_s,
                    north_m: s.point_neu[0],
                    east_m: s.point_neu[1],
                    speed_m_s: norm(s.vel_neu_m_s),
                    accel_m_s2: norm(s.accel_neu_m_s2),
                }
            })
            .collect();
        let finite = |p: &TracePoint| {
            [p.t_s, p.north_m, p.east_m, p.speed_m_s, p.accel_m_s2]
                .iter()
                .all(|v| v.is_finite())
        };
        if !points.iter().all(finite) {
            return Err(PlotError::BadScene {
                what: "a trajectory sample is not finite",
            });
        }
        Ok(SpeedTrace {
            points,
            duration_s,
            max_speed_m_s: limits.max_speed_m_s,
            max_accel_m_s2: limits.max_accel_m_s2,
        })
    }

    /// The colour of a speed on this trajectory's scale.
    pub(crate) fn color(&self, speed_m_s: f64) -> RGBColor {
        rgb(speed_color(speed_m_s, self.max_speed_m_s))
    }

    /// The legend's text for the speed scale.
    pub(crate) fn legend_text(&self) -> String {
        format!(
            "trajectory, speed 0 → {:.1} m/s (limit)",
            self.max_speed_m_s
        )
    }

    /// Runs of the curve with one colour each: every run ends where the next one starts.
    fn runs(&self) -> Vec<(RGBColor, Vec<&TracePoint>)> {
        let level = |p: &TracePoint| (p.speed_m_s / self.max_speed_m_s * RUN_LEVELS).round() as i64;
        let mut runs: Vec<(i64, Vec<&TracePoint>)> = Vec::new();
        for w in self.points.windows(2) {
            let l = level(&w[0]).max(level(&w[1]));
            match runs.last_mut() {
                Some((rl, pts)) if *rl == l => pts.push(&w[1]),
                _ => runs.push((l, vec![&w[0], &w[1]])),
            }
        }
        runs.into_iter()
            .map(|(l, pts)| {
                let speed = l as f64 / RUN_LEVELS * self.max_speed_m_s;
                (self.color(speed), pts)
            })
            .collect()
    }
}

/// A chart with east right and north up, metres.
pub(crate) type MapChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The curve over a map, `width` pixels wide, coloured by speed over a dark casing.
pub(crate) fn draw_on_map<DB: DrawingBackend>(
    chart: &mut MapChart<'_, DB>,
    trace: &SpeedTrace,
    width: u32,
) -> Result<(), PlotError> {
    let en = |p: &TracePoint| (p.east_m, p.north_m);
    chart
        .draw_series(std::iter::once(PathElement::new(
            trace.points.iter().map(en).collect::<Vec<_>>(),
            CASING_COLOR.stroke_width(width + 2),
        )))
        .map_err(err)?;
    chart
        .draw_series(trace.runs().into_iter().map(|(color, pts)| {
            PathElement::new(
                pts.into_iter().map(en).collect::<Vec<_>>(),
                color.stroke_width(width),
            )
        }))
        .map_err(err)?;
    Ok(())
}

/// The legend's sample of the speed scale: slow at the left, fast at the right.
pub(crate) fn draw_scale_sample<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    trace: &SpeedTrace,
    (x, cy): (i32, i32),
    (w, half_h): (i32, i32),
) -> Result<(), PlotError> {
    for i in 0..w.max(1) {
        let f = f64::from(i) / f64::from((w - 1).max(1));
        let color = trace.color(f * trace.max_speed_m_s);
        let column = vec![(x + i, cy - half_h), (x + i, cy + half_h)];
        root.draw(&PathElement::new(column, color)).map_err(err)?;
    }
    Ok(())
}

/// The height of the panel strip under a map `width_px` wide, pixels.
pub(crate) fn panel_height(width_px: u32) -> u32 {
    (width_px * 2 / 5).clamp(160, 600)
}

/// Speed and acceleration against time, side by side on `area` (the strip under the map), with
/// the limits dashed and labelled. `font` is the axis titles' size.
pub(crate) fn draw_panels<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    trace: &SpeedTrace,
    mode: TextMode,
    font: f64,
) -> Result<(), PlotError> {
    area.fill(&WHITE).map_err(err)?;
    let (w, h) = area.dim_in_pixel();
    let (w, h) = (w as i32, h as i32);
    let left = (4.6 * font) as i32;
    let top = (1.0 * font) as i32;
    let bottom = (3.6 * font) as i32;
    let gap = (1.6 * font) as i32;
    let pw = ((w - 2 * left - gap - (2.0 * font) as i32) / 2).max(20);
    let ph = (h - top - bottom).max(20);
    let t_max = trace.duration_s.max(1e-3);
    let peak = |f: fn(&TracePoint) -> f64| trace.points.iter().map(f).fold(0.0, f64::max);
    let speed_top = peak(|p| p.speed_m_s).max(trace.max_speed_m_s) * 1.25;
    let accel_top = peak(|p| p.accel_m_s2).max(trace.max_accel_m_s2) * 1.25;
    let speed = Panel {
        x0: left,
        y0: top,
        w: pw,
        h: ph,
        xr: (0.0, t_max),
        yr: (0.0, speed_top),
    };
    let accel = Panel {
        x0: left + pw + gap + left,
        yr: (0.0, accel_top),
        ..speed
    };
    let stroke = ((font / 18.0) * 2.5).round().max(1.0) as u32;
    for (panel, limit, label, y_title, value) in [
        (
            &speed,
            trace.max_speed_m_s,
            format!("speed limit {:.1} m/s", trace.max_speed_m_s),
            "SPEED (m/s)",
            (|p: &TracePoint| p.speed_m_s) as fn(&TracePoint) -> f64,
        ),
        (
            &accel,
            trace.max_accel_m_s2,
            format!("acceleration limit {:.1} m/s²", trace.max_accel_m_s2),
            "ACCELERATION (m/s²)",
            |p: &TracePoint| p.accel_m_s2,
        ),
    ] {
        panel.grid(area, font)?;
        let is_speed = std::ptr::eq(panel, &speed);
        if is_speed {
            // The speed in the map's colours: the panel is the scale's key.
            for (color, pts) in trace.runs() {
                let pts: Vec<_> = pts.iter().map(|p| panel.px(p.t_s, value(p))).collect();
                area.draw(&PathElement::new(pts, color.stroke_width(stroke + 1)))
                    .map_err(err)?;
            }
        } else {
            let pts: Vec<_> = (trace.points.iter())
                .map(|p| panel.px(p.t_s, value(p)))
                .collect();
            area.draw(&PathElement::new(pts, ACCEL_COLOR.stroke_width(stroke)))
                .map_err(err)?;
        }
        let (x0, y) = panel.px(0.0, limit);
        let x1 = panel.x0 + panel.w;
        dashed(area, (x0, x1), y, LIMIT_COLOR.stroke_width(stroke.max(2)))?;
        draw_label(
            area,
            mode,
            &Label {
                text: &label,
                size: font * 0.85,
                at: (x0 + (0.5 * font) as i32, y - (0.5 * font) as i32),
                h: HPos::Left,
                v: VAlign::Baseline,
                vertical: false,
            },
        )?;
        panel.axes(area, mode, font, ("TIME (s)", y_title))?;
    }
    Ok(())
}

/// A horizontal dashed line from `x0` to `x1` at `y`.
fn dashed<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x0, x1): (i32, i32),
    y: i32,
    style: ShapeStyle,
) -> Result<(), PlotError> {
    let (dash, space) = (10, 6);
    let mut x = x0;
    while x < x1 {
        let end = (x + dash).min(x1);
        area.draw(&PathElement::new(vec![(x, y), (end, y)], style))
            .map_err(err)?;
        x += dash + space;
    }
    Ok(())
}

fn err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}
