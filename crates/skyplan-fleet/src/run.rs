//! A fleet run: each mission planned and reserved against the store in order, one record per
//! flight, and the run's statistics.

use crate::flight::{FlightError, FlightRequest, flight_volumes, reserve_flight};
use crate::mission::Mission;
use serde::Serialize;
use skyplan_airspace::{
    DepartureWindow, IntentRef, OperationalIntent, PriorityRule, Timestamp, VolumeOptions,
    first_conflict,
};
use skyplan_airspace_store::{IntentStore, ReserveError, StoreError};
use skyplan_plan::{PlanRequest, Session};
use std::time::Instant;

/// How a flight whose departure conflicts is handled. Its JSON name (`shift`,
/// `reject_on_conflict`, `space_time`) is what reports write and Python takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Its departure moves to the earliest free one of its window.
    Shift,
    /// The baseline: refused when its earliest departure conflicts (detect and reject, as
    /// InterUSS's mock USS does).
    RejectOnConflict,
    /// Re-routed in space and time around the others ([`crate::reserve_space_time`]): a later
    /// departure, hovering and detours, the earliest arrival.
    SpaceTime,
}

impl Mode {
    /// Every mode, in the order `bench --fleet` runs them.
    pub const ALL: [Mode; 3] = [Mode::Shift, Mode::SpaceTime, Mode::RejectOnConflict];

    /// The mode of a JSON name (`"space_time"`), if there is one.
    ///
    /// ```
    /// use skyplan_fleet::Mode;
    /// assert_eq!(Mode::of_key("space_time"), Some(Mode::SpaceTime));
    /// assert_eq!(Mode::of_key("fast"), None);
    /// assert_eq!(Mode::keys(), "shift, space_time, reject_on_conflict");
    /// ```
    pub fn of_key(key: &str) -> Option<Self> {
        serde_json::from_value(serde_json::Value::String(key.to_string())).ok()
    }

    /// The JSON names of every mode, comma-separated (for error messages).
    pub fn keys() -> String {
        Self::ALL
            .iter()
            .filter_map(|m| serde_json::to_value(m).ok())
            .filter_map(|v| v.as_str().map(str::to_string))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The mode's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Shift => "shift departure",
            Self::RejectOnConflict => "reject on conflict",
            Self::SpaceTime => "space-time search",
        }
    }
}

/// How a fleet is flown.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOptions {
    /// Shift or reject.
    pub mode: Mode,
    /// Which stored intents bind a flight.
    pub rule: PriorityRule,
    /// The departure grid's step, milliseconds.
    pub step_ms: i64,
    /// How volumes are made.
    pub volumes: VolumeOptions,
    /// With [`Mode::SpaceTime`]: how long after a flight's start (its planning included) its
    /// answer is due ([`crate::FlightRequest::deadline`]: its search proves the earliest
    /// arrival over half the time left, then heads for the goal, and gives up at four-fifths,
    /// [`Status::TimedOut`]); `None`: never, every arrival proven the earliest.
    pub search_deadline: Option<std::time::Duration>,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            mode: Mode::Shift,
            rule: PriorityRule::EqualOrHigher,
            step_ms: crate::DEPARTURE_STEP_MS,
            volumes: VolumeOptions::default(),
            search_deadline: None,
        }
    }
}

/// What became of a mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Planned and reserved.
    Accepted,
    /// Planned, but no departure of its window is free.
    Refused,
    /// No route (the planner's failure is the record's message).
    NoRoute,
    /// Planned, but its search around the others gave up before the run's deadline, with no
    /// route found (the record's message says after how many states); nothing reserved.
    TimedOut,
}

impl Status {
    /// The status as the report writes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Accepted => "accepted",
            Self::Refused => "refused",
            Self::NoRoute => "no_route",
            Self::TimedOut => "timed_out",
        }
    }
}

/// One flight of a run.
#[derive(Debug, Clone, Serialize)]
pub struct FlightRecord {
    /// The mission's id.
    pub mission: String,
    /// What became of it.
    pub status: Status,
    /// The intent stored (accepted flights).
    pub intent_id: Option<String>,
    /// Its departure (accepted flights).
    pub departure: Option<Timestamp>,
    /// Seconds after its window's earliest departure (accepted flights).
    pub delay_s: Option<f64>,
    /// Its duration, seconds (planned flights).
    pub duration_s: Option<f64>,
    /// Seconds hovering after departure (accepted flights, space-time search).
    pub hover_s: Option<f64>,
    /// Metres longer than the route in an empty sky (accepted flights, space-time search).
    pub detour_m: Option<f64>,
    /// Seconds later at the goal than in an empty sky leaving at the window's start
    /// (accepted flights, space-time search; the delay with the other modes).
    pub arrival_delay_s: Option<f64>,
    /// At most this many seconds later at the goal than the earliest arrival possible
    /// (accepted flights, space-time search): 0 unless its deadline stopped the search proving
    /// the earliest arrival part way.
    pub arrival_gap_s: Option<f64>,
    /// The intents that blocked it (refused flights), sorted by id.
    pub blocking: Vec<IntentRef>,
    /// Why there is no route (`no_route`).
    pub message: Option<String>,
    /// Planning, milliseconds.
    pub plan_ms: f64,
    /// Reserving (search and check-and-insert), milliseconds.
    pub reserve_ms: f64,
    /// Planning and reserving, milliseconds.
    pub latency_ms: f64,
    /// Stored intents read through the index and checked for this flight.
    pub checked: usize,
    /// Intents this run had stored before this flight.
    pub stored_before: usize,
    /// The planned route, (north, east) metres (for pictures).
    #[serde(skip)]
    pub route_ne: Vec<(f64, f64)>,
    /// The intent stored.
    #[serde(skip)]
    pub intent: Option<OperationalIntent>,
}

/// Why a run stopped.
#[derive(Debug, thiserror::Error)]
pub enum FleetError {
    /// The store failed.
    #[error("mission {mission}: {error}")]
    Store {
        /// The mission being reserved.
        mission: String,
        /// The store's error.
        error: StoreError,
    },
    /// A flight's volumes could not be made (a map without a geodetic home, bad options).
    #[error("mission {mission}: {error}")]
    Flight {
        /// The mission.
        mission: String,
        /// Why.
        error: String,
    },
}

/// Plans `mission` (its start, goal and altitude over `base`) in `session` and reserves it in
/// `store`; `stored_before` is recorded as given.
pub fn fly_mission(
    session: &mut Session,
    store: &dyn IntentStore,
    base: &PlanRequest,
    mission: &Mission,
    options: &RunOptions,
    stored_before: usize,
) -> Result<FlightRecord, FleetError> {
    fly_mission_in(session, store, base, mission, options, stored_before, None)
}

/// [`fly_mission`], in [`Mode::SpaceTime`] with the stored intents kept in `cache` (one per
/// run: [`fly_fleet`]).
fn fly_mission_in(
    session: &mut Session,
    store: &dyn IntentStore,
    base: &PlanRequest,
    mission: &Mission,
    options: &RunOptions,
    stored_before: usize,
    cache: Option<&mut crate::SpaceTimeCache>,
) -> Result<FlightRecord, FleetError> {
    crate::refuse_plan_departure(base).map_err(|error| FleetError::Flight {
        mission: mission.id.clone(),
        error,
    })?;
    let t0 = Instant::now();
    let planned = session.plan(&mission.request(base));
    let plan_ms = t0.elapsed().as_secs_f64() * 1e3;
    let mut record = FlightRecord {
        mission: mission.id.clone(),
        status: Status::NoRoute,
        intent_id: None,
        departure: None,
        delay_s: None,
        duration_s: None,
        hover_s: None,
        detour_m: None,
        arrival_delay_s: None,
        arrival_gap_s: None,
        blocking: Vec::new(),
        message: None,
        plan_ms,
        reserve_ms: 0.0,
        latency_ms: plan_ms,
        checked: 0,
        stored_before,
        route_ne: Vec::new(),
        intent: None,
    };
    let plan = match planned {
        Ok(plan) => plan,
        Err(failure) => {
            record.message = Some(failure.message);
            return Ok(record);
        }
    };
    record.route_ne = plan.points_nea().iter().map(|p| (p[0], p[1])).collect();
    let window = match options.mode {
        Mode::Shift | Mode::SpaceTime => mission.window,
        Mode::RejectOnConflict => DepartureWindow::at(mission.window.earliest),
    };
    let request = FlightRequest {
        window,
        priority: mission.priority,
        owner: mission.owner.clone(),
        rule: options.rule,
        step_ms: options.step_ms,
        volumes: options.volumes,
        deadline: options.search_deadline.map(|d| t0 + d),
    };
    let t1 = Instant::now();
    let fail = |error: String| FleetError::Flight {
        mission: mission.id.clone(),
        error,
    };
    if options.mode == Mode::SpaceTime {
        return space_time(
            session,
            store,
            &plan,
            &request,
            record,
            (t0, t1),
            &mission.request(base),
            cache,
            fail,
        );
    }
    let flight = flight_volumes(&plan, &request).map_err(|e: FlightError| fail(e.to_string()))?;
    record.duration_s = Some(flight.duration_s);
    let (result, counts) = reserve_flight(store, &flight, &request);
    record.reserve_ms = t1.elapsed().as_secs_f64() * 1e3;
    record.latency_ms = t0.elapsed().as_secs_f64() * 1e3;
    record.checked = counts.nearby;
    settle(record, result, fail, |record, r| {
        record.arrival_delay_s = Some(r.delay_ms as f64 / 1000.0);
        (r.intent, r.departure, r.delay_ms)
    })
}

/// A record completed by its reservation's outcome: accepted (`accept` fills what the mode
/// knows and gives the intent, departure and delay), refused (the blocking intents), or the
/// run's error.
fn settle<T>(
    mut record: FlightRecord,
    result: Result<T, ReserveError>,
    fail: impl Fn(String) -> FleetError,
    accept: impl FnOnce(&mut FlightRecord, T) -> (OperationalIntent, Timestamp, i64),
) -> Result<FlightRecord, FleetError> {
    match result {
        Ok(r) => {
            let (intent, departure, delay_ms) = accept(&mut record, r);
            record.status = Status::Accepted;
            record.intent_id = Some(intent.id.clone());
            record.departure = Some(departure);
            record.delay_s = Some(delay_ms as f64 / 1000.0);
            record.intent = Some(intent);
        }
        Err(ReserveError::Blocked(b)) => {
            record.status = Status::Refused;
            record.blocking = b.blocking;
        }
        Err(e @ ReserveError::Deadline { .. }) => {
            record.status = Status::TimedOut;
            record.message = Some(e.to_string());
        }
        Err(ReserveError::Invalid(e)) => return Err(fail(e.to_string())),
        Err(ReserveError::Store(error)) => {
            return Err(FleetError::Store {
                mission: record.mission.clone(),
                error,
            });
        }
    }
    Ok(record)
}

/// [`fly_mission`]'s reservation in [`Mode::SpaceTime`].
#[allow(clippy::too_many_arguments)]
fn space_time(
    session: &mut Session,
    store: &dyn IntentStore,
    plan: &skyplan_plan::Plan,
    request: &FlightRequest,
    mut record: FlightRecord,
    (t0, t1): (Instant, Instant),
    planned_for: &PlanRequest,
    cache: Option<&mut crate::SpaceTimeCache>,
    fail: impl Fn(String) -> FleetError,
) -> Result<FlightRecord, FleetError> {
    let Some(grid) = crate::search_grid(session, planned_for, plan).map_err(|f| fail(f.message))?
    else {
        return Err(fail(format!(
            "the space-time search needs a 2D grid planner; {} has no grid",
            plan.planner.name()
        )));
    };
    let (result, nearby) = match cache {
        Some(cache) => crate::reserve_space_time_cached(store, &grid, plan, request, cache),
        None => crate::reserve_space_time(store, &grid, plan, request),
    };
    record.reserve_ms = t1.elapsed().as_secs_f64() * 1e3;
    record.latency_ms = t0.elapsed().as_secs_f64() * 1e3;
    record.checked = nearby;
    settle(record, result, fail, |record, r| {
        record.duration_s = Some(r.flight.duration_s);
        record.hover_s = Some(r.hover_s);
        record.detour_m = Some(r.detour_m);
        record.arrival_delay_s = Some(r.arrival_delay_s);
        record.arrival_gap_s = Some(r.arrival_gap_s);
        record.route_ne = r.route_nea.iter().map(|p| (p[0], p[1])).collect();
        (r.intent, r.departure, r.delay_ms)
    })
}

/// Every mission in order ([`fly_mission`]), calling `progress(k, record)` after the k-th.
pub fn fly_fleet(
    session: &mut Session,
    store: &dyn IntentStore,
    base: &PlanRequest,
    missions: &[Mission],
    options: &RunOptions,
    mut progress: impl FnMut(usize, &FlightRecord),
) -> Result<Vec<FlightRecord>, FleetError> {
    let mut records = Vec::with_capacity(missions.len());
    let mut stored = 0;
    // The stored intents as the space-time search sees them, kept from flight to flight.
    let mut cache = crate::SpaceTimeCache::new();
    for (k, m) in missions.iter().enumerate() {
        let record = fly_mission_in(session, store, base, m, options, stored, Some(&mut cache))?;
        stored += usize::from(record.status == Status::Accepted);
        progress(k, &record);
        records.push(record);
    }
    Ok(records)
}

/// The nearest-rank percentile `p` (0 to 100) of `values` (sorted here); 0 for none.
///
/// ```
/// assert_eq!(skyplan_fleet::percentile(&[3.0, 1.0, 2.0, 4.0], 50.0), 2.0);
/// assert_eq!(skyplan_fleet::percentile(&[3.0, 1.0, 2.0, 4.0], 99.0), 4.0);
/// ```
pub fn percentile(values: &[f64], p: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((p / 100.0) * v.len() as f64).ceil() as usize;
    v[rank.clamp(1, v.len()) - 1]
}

/// Latency over one tenth of the run (flights in order).
#[derive(Debug, Clone, Serialize)]
pub struct Decile {
    /// Flights `from..to` (0-based, in order).
    pub from: usize,
    /// End (exclusive).
    pub to: usize,
    /// Intents stored when the first of them was reserved.
    pub stored_at_start: usize,
    /// Median plan-and-reserve latency, milliseconds.
    pub p50_ms: f64,
    /// 99th percentile, milliseconds.
    pub p99_ms: f64,
    /// Mean intents checked per request.
    pub checked_mean: f64,
}

/// A run's totals.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Missions.
    pub missions: usize,
    /// Accepted.
    pub accepted: usize,
    /// Refused by the others' intents.
    pub refused: usize,
    /// Without a route.
    pub no_route: usize,
    /// Whose search around the others passed its deadline.
    pub timed_out: usize,
    /// Accepted over missions.
    pub share_planned: f64,
    /// Mean delay of the accepted flights, seconds.
    pub delay_mean_s: f64,
    /// 95th percentile of their delay, seconds.
    pub delay_p95_s: f64,
    /// Mean of how much later than alone the accepted flights arrive, seconds (the delay,
    /// plus the hovering and detours of the space-time search).
    pub arrival_delay_mean_s: f64,
    /// Its 95th percentile, seconds.
    pub arrival_delay_p95_s: f64,
    /// Accepted flights whose search did not prove their arrival the earliest (its deadline
    /// stopped the proof part way: [`FlightRecord::arrival_gap_s`]).
    pub unproven: usize,
    /// Their mean bound on how much earlier they could arrive, seconds (0 with none).
    pub arrival_gap_mean_s: f64,
    /// Accepted flights that hover on the way.
    pub hovering: usize,
    /// Accepted flights whose route is more than a metre longer than alone.
    pub detoured: usize,
    /// Median plan-and-reserve latency over every flight, milliseconds.
    pub latency_p50_ms: f64,
    /// Its 99th percentile, milliseconds.
    pub latency_p99_ms: f64,
    /// Mean stored intents read and checked per request (planned flights).
    pub checked_mean: f64,
    /// Most read by one request.
    pub checked_max: usize,
    /// The latency as the store fills, by tenths of the run.
    pub deciles: Vec<Decile>,
}

impl Summary {
    /// The totals of `records`.
    pub fn of(records: &[FlightRecord]) -> Self {
        let accepted: Vec<&FlightRecord> = records
            .iter()
            .filter(|r| r.status == Status::Accepted)
            .collect();
        let delays: Vec<f64> = accepted.iter().filter_map(|r| r.delay_s).collect();
        let arrivals: Vec<f64> = accepted.iter().filter_map(|r| r.arrival_delay_s).collect();
        let gaps: Vec<f64> = accepted
            .iter()
            .filter_map(|r| r.arrival_gap_s)
            .filter(|&g| g > 0.0)
            .collect();
        let latency: Vec<f64> = records.iter().map(|r| r.latency_ms).collect();
        let planned: Vec<&FlightRecord> = records
            .iter()
            .filter(|r| r.status != Status::NoRoute)
            .collect();
        let mean = |v: &[f64]| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let checked: Vec<f64> = planned.iter().map(|r| r.checked as f64).collect();
        let n = records.len();
        let deciles = (0..10)
            .map(|d| (d * n / 10, (d + 1) * n / 10))
            .filter(|(a, b)| b > a)
            .map(|(from, to)| {
                let part = &records[from..to];
                let l: Vec<f64> = part.iter().map(|r| r.latency_ms).collect();
                let c: Vec<f64> = part
                    .iter()
                    .filter(|r| r.status != Status::NoRoute)
                    .map(|r| r.checked as f64)
                    .collect();
                Decile {
                    from,
                    to,
                    stored_at_start: part[0].stored_before,
                    p50_ms: percentile(&l, 50.0),
                    p99_ms: percentile(&l, 99.0),
                    checked_mean: mean(&c),
                }
            })
            .collect();
        let count = |s: Status| records.iter().filter(|r| r.status == s).count();
        Self {
            missions: n,
            accepted: accepted.len(),
            refused: count(Status::Refused),
            no_route: count(Status::NoRoute),
            timed_out: count(Status::TimedOut),
            share_planned: if n == 0 {
                0.0
            } else {
                accepted.len() as f64 / n as f64
            },
            delay_mean_s: mean(&delays),
            delay_p95_s: percentile(&delays, 95.0),
            arrival_delay_mean_s: mean(&arrivals),
            arrival_delay_p95_s: percentile(&arrivals, 95.0),
            unproven: gaps.len(),
            arrival_gap_mean_s: mean(&gaps),
            hovering: accepted
                .iter()
                .filter(|r| r.hover_s.is_some_and(|h| h > 0.0))
                .count(),
            detoured: accepted
                .iter()
                .filter(|r| r.detour_m.is_some_and(|d| d > 1.0))
                .count(),
            latency_p50_ms: percentile(&latency, 50.0),
            latency_p99_ms: percentile(&latency, 99.0),
            checked_mean: mean(&checked),
            checked_max: planned.iter().map(|r| r.checked).max().unwrap_or(0),
            deciles,
        }
    }
}

/// Every pair of `intents` (in the order they were stored) that share a point in space and
/// time although the later one was bound by the earlier under `rule`: brute force over every
/// pair and every pair of volumes with the exact test — the oracle a run is checked against
/// (none is expected).
pub fn binding_conflicts(
    intents: &[OperationalIntent],
    rule: PriorityRule,
) -> Vec<(IntentRef, IntentRef)> {
    let mut out = Vec::new();
    for (j, later) in intents.iter().enumerate() {
        for earlier in &intents[..j] {
            if rule.binds(later.priority, earlier)
                && first_conflict(&later.volumes, &earlier.volumes).is_some()
            {
                out.push((earlier.reference(), later.reference()));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_airspace::{Altitude, IntentState, LatLng, Polygon, Volume3D, Volume4D};

    fn intent(id: &str, priority: u32, lat: f64, start_ms: i64) -> OperationalIntent {
        let d = 0.001;
        let vertices = vec![
            LatLng { lat, lng: -122.4 },
            LatLng {
                lat,
                lng: -122.4 + d,
            },
            LatLng {
                lat: lat + d,
                lng: -122.4 + d,
            },
            LatLng {
                lat: lat + d,
                lng: -122.4,
            },
        ];
        OperationalIntent {
            id: id.into(),
            version: 1,
            state: IntentState::Accepted,
            priority,
            owner: "t".into(),
            volumes: vec![Volume4D {
                volume: Volume3D {
                    outline_polygon: Polygon { vertices },
                    altitude_lower: Altitude::w84_m(0.0),
                    altitude_upper: Altitude::w84_m(50.0),
                },
                time_start: Timestamp::from_unix_ms(start_ms).into(),
                time_end: Timestamp::from_unix_ms(start_ms + 60_000).into(),
            }],
        }
    }

    #[test]
    fn the_oracle_finds_what_binds_and_only_that() {
        let rule = PriorityRule::EqualOrHigher;
        let a = intent("a", 5, 37.79, 0);
        // The same place, overlapping in time (touching at the end counts), equal priority.
        let b = intent("b", 5, 37.7905, 60_000);
        let found = binding_conflicts(&[a.clone(), b.clone()], rule);
        assert_eq!(found, vec![(a.reference(), b.reference())]);
        // A more important later one is not bound; every rule still sees it.
        let urgent = intent("u", 9, 37.7905, 30_000);
        assert!(binding_conflicts(&[a.clone(), urgent.clone()], rule).is_empty());
        assert_eq!(
            binding_conflicts(&[a.clone(), urgent], PriorityRule::Every).len(),
            1
        );
        // A millisecond later, or beside it: clear.
        let later = intent("l", 5, 37.7905, 60_001);
        let beside = intent("s", 5, 37.7915, 0);
        assert!(binding_conflicts(&[a, later, beside], rule).is_empty());
    }

    #[test]
    fn summary_counts_and_deciles() {
        let record = |k: usize, status: Status| FlightRecord {
            mission: format!("m{k}"),
            status,
            intent_id: None,
            departure: None,
            delay_s: (status == Status::Accepted).then_some(k as f64),
            duration_s: None,
            hover_s: None,
            detour_m: None,
            arrival_delay_s: (status == Status::Accepted).then_some(k as f64),
            arrival_gap_s: None,
            blocking: Vec::new(),
            message: None,
            plan_ms: 0.0,
            reserve_ms: 0.0,
            latency_ms: k as f64,
            checked: k,
            stored_before: k / 2,
            route_ne: Vec::new(),
            intent: None,
        };
        let records: Vec<_> = (1..=20)
            .map(|k| {
                record(
                    k,
                    if k % 2 == 0 {
                        Status::Accepted
                    } else {
                        Status::Refused
                    },
                )
            })
            .collect();
        let s = Summary::of(&records);
        assert_eq!(
            (s.missions, s.accepted, s.refused, s.no_route),
            (20, 10, 10, 0)
        );
        assert_eq!(s.share_planned, 0.5);
        // Delays 2, 4, …, 20.
        assert_eq!((s.delay_mean_s, s.delay_p95_s), (11.0, 20.0));
        assert_eq!((s.latency_p50_ms, s.latency_p99_ms), (10.0, 20.0));
        assert_eq!((s.checked_mean, s.checked_max), (10.5, 20));
        assert_eq!(s.deciles.len(), 10);
        assert_eq!(
            (
                s.deciles[9].from,
                s.deciles[9].to,
                s.deciles[9].stored_at_start
            ),
            (18, 20, 9)
        );
        assert_eq!((s.deciles[9].p50_ms, s.deciles[9].p99_ms), (19.0, 20.0));
    }
}
