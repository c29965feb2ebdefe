//! One flight from the ground station's side, for any front end (`skyplan fly`, `skyplan bench
//! --replan`): fly the executor, tell the story line by line to an [`Observer`], sum it up.
//!
//! The observer decides where lines go (a terminal above a progress bar, a live view, nowhere);
//! this module only makes them.

use crate::words::{note_line, tidy, tracking_line, update_line};
use skyplan_flight::executor::{FlightExecutor, Note, Outcome};
use skyplan_frames::LocalFrame;
use skyplan_link::ground::{FlightSummary, GroundError, GroundStation, LogRow, Update};
use skyplan_link::vehicle::{SimReport, SimServerConfig};

/// Where a flight's story goes.
pub trait Observer {
    /// One line of the story (a state change, a reached waypoint, a refusal, a replan, …).
    fn say(&mut self, line: &str);
    /// Every update as it comes, after its line (progress bars, live views, recorders).
    fn update(&mut self, _update: &Update) {}
}

/// An observer that keeps nothing (benchmarks).
pub struct Quiet;

impl Observer for Quiet {
    fn say(&mut self, _line: &str) {}
}

/// A flight flown: its log, how it ended and the ground station's counts.
pub struct Flown {
    /// The flight log, one row per telemetry update.
    pub log: Vec<LogRow>,
    /// `None` when an aborted flight did not land in time.
    pub outcome: Option<Outcome>,
    /// Vehicle time, wall time, messages.
    pub summary: FlightSummary,
}

/// Flies `ex` over `gcs`, telling `observer` each note and update; then tells the summary (time,
/// waypoints reached and their worst errors, where the vehicle is, the result).
pub fn fly<E: FlightExecutor>(
    gcs: &mut GroundStation,
    ex: &mut E,
    frame: &LocalFrame,
    observer: &mut dyn Observer,
) -> Result<Flown, GroundError> {
    // Waypoints of the route being flown (a replan, or the way home, brings a new route).
    let mut n = ex.targets().len();
    let mut summary = gcs.fly(ex, frame, |u| {
        match &u {
            Update::Notes(t, notes) => {
                for note in notes {
                    if let Note::Replanned { targets, .. } | Note::ReturningHome { targets, .. } =
                        note
                    {
                        n = targets.len();
                    }
                    if let Some(line) = note_line(*t, n, note) {
                        observer.say(&line);
                    }
                }
            }
            other => {
                if let Some(line) = update_line(other) {
                    observer.say(&line);
                }
            }
        }
        observer.update(&u);
    })?;
    for line in summary_lines(&summary, ex) {
        observer.say(&line);
    }
    let log = std::mem::take(&mut summary.log);
    Ok(Flown {
        log,
        outcome: ex.outcome().cloned(),
        summary,
    })
}

/// The flight summed up: times and counts, how a reference was followed (if flown by one), the
/// vehicle at the end, the result.
pub fn summary_lines<E: FlightExecutor>(summary: &FlightSummary, ex: &E) -> Vec<String> {
    let n = ex.targets().len();
    let reached = ex.reached();
    let worst_h = reached
        .iter()
        .map(|r| r.horizontal_error_m)
        .fold(0.0, f64::max);
    let worst_yaw = reached
        .iter()
        .map(|r| r.heading_error_rad.to_degrees())
        .fold(0.0, f64::max);
    let replans = summary.replans.len();
    // Every replan and a way home start a new route; `n` is the last one's length.
    let how_many = match replans + usize::from(ex.flew_way_home()) {
        0 => format!("{} of {n}", reached.len()),
        r => format!("{} (over {} routes)", reached.len(), r + 1),
    };
    let mut lines = vec![format!(
        "flight     {:.1} s simulated/vehicle time, {:.2} s wall; {how_many} waypoints reached (worst {:.2} m, {:.1}°); {} position targets sent, {} vehicle heartbeats",
        summary.time_s,
        summary.wall_time_s,
        worst_h,
        worst_yaw,
        summary.position_targets_sent,
        summary.heartbeats_received
    )];
    if let Some(r) = ex.tracking() {
        lines.push(tracking_line(&r));
    }
    if let Some(t) = ex.last_telemetry() {
        lines.push(format!(
            "vehicle    at N {:.2} m, E {:.2} m, {:.2} m above home, {}, state {}",
            t.north_m,
            t.east_m,
            tidy(t.alt_m()),
            if t.armed { "ARMED" } else { "disarmed" },
            ex.state()
        ));
    }
    lines.push(match ex.outcome() {
        Some(Outcome::Completed) if ex.tracking().is_some_and(|r| r.by_waypoints_from_s.is_some()) => {
            "result     landed and disarmed after flying the reference, then a replanned route by waypoints to the goal".to_string()
        }
        Some(Outcome::Completed) if ex.tracking().is_some() => {
            "result     landed and disarmed after flying the reference to its end".to_string()
        }
        Some(Outcome::Completed) => {
            format!("result     landed and disarmed after reaching all {n} waypoints")
        }
        Some(Outcome::Failed(f)) => format!("result     FAILED: {f}"),
        None => "result     FAILED: gave up waiting for the landing".to_string(),
    });
    lines
}

/// The simulator's account of the flown track: its length, its closest approach to an obstacle
/// and the route's safety margin `margin_m` (if known), or the collision.
pub fn track_line(report: &SimReport, margin_m: Option<f64>) -> String {
    let margin = margin_m.map_or(String::new(), |m| format!(", safety margin {m} m"));
    let clearance = match report.track.closest() {
        Some(c) => format!(
            "closest obstacle {:.2} m ({}) at {:.1} s{margin}",
            c.clearance_m,
            obstacle_name(report, c.box_index),
            c.time_s
        ),
        None => format!("no obstacle within 20 m{margin}"),
    };
    let hidden = report.hidden_boxes;
    match report.track.collision() {
        Some(c) => format!(
            "track      COLLISION: {} samples inside obstacles, first at {:.1} s ({})",
            report.track.colliding_samples(),
            c.time_s,
            obstacle_name(report, c.box_index)
        ),
        None => {
            let what = match hidden {
                0 => "the map's obstacles".to_string(),
                1 => "the map's obstacles or the hidden building".to_string(),
                n => format!("the map's obstacles or the {n} hidden buildings"),
            };
            format!(
                "track      flown {:.1} m, max altitude {:.2} m, no collision with {what} ({clearance})",
                report.distance_m, report.max_alt_m
            )
        }
    }
}

/// An obstacle of the simulated world by its index: a map obstacle (a footprint map's building
/// by its feature in the file), or a hidden building.
pub fn obstacle_name(report: &SimReport, box_index: usize) -> String {
    let hidden = report.hidden_boxes;
    match box_index.checked_sub(report.map_boxes) {
        Some(k) if hidden > 0 => format!("hidden building #{} of {hidden}", k + 1),
        _ => match report.map_features.get(box_index) {
            Some(feature) => format!("the building of feature {feature}"),
            None => format!("map obstacle #{box_index}"),
        },
    }
}

/// The simulator's account when it starts (`skyplan sim`): where it listens, how fast, where
/// the vehicle is, what the track is checked against (the map and the hidden obstacles, read from
/// `hidden_from`) and what its sensor sees.
///
/// ```
/// use skyplan_frames::Lla;
/// use skyplan_link::vehicle::SimServerConfig;
/// let home = Lla { lat_deg: 37.5, lon_deg: -122.25, alt_m: 0.0 };
/// let config = SimServerConfig { speedup: 2.0, ..SimServerConfig::at(home) };
/// let line = skyplan_flyer::flight::sim_listening_line("tcp:127.0.0.1:5760", &config, "city.csv", None);
/// assert!(line.contains("listening on tcp:127.0.0.1:5760, 2× real time, home lat 37.5000000, lon -122.2500000;"));
/// assert!(line.ends_with("obstacles from city.csv; OBSTACLE_DISTANCE at 10 Hz, range 30 m"));
/// ```
pub fn sim_listening_line(
    listening: &str,
    config: &SimServerConfig,
    map_name: &str,
    hidden_from: Option<&str>,
) -> String {
    let hidden = match (hidden_from, config.hidden.len()) {
        (Some(from), 1) => format!(" and 1 hidden obstacle from {from}"),
        (Some(from), n) => format!(" and {n} hidden obstacles from {from}"),
        (None, _) => String::new(),
    };
    let ground = match config.terrain {
        Some(_) => format!(
            ", on the DEM's ground ({:.1} m above sea level there)",
            config.home.alt_m
        ),
        None => String::new(),
    };
    format!(
        "sim        simulated multicopter (MAVLink system 1, ArduCopter modes) listening on {listening}, \
         {}× real time, home lat {:.7}, lon {:.7}{ground}; obstacles from {map_name}{hidden}; OBSTACLE_DISTANCE at 10 Hz, range {} m",
        config.speedup, config.home.lat_deg, config.home.lon_deg, config.sensor_range_m
    )
}

/// The simulator's account when it stops (`skyplan sim`): times, distance, and any collision
/// (with a map box, or with a hidden one: those come after the map's `map_boxes`).
pub fn sim_stopped_line(report: &SimReport, map_boxes: usize) -> String {
    format!(
        "sim        stopped after {:.1} s simulated, {:.1} s wall; flown {:.1} m, {}",
        report.sim_time_s,
        report.wall_time_s,
        report.distance_m,
        match report.track.collision() {
            Some(c) if c.box_index >= map_boxes => format!(
                "COLLISION with hidden obstacle #{} at {:.1} s",
                c.box_index - map_boxes,
                c.time_s
            ),
            Some(c) => format!(
                "COLLISION with obstacle #{} at {:.1} s",
                c.box_index, c.time_s
            ),
            None => "no collision".into(),
        }
    )
}

/// Whether a note moves the progress bar: the index of a reached waypoint.
pub fn reached_index(note: &Note) -> Option<usize> {
    match note {
        Note::Reached(r) => Some(r.index),
        _ => None,
    }
}

/// The lowest a flight flew above the ground over terrain, once on its way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowPoint {
    /// Height above the ground there, metres.
    pub above_ground_m: f64,
    /// When, seconds of the log.
    pub time_s: f64,
    /// Where, metres north and east of the map's home.
    pub ne_m: [f64; 2],
}

/// The lowest height above `terrain`'s ground of the logged positions flying the route (state
/// WAYPOINT, the first waypoint reached: the climb from the ground and the descent to it are
/// not counted); `None` without such rows or where the DEM does not reach any of them.
///
/// ```
/// use skyplan_flight::executor::{FlightState, Target};
/// use skyplan_flyer::flight::lowest_over_ground;
/// use skyplan_link::ground::LogRow;
/// use skyplan_map::terrain::{Dem, Terrain};
/// use skyplan_frames::{Lla, LocalFrame};
/// // Ground rising 1 m per ~100 m east (3 × 3 samples, 0.001° apart).
/// let dem = Dem::geographic(3, 3, vec![0.0, 1.0, 2.0, 0.0, 1.0, 2.0, 0.0, 1.0, 2.0], [-84.001, 36.001], [0.001, 0.001])?;
/// let t = Terrain::new(dem, LocalFrame::new(Lla { lat_deg: 36.0, lon_deg: -84.0, alt_m: 0.0 })?)?;
/// let target = Target { north_m: 0.0, east_m: 80.0, alt_m: 30.0, heading_rad: 0.0 };
/// let row = |time_s: f64, east_m: f64, alt_m: f64, to: usize| LogRow {
///     time_s, state: FlightState::Waypoint, lat_deg: 36.0, lon_deg: -84.0, north_m: 0.0,
///     east_m, alt_m, yaw_rad: 0.0, speed_m_s: 5.0, target: Some((to, target)),
/// };
/// // The first row still climbs to the first waypoint: not counted.
/// let log = [row(0.0, 0.0, 20.0, 0), row(1.0, 0.0, 30.0, 1), row(2.0, 80.0, 30.0, 1)];
/// let low = lowest_over_ground(&log, &t).unwrap();
/// assert_eq!(low.time_s, 2.0);
/// assert!((low.above_ground_m - (30.0 - 80.0 / 89.9)).abs() < 0.05, "{low:?}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn lowest_over_ground(
    log: &[LogRow],
    terrain: &skyplan_map::terrain::Terrain,
) -> Option<LowPoint> {
    use skyplan_flight::executor::FlightState;
    log.iter()
        .filter(|r| {
            r.state == FlightState::Waypoint && r.target.is_some_and(|(index, _)| index >= 1)
        })
        .filter_map(|r| {
            let ground_m = terrain.ground_m(r.north_m, r.east_m).ok()?;
            Some(LowPoint {
                above_ground_m: r.alt_m - ground_m,
                time_s: r.time_s,
                ne_m: [r.north_m, r.east_m],
            })
        })
        .min_by(|a, b| a.above_ground_m.total_cmp(&b.above_ground_m))
}
