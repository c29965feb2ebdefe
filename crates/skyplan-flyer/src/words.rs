//! A flight told in words and rows: one line per executor note, simulator note and ground-station
//! update (what `skyplan fly` and `skyplan sim` print), and the flight log as CSV.
//!
//! Pure functions: the caller decides where the text goes.
//!
//! ```
//! use skyplan_flight::executor::{FlightState, Note};
//! let note = Note::State { from: FlightState::Arming, to: FlightState::Takeoff };
//! assert_eq!(
//!     skyplan_flyer::words::note_line(3.5, 4, &note).as_deref(),
//!     Some("state          3.5 s  ARMING → TAKEOFF")
//! );
//! ```

use skyplan_flight::executor::{FailsafeAction, FlightState, Note, TrackingReport};
use skyplan_flight::sensing::ReplanEvent;
use skyplan_link::ground::{LogRow, Progress, Update};
use skyplan_link::vehicle::SimNote;

/// How an executor note reads (`None`: not worth a line); `n` is the number of waypoints.
pub fn note_line(t: f64, n: usize, note: &Note) -> Option<String> {
    Some(match note {
        Note::State { from, to } => format!("state      {t:7.1} s  {from} → {to}"),
        Note::Reached(r) => format!(
            "waypoint   {:7.1} s  {} of {n} reached: {:.2} m off, heading off {:.1}°",
            r.time_s,
            r.index + 1,
            r.horizontal_error_m,
            r.heading_error_rad.to_degrees()
        ),
        Note::Refused { command, reason } => format!("refused    {t:7.1} s  {command}: {reason}"),
        Note::LinkLost {
            state,
            silent_s,
            wait_s,
            action,
        } => format!(
            "link       {t:7.1} s  lost in {state}: no heartbeat for {silent_s:.1} s; sending nothing, waiting up to {wait_s:.1} s for it to return (--failsafe {action})"
        ),
        Note::LinkRegained { silent_s, action } => format!(
            "link       {t:7.1} s  back after {silent_s:.1} s: commanding {}",
            match action {
                FailsafeAction::Land => "LAND (--failsafe land)",
                FailsafeAction::ReturnToLaunch => "RTL (--failsafe rtl)",
                FailsafeAction::Hold => "LOITER (--failsafe hold)",
                FailsafeAction::Return => "the planned way home (--failsafe return)",
            }
        ),
        Note::Replanned { event, targets } => format!(
            "replan     {t:7.1} s  at N {:.1} m, E {:.1} m: {} ({}, {:.2} ms{}, {} expansions, {} learned cells): new route of {} waypoints, {:.1} m",
            event.position_ned[0],
            event.position_ned[1],
            event.reason,
            event.planner,
            event.latency_ms,
            event
                .cpu_ms
                .map_or(String::new(), |c| format!(", CPU {c:.2} ms")),
            event.expansions,
            event.learned_cells,
            targets.len(),
            event.route_length_m
        ),
        Note::Holding { reason, hold_s } => {
            format!(
                "hold       {t:7.1} s  no route: {reason}; holding {hold_s:.1} s (and until at rest), then landing"
            )
        }
        Note::ByWaypoints { reason } => {
            format!("replan     {t:7.1} s  {reason}: flying the new route by waypoints")
        }
        Note::WayHomeWanted { reason } => {
            format!("home       {t:7.1} s  {reason}: holding while the way home is planned")
        }
        Note::ReturningHome {
            targets,
            length_m,
            planner,
        } => {
            let last = targets.last().map_or(String::new(), |w| {
                format!(" to N {:.1} m, E {:.1} m", w.north_m, w.east_m)
            });
            format!(
                "home       {t:7.1} s  way home by {planner}: {} waypoints, {length_m:.1} m{last}, flown in GUIDED, landing there",
                targets.len()
            )
        }
        Note::NoWayHome { reason } => {
            format!("home       {t:7.1} s  no way home ({reason}): landing where it is")
        }
        Note::Finished => return None,
    })
}

/// How a flight by a reference went: the largest tracking error, the reference's duration and
/// the time flown on it (from its clock's start to the arrival at its end) with their ratio.
///
/// ```
/// use skyplan_flight::executor::TrackingReport;
/// let r = TrackingReport {
///     duration_s: 50.0,
///     started_s: Some(8.0),
///     flown_s: Some(50.5),
///     max_tracking_error_m: 0.031,
///     max_path_error_m: 0.02,
///     samples: 480,
///     setpoints_sent: 790,
///     switches: 0,
///     slowest_switch_ms: 0.0,
///     by_waypoints_from_s: None,
/// };
/// assert_eq!(
///     skyplan_flyer::words::tracking_line(&r),
///     "reference  max tracking error 0.03 m over 480 samples (0.02 m from its path); reference duration 50.0 s, flown 50.5 s on it (1.010 of its duration); 790 setpoints sent"
/// );
/// ```
pub fn tracking_line(r: &TrackingReport) -> String {
    let flown = match (r.started_s, r.flown_s, r.time_ratio()) {
        (_, Some(f), Some(ratio)) => format!("flown {f:.1} s on it ({ratio:.3} of its duration)"),
        (_, Some(f), None) => format!("flown {f:.1} s on it"),
        (Some(_), None, _) => "its end not reached".to_string(),
        (None, None, _) => "its clock never started (the start was not reached)".to_string(),
    };
    let by_waypoints = r.by_waypoints_from_s.map_or(String::new(), |t| {
        format!("; from {t:.1} s on it, a replanned route flown by waypoints")
    });
    let switches = match r.switches {
        0 => String::new(),
        1 => format!(
            "; switched once to a replanned trajectory without stopping (made in {:.1} ms)",
            r.slowest_switch_ms
        ),
        n => format!(
            "; switched {n} times to a replanned trajectory without stopping (each made in at most {:.1} ms)",
            r.slowest_switch_ms
        ),
    };
    format!(
        "reference  max tracking error {:.2} m over {} samples ({:.2} m from its path); reference duration {:.1} s, {flown}; {} setpoints sent{switches}{by_waypoints}",
        r.max_tracking_error_m, r.samples, r.max_path_error_m, r.duration_s, r.setpoints_sent
    )
}

/// How a simulator note reads (`None`: not worth a line).
pub fn sim_note_line(n: &SimNote) -> Option<String> {
    Some(match n {
        SimNote::Connected(p) => format!("ground station connected from {p}"),
        SimNote::Disconnected(why) => format!("ground station left ({why})"),
        SimNote::Mode(m) => format!("mode {m}"),
        SimNote::Armed(true) => "armed".into(),
        SimNote::Armed(false) => "disarmed".into(),
        SimNote::Refused(why) => format!("refused: {why}"),
        SimNote::Takeoff(alt) => format!("taking off to {alt:.1} m"),
        SimNote::Landed => "touched down".into(),
        SimNote::MissionUploaded(n) => format!("mission of {n} items received"),
        SimNote::FenceUploaded(n) => {
            format!("fence of {n} items received and stored (not enabled)")
        }
        SimNote::MissionItemReached(s) => format!("mission item {s} reached"),
        SimNote::Collision(c) => format!(
            "COLLISION at {:.1} s: N {:.2} E {:.2} alt {:.2} m inside obstacle #{}",
            c.time_s, c.point_ned_m[0], c.point_ned_m[1], -c.point_ned_m[2], c.box_index
        ),
        SimNote::GroundStrike(g) => format!(
            "GROUND STRIKE at {:.1} s: N {:.2} E {:.2} alt {:.2} m, flown into the ground",
            g.time_s, g.position_ned_m[0], g.position_ned_m[1], -g.position_ned_m[2]
        ),
        SimNote::Failsafe(why) => format!("failsafe: {why}"),
        SimNote::LinkDropped => "injected fault: the vehicle stops talking".into(),
        SimNote::LinkRestored => "injected fault over: the vehicle talks again".into(),
    })
}

/// How a ground-station update reads, for the updates that are told as one line (status texts,
/// the link closing, time-outs, Ctrl-C, modes); `None` for notes and progress, which the caller
/// shows its own way.
pub fn update_line(u: &Update) -> Option<String> {
    Some(match u {
        Update::StatusText(text) => format!("vehicle    says: {text}"),
        Update::LinkClosed(why) => format!("link       closed: {why}"),
        Update::TimedOut(limit) => format!("timeout    {limit} s wall exceeded: landing"),
        Update::Interrupted(action) => format!(
            "interrupt  Ctrl-C: {}",
            match action {
                FailsafeAction::Land => "landing",
                FailsafeAction::ReturnToLaunch => "returning to launch",
                FailsafeAction::Hold => "holding position (LOITER), then leaving it to the pilot",
                FailsafeAction::Return => "flying the planned way home",
            }
        ),
        Update::Mode(m) => format!("mode       {m}"),
        Update::Warning(w) => format!("sensor     {w}"),
        Update::Notes(..) | Update::Progress(_) | Update::Reading(_) => return None,
    })
}

/// The progress line: distance left and vehicle time.
pub fn progress_message(p: &Progress) -> String {
    format!(
        "{:.1} m left  t {:.1} s",
        p.distance_left_m.max(0.0),
        p.time_s
    )
}

/// Shows values that round to zero as 0.000, not -0.000.
pub fn tidy(x: f64) -> f64 {
    if x.abs() < 0.0005 { 0.0 } else { x }
}

/// The CSV header of the flight log: the telemetry columns, then the replan columns.
pub const LOG_COLUMNS: [&str; 21] = [
    "time_s",
    "state",
    "north_m",
    "east_m",
    "alt_m",
    "heading_deg",
    "ground_speed_m_s",
    "target_index",
    "target_north_m",
    "target_east_m",
    "target_alt_m",
    "target_heading_deg",
    "lat_deg",
    "lon_deg",
    "replan_planner",
    "replan_latency_ms",
    "replan_cpu_ms",
    "replan_expansions",
    "replan_route_length_m",
    "replan_learned_cells",
    "replan_reason",
];

/// The flight log as CSV: [`LOG_COLUMNS`], then a row per telemetry sample (target columns
/// empty when there is no target; `target_index` counts from 1; replan columns empty) and, in
/// time order among them, a row per replan (state `REPLAN`, where the vehicle was, and the
/// replan's planner, latency, CPU time, expansions, new route length, learned cells and reason;
/// the other columns empty).
///
/// ```
/// use skyplan_flight::sensing::ReplanEvent;
/// let replan = ReplanEvent { time_s: 2.0, position_ned: [10.0, 5.0, -5.0],
///     reason: "learned obstacle at N 20.5 E 5.5 blocks the leg to waypoint 2".into(),
///     planner: "dstar-lite".into(), latency_ms: 0.8, cpu_ms: Some(0.7), expansions: 300,
///     route_length_m: 120.0, learned_cells: 9 };
/// let csv = skyplan_flyer::words::log_csv(&[], &[replan]);
/// let row = csv.lines().nth(1).unwrap();
/// assert_eq!(row, "2.000,REPLAN,10.000,5.000,5.000,,,,,,,,,,\"dstar-lite\",0.800,0.700,300,120.0,9,\
///     \"learned obstacle at N 20.5 E 5.5 blocks the leg to waypoint 2\"");
/// ```
pub fn log_csv(log: &[LogRow], replans: &[ReplanEvent]) -> String {
    let mut out = LOG_COLUMNS.join(",");
    out.push('\n');
    let mut events = replans.iter().peekable();
    for r in log {
        while let Some(e) = events.next_if(|e| e.time_s <= r.time_s) {
            out.push_str(&replan_row(e));
        }
        let target = match r.target {
            Some((i, t)) => format!(
                "{},{:.3},{:.3},{:.3},{:.2}",
                i + 1,
                t.north_m,
                t.east_m,
                t.alt_m,
                t.heading_rad.to_degrees()
            ),
            None => ",,,,".to_string(),
        };
        out.push_str(&format!(
            "{:.3},{},{:.3},{:.3},{:.3},{:.2},{:.3},{target},{:.7},{:.7},,,,,,,\n",
            r.time_s,
            FlightState::name(r.state),
            r.north_m,
            r.east_m,
            tidy(r.alt_m),
            r.yaw_rad.to_degrees(),
            r.speed_m_s,
            r.lat_deg,
            r.lon_deg
        ));
    }
    for e in events {
        out.push_str(&replan_row(e));
    }
    out
}

/// One replan as a flight-log row (see [`log_csv`]).
fn replan_row(e: &ReplanEvent) -> String {
    let [n, east, d] = e.position_ned;
    format!(
        "{:.3},REPLAN,{n:.3},{east:.3},{:.3},,,,,,,,,,{},{:.3},{},{},{:.1},{},{}\n",
        e.time_s,
        tidy(-d),
        quoted(&e.planner),
        e.latency_ms,
        e.cpu_ms.map_or(String::new(), |c| format!("{c:.3}")),
        e.expansions,
        e.route_length_m,
        e.learned_cells,
        quoted(&e.reason)
    )
}

/// A CSV field in double quotes (inner quotes doubled).
fn quoted(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "\"\""))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fault_notes_and_progress_read_plainly() {
        let lost = Note::LinkLost {
            state: FlightState::Waypoint,
            silent_s: 1.04,
            wait_s: 6.0,
            action: FailsafeAction::ReturnToLaunch,
        };
        assert_eq!(
            note_line(31.4, 3, &lost).unwrap(),
            "link          31.4 s  lost in WAYPOINT: no heartbeat for 1.0 s; sending nothing, waiting up to 6.0 s for it to return (--failsafe rtl)"
        );
        let back = Note::LinkRegained {
            silent_s: 2.0,
            action: FailsafeAction::Hold,
        };
        assert!(
            note_line(40.0, 3, &back)
                .unwrap()
                .ends_with("back after 2.0 s: commanding LOITER (--failsafe hold)")
        );
        assert_eq!(note_line(1.0, 3, &Note::Finished), None);
        let p = Progress {
            time_s: 12.34,
            state: FlightState::Waypoint,
            reached: 2,
            waypoints: 5,
            distance_left_m: 123.45,
            telemetry: None,
            readings: 0,
            replans: 0,
        };
        assert_eq!(progress_message(&p), "123.5 m left  t 12.3 s");
    }
}
