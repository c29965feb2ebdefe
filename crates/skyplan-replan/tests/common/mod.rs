//! A fake flight loop for the tests and the example: a point flies the targets at a constant
//! speed, a range sensor is simulated by casting rays against the true boxes (an independent
//! ray caster), the replanner is fed every reading, and routes are swapped on `Replace`.
#![allow(dead_code)]

use skyplan_flight::executor::Target;
use skyplan_flight::sensing::{ObstacleReading, RouteDecision, RouteWatcher, SectorRange};
use skyplan_map::colliders::ObstacleBox;
use skyplan_plan::FCND_DEFAULT_GOAL_NE;
use skyplan_replan::hidden::HiddenSpec;
use skyplan_search::MoveModel;

/// Sensor: 72 sectors of 5° from north, 30 m.
pub const SECTORS: usize = 72;
pub const RANGE_M: f64 = 30.0;

/// How a flight ended.
pub struct Flight {
    pub reached_goal: bool,
    pub hold: Option<String>,
    pub track: Vec<[f64; 3]>,
    pub replans: Vec<skyplan_flight::sensing::ReplanEvent>,
}

/// The distance along a horizontal ray from `(n, e)` at `alt_m` to the first box, if within
/// `max_m` (slab test on the box's footprint; boxes not spanning the altitude are ignored).
pub fn cast(
    boxes: &[ObstacleBox],
    n: f64,
    e: f64,
    alt_m: f64,
    bearing_rad: f64,
    max_m: f64,
) -> Option<f64> {
    let (dn, de) = (bearing_rad.cos(), bearing_rad.sin());
    let mut best: Option<f64> = None;
    for b in boxes {
        if !(b.bottom_m() <= alt_m && alt_m <= b.top_m()) {
            continue;
        }
        let (mut t0, mut t1) = (0.0f64, max_m);
        let mut ok = true;
        for (p, d, c, h) in [
            (n, dn, b.north_m, b.half_north_m),
            (e, de, b.east_m, b.half_east_m),
        ] {
            if d.abs() < 1e-12 {
                if (p - c).abs() > h {
                    ok = false;
                }
            } else {
                let (a, z) = ((c - h - p) / d, (c + h - p) / d);
                let (lo, hi) = if a < z { (a, z) } else { (z, a) };
                t0 = t0.max(lo);
                t1 = t1.min(hi);
            }
        }
        if ok && t0 <= t1 && best.is_none_or(|x| t0 < x) {
            best = Some(t0);
        }
    }
    best
}

/// One sweep of the simulated sensor at a position (north, east, alt).
pub fn sense(boxes: &[ObstacleBox], p: [f64; 3], time_s: f64) -> ObstacleReading {
    let near: Vec<ObstacleBox> = boxes
        .iter()
        .filter(|b| {
            (b.north_m - p[0]).abs() <= b.half_north_m + RANGE_M
                && (b.east_m - p[1]).abs() <= b.half_east_m + RANGE_M
        })
        .copied()
        .collect();
    let inc = (360.0 / SECTORS as f64).to_radians();
    let ranges = (0..SECTORS)
        .map(
            |i| match cast(&near, p[0], p[1], p[2], inc * i as f64, RANGE_M) {
                Some(d) => SectorRange::Obstacle(d),
                None => SectorRange::Clear,
            },
        )
        .collect();
    ObstacleReading {
        time_s,
        position_ned: [p[0], p[1], -p[2]],
        velocity_ned_m_s: [0.0; 3],
        first_bearing_rad: 0.0,
        increment_rad: inc,
        min_range_m: 0.2,
        max_range_m: RANGE_M,
        ranges,
    }
}

/// True if the segment `a → b` meets the box grown by `grow_m` on every axis (3D slab test).
pub fn segment_meets_box(a: [f64; 3], b: [f64; 3], bx: &ObstacleBox, grow_m: f64) -> bool {
    let centre = [bx.north_m, bx.east_m, bx.up_m];
    let half = [
        bx.half_north_m + grow_m,
        bx.half_east_m + grow_m,
        bx.half_up_m + grow_m,
    ];
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let d = b[k] - a[k];
        let (lo, hi) = (centre[k] - half[k], centre[k] + half[k]);
        if d.abs() < 1e-12 {
            if a[k] < lo || a[k] > hi {
                return false;
            }
        } else {
            let (u, v) = ((lo - a[k]) / d, (hi - a[k]) / d);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
    }
    t0 <= t1
}

/// Flies `targets` at `speed_m_s`, a reading every `dt_s`, until the last target is reached, a
/// hold, or `max_time_s`.
pub fn fly(
    watcher: &mut dyn RouteWatcher,
    mut targets: Vec<Target>,
    truth: &[ObstacleBox],
    start: [f64; 3],
    speed_m_s: f64,
    dt_s: f64,
    max_time_s: f64,
) -> Flight {
    let mut p = start;
    let mut track = vec![p];
    let mut replans = Vec::new();
    let mut t = 0.0;
    let mut next = 0;
    while t < max_time_s {
        let reading = sense(truth, p, t);
        match watcher.on_reading(&reading, &targets[next..]) {
            RouteDecision::Keep => {}
            RouteDecision::Replace {
                targets: new,
                event,
            } => {
                assert!(!new.is_empty(), "an empty route replaced the old one");
                targets = new;
                next = 0;
                replans.push(event);
            }
            RouteDecision::Hold { reason } => {
                return Flight {
                    reached_goal: false,
                    hold: Some(reason),
                    track,
                    replans,
                };
            }
        }
        let mut budget = speed_m_s * dt_s;
        while budget > 0.0 && next < targets.len() {
            let g = &targets[next];
            let d = [g.north_m - p[0], g.east_m - p[1], g.alt_m - p[2]];
            let dist = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if dist <= budget {
                p = [g.north_m, g.east_m, g.alt_m];
                budget -= dist;
                next += 1;
            } else {
                let s = budget / dist;
                p = [p[0] + s * d[0], p[1] + s * d[1], p[2] + s * d[2]];
                budget = 0.0;
            }
        }
        track.push(p);
        t += dt_s;
        if next == targets.len() {
            return Flight {
                reached_goal: true,
                hold: None,
                track,
                replans,
            };
        }
    }
    Flight {
        reached_goal: false,
        hold: None,
        track,
        replans,
    }
}

/// A route's north/east points (from a plan's waypoints).
pub fn route_ne(waypoints: &[[f64; 4]]) -> Vec<[f64; 2]> {
    waypoints.iter().map(|w| [w[0], w[1]]).collect()
}

/// `count` hidden buildings (seeded) on or near `route_ne` in the city: start at home, the default
/// goal, 5 m altitude, 5 m margin, reachability on 1 m octile cells.
pub fn city_hidden_spec(route_ne: Vec<[f64; 2]>, count: usize, seed: u64) -> HiddenSpec {
    HiddenSpec {
        count,
        seed,
        route_ne,
        start_ne: [0.0, 0.0],
        goal_ne: FCND_DEFAULT_GOAL_NE,
        alt_m: 5.0,
        safety_m: 5.0,
        cell_m: 1.0,
        model: MoveModel::Octile,
    }
}

/// The length of a flown track, metres (3D).
pub fn track_length_m(track: &[[f64; 3]]) -> f64 {
    track
        .windows(2)
        .map(|w| {
            ((w[1][0] - w[0][0]).powi(2)
                + (w[1][1] - w[0][1]).powi(2)
                + (w[1][2] - w[0][2]).powi(2))
            .sqrt()
        })
        .sum()
}

/// The first segment of `track` that meets a box of `boxes` grown by `grow_m`, with that box.
pub fn first_collision<'a>(
    track: &[[f64; 3]],
    boxes: &'a [ObstacleBox],
    grow_m: f64,
) -> Option<([f64; 3], [f64; 3], &'a ObstacleBox)> {
    track.windows(2).find_map(|w| {
        boxes
            .iter()
            .find(|b| segment_meets_box(w[0], w[1], b, grow_m))
            .map(|b| (w[0], w[1], b))
    })
}
