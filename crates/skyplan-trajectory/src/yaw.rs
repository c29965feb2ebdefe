//! Yaw along the direction of travel: held over each piece, turned between pieces by a cubic
//! smoothstep (rate zero at both ends) whose duration puts its proven rate bound at the limit.

use crate::bezier::{hodograph, hull_max, norm};
use crate::check::BOUND_DEPTH;
use crate::{Piece, YawPiece, wrap_rad};
use skyplan_world3::Neu;

/// The heading of each piece's chord (the previous heading for a vertical piece).
fn headings(pieces: &[Piece]) -> Vec<f64> {
    let mut out = Vec::with_capacity(pieces.len());
    let mut last: Option<f64> = None;
    for p in pieces {
        let c = &p.control_points_neu;
        let (a, b) = (c[0], c[c.len() - 1]);
        let (dn, de) = (b[0] - a[0], b[1] - a[1]);
        if dn.hypot(de) > 1e-6 {
            last = Some(de.atan2(dn));
        }
        out.push(last.unwrap_or(f64::NAN));
    }
    // Pieces before the first horizontal one take its heading (0 if none moves sideways).
    let first = out.iter().copied().find(|h| h.is_finite()).unwrap_or(0.0);
    out.iter()
        .map(|&h| if h.is_finite() { h } else { first })
        .collect()
}

/// The shortest duration of a smoothstep turn by `delta_rad` whose hull bound on the rate is at
/// most `max_rate_rad_s`.
fn turn_duration_s(delta_rad: f64, max_rate_rad_s: f64) -> f64 {
    let c: Vec<Neu> = [0.0, 0.0, delta_rad, delta_rad]
        .iter()
        .map(|&v| [v, 0.0, 0.0])
        .collect();
    hull_max(&hodograph(&c, 1.0), BOUND_DEPTH, &norm) / max_rate_rad_s * (1.0 + 1e-9)
}

fn hold(duration_s: f64, y: f64) -> YawPiece {
    YawPiece {
        duration_s,
        control_points_rad: [y; 4],
    }
}

/// Yaw pieces covering the same total time as `pieces`, starting at `start_yaw_rad` (turned to
/// the first piece's heading at once) or, without one, at the first piece's heading.
pub(crate) fn profile(
    pieces: &[Piece],
    max_rate_rad_s: f64,
    start_yaw_rad: Option<f64>,
) -> Vec<YawPiece> {
    let total: f64 = pieces.iter().map(|p| p.duration_s).sum();
    let heads = headings(pieces);
    let mut out = Vec::new();
    let first = heads.first().copied().unwrap_or(0.0);
    let mut yaw = start_yaw_rad.unwrap_or(first);
    let mut now = 0.0; // where the yaw profile has reached
    let delta = wrap_rad(first - yaw);
    if delta.abs() >= 1e-9 {
        let d = turn_duration_s(delta, max_rate_rad_s).min(total);
        out.push(YawPiece {
            duration_s: d,
            control_points_rad: [yaw, yaw, yaw + delta, yaw + delta],
        });
        yaw += delta;
        now = d;
    }
    let mut junction = 0.0;
    for (k, p) in pieces.iter().enumerate() {
        junction += p.duration_s;
        let Some(&next) = heads.get(k + 1) else {
            break;
        };
        let delta = wrap_rad(next - yaw);
        if delta.abs() < 1e-9 {
            continue;
        }
        let d = turn_duration_s(delta, max_rate_rad_s);
        // Centred on the junction, after the last turn, and inside the trajectory.
        let start = (junction - d / 2.0).max(now).min(total - d);
        if start < now {
            continue; // no room left to turn: keep the heading
        }
        if start > now {
            out.push(hold(start - now, yaw));
        }
        out.push(YawPiece {
            duration_s: d,
            control_points_rad: [yaw, yaw, yaw + delta, yaw + delta],
        });
        yaw += delta;
        now = start + d;
    }
    if total > now {
        out.push(hold(total - now, yaw));
    }
    out
}
