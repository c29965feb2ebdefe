//! `Airspace`: a shared airspace store (SQLite file, memory, or PostgreSQL) that flights planned
//! by a `Planner` are reserved in as operational intents, one at a time or a whole fleet — what
//! `POST /api/intents` and `skyplan fleet` do, through the same crate (`skyplan-fleet`).

use crate::arrays::to_json;
use crate::errors::{bad_input, to_py};
use crate::planner::{Plan, Planner, json_to_py, request_of};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};
use serde_json::{Value, json};
use skyplan_airspace::{MAX_PRIORITY, OperationalIntent, PriorityRule, Timestamp};
use skyplan_airspace_store::{IntentStore, ReserveError, StoreError, open_url};
use skyplan_fleet::{
    Clock, FlightRequest, Format, Mode, RunOptions, Summary, binding_conflicts, fly_fleet,
    parse_missions,
};
use skyplan_plan::PlanFailure;

/// A `skyplan.Conflict` (the intents in the way as `conflicts`, `[(id, version), …]`) or
/// `skyplan.AirspaceUnavailable`, by name from `skyplan._errors`.
fn raise(class: &str, message: String, conflicts: Option<Vec<(String, u64)>>) -> PyErr {
    Python::attach(|py| {
        let made = py
            .import("skyplan._errors")
            .and_then(|m| m.getattr(class))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from))
            .and_then(|ty| ty.call1((message.clone(),)));
        match made {
            Ok(err) => {
                if let Some(c) = conflicts
                    && let Err(e) = err.setattr("conflicts", c)
                {
                    return e;
                }
                PyErr::from_value(err)
            }
            Err(_) => to_py(PlanFailure::internal(message)),
        }
    })
}

fn store_error(e: StoreError) -> PyErr {
    match e {
        StoreError::Invalid(e) => bad_input(e.to_string()),
        StoreError::Address(_) => bad_input(format!("url: {e}")),
        e => raise("AirspaceUnavailable", e.to_string(), None),
    }
}

fn reserve_error(e: ReserveError) -> PyErr {
    match e {
        ReserveError::Blocked(b) => {
            let conflicts = b
                .blocking
                .iter()
                .map(|r| (r.id.clone(), r.version))
                .collect();
            raise("Conflict", b.to_string(), Some(conflicts))
        }
        ReserveError::Invalid(e) => bad_input(e.to_string()),
        ReserveError::Store(e) => store_error(e),
        e @ ReserveError::Deadline { .. } => {
            crate::errors::fail(skyplan_plan::FailureKind::Timeout, e.to_string())
        }
    }
}

/// Intents are in latitude and longitude: the planner's map needs a geodetic home.
fn needs_home(planner: &Planner) -> PyResult<()> {
    if planner.world().frame().is_none() {
        return Err(bad_input(format!(
            "planner: the map {} has no geodetic home, so its routes have no latitude and longitude for an operational intent",
            planner.world().name()
        )));
    }
    Ok(())
}

fn to_dict<'py>(py: Python<'py>, v: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let value =
        serde_json::to_value(v).map_err(|e| to_py(PlanFailure::internal(format!("JSON: {e}"))))?;
    json_to_py(py, &value)
}

/// A departure as `departure_window` reads it: an RFC 3339 string, a dict
/// `{"earliest": …, "latest": …}`, or a pair `(earliest, latest)`.
fn departure_value(obj: &Bound<'_, PyAny>) -> PyResult<Value> {
    let v = to_json(obj, "departure")?;
    Ok(match v {
        Value::Array(a) if a.len() == 2 => json!({ "earliest": a[0], "latest": a[1] }),
        v => v,
    })
}

/// The shared airspace: operational intents (the InterUSS DSS's JSON shape) in a store that
/// several programs and `skyplan serve` processes may share.
///
/// `url`: `"sqlite:FILE"`, `"sqlite::memory:"` (this object's own) or
/// `"postgres://USER@HOST:PORT/DATABASE"` (TLS with libpq's `?sslmode=verify-full`,
/// `&sslrootcert=CA.pem`, `&sslcert=…&sslkey=…`; docs/FLEET.md). Raises `BadInput` for an
/// address it does not know and `AirspaceUnavailable` when the store cannot be opened.
#[pyclass(module = "skyplan", frozen)]
pub struct Airspace {
    url: String,
    store: Box<dyn IntentStore>,
    /// The stored intents a `space_time` reservation read, kept for the next ones (as the
    /// server keeps them): read, decoded and rasterised once.
    space_time_cache: std::sync::Mutex<skyplan_fleet::SpaceTimeCache>,
}

#[pymethods]
impl Airspace {
    #[new]
    fn new(py: Python<'_>, url: &str) -> PyResult<Self> {
        let owned = url.to_string();
        let store = py.detach(move || open_url(&owned)).map_err(store_error)?;
        Ok(Self {
            url: url.to_string(),
            store,
            space_time_cache: std::sync::Mutex::new(skyplan_fleet::SpaceTimeCache::new()),
        })
    }

    /// The store's address.
    #[getter]
    fn url(&self) -> String {
        self.url.clone()
    }

    /// Plans a route with `planner` (`start`, `goal` and the options as `Planner.plan` takes
    /// them) and reserves it as a new operational intent, atomically against the store.
    ///
    /// `departure`: an RFC 3339 instant, or a window `(earliest, latest)` / `{"earliest": …,
    /// "latest": …}` (not more than a minute in the past, within 30 days). `priority`: 0 to 100;
    /// the flight keeps clear of stored intents of equal or higher priority. `search`:
    /// `"departure"` moves the planned route's departure to the earliest free one of the
    /// window; `"space_time"` re-plans the route around the others (hovering, detours, a later
    /// departure; the earliest arrival). `deadline_ms` (with `"space_time"`): the answer is due
    /// this many milliseconds after the call; the search proves the earliest arrival over half
    /// the time left when it starts, then heads for the goal (`arrival_gap_s` bounds what that may
    /// cost), and at four-fifths gives up, raising `Timeout` with nothing reserved.
    ///
    /// Returns a dict: `intent` (as stored), `departure`, `delay_s`, `duration_s`, `timing`,
    /// `nearby_intents`, `plan` (a `Plan`: the route in an empty sky), and with
    /// `search="space_time"` also `space_time` (`hover_s`, `detour_m`, `arrival_delay_s`,
    /// `arrival_gap_s`: at most how much sooner it could arrive, 0 when proven the earliest,
    /// `route_ne`). Raises `Conflict` (its `conflicts`: the blocking intents' `(id, version)`)
    /// when no departure of the window is free, the planning errors as `Planner.plan` does,
    /// `BadInput` for a bad departure, priority, owner or search.
    #[pyo3(signature = (planner, departure, *, priority = 0, owner = "python", search = "departure", deadline_ms = None, start = None, goal = None, **options))]
    #[allow(clippy::too_many_arguments)]
    fn reserve<'py>(
        &self,
        py: Python<'py>,
        planner: &Planner,
        departure: &Bound<'py, PyAny>,
        priority: u32,
        owner: &str,
        search: &str,
        deadline_ms: Option<u64>,
        start: Option<&Bound<'py, PyAny>>,
        goal: Option<&Bound<'py, PyAny>>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let called = std::time::Instant::now();
        let window = skyplan_fleet::departure_window(
            &departure_value(departure)?,
            "departure",
            Timestamp::now(),
        )
        .map_err(|e| bad_input(e.to_string()))?;
        if priority > MAX_PRIORITY {
            return Err(bad_input(format!(
                "priority: {priority} is above {MAX_PRIORITY}"
            )));
        }
        let owner = owner.trim();
        if owner.is_empty() || owner.chars().count() > 200 {
            return Err(bad_input("owner: expected 1 to 200 characters"));
        }
        let space_time = match search {
            "departure" => false,
            "space_time" => true,
            other => {
                return Err(bad_input(format!(
                    "search: expected \"departure\" or \"space_time\", got {other:?}"
                )));
            }
        };
        if deadline_ms.is_some() && !space_time {
            return Err(bad_input(
                "deadline_ms: only search=\"space_time\" searches, so only it has a deadline",
            ));
        }
        needs_home(planner)?;
        let request = request_of(start, goal, options)?;
        skyplan_fleet::refuse_plan_departure(&request).map_err(bad_input)?;
        let planned = planner.with_session(py, move |session| {
            let plan = session.plan(&request)?;
            let grid = if space_time {
                skyplan_fleet::search_grid(session, &request, &plan)?
            } else {
                None
            };
            Ok::<_, PlanFailure>((plan, grid))
        })?;
        let (plan, grid) = planned.map_err(to_py)?;
        let mut flight_request = FlightRequest::new(window, priority, owner.to_string());
        flight_request.deadline =
            deadline_ms.map(|ms| called + std::time::Duration::from_millis(ms));
        let store = self.store.as_ref();
        let answer = if space_time {
            let Some(grid) = grid else {
                return Err(bad_input(format!(
                    "search: space_time needs a 2D grid planner's plan; {} has no grid",
                    plan.planner.name()
                )));
            };
            let cache = &self.space_time_cache;
            let r = py
                .detach(|| {
                    skyplan_fleet::reserve_space_time_shared(
                        store,
                        &grid,
                        &plan,
                        &flight_request,
                        cache,
                    )
                    .0
                })
                .map_err(reserve_error)?;
            json!({
                "intent": r.intent,
                "departure": r.departure,
                "delay_s": r.delay_ms as f64 / 1000.0,
                "duration_s": r.flight.duration_s,
                "timing": r.flight.timing,
                "nearby_intents": r.nearby,
                "space_time": r.search_json(),
            })
        } else {
            let r = py
                .detach(|| skyplan_fleet::reserve_plan(store, &plan, &flight_request))
                .map_err(|e| match e {
                    skyplan_fleet::FlightError::Reserve(e) => reserve_error(e),
                    e => bad_input(e.to_string()),
                })?;
            json!({
                "intent": r.reserved.intent,
                "departure": r.reserved.departure,
                "delay_s": r.reserved.delay_ms as f64 / 1000.0,
                "duration_s": r.flight.duration_s,
                "timing": r.flight.timing,
                "nearby_intents": r.reserved.nearby,
            })
        };
        let dict = json_to_py(py, &answer)?;
        dict.set_item("plan", Plan { inner: plan })?;
        Ok(dict)
    }

    /// Every stored intent, in the order stored, as dicts.
    fn intents<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let all = py.detach(|| self.store.list()).map_err(store_error)?;
        to_dict(py, &all)
    }

    /// The intent with this id, or None.
    fn get<'py>(&self, py: Python<'py>, id: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let one = py.detach(|| self.store.get(id)).map_err(store_error)?;
        one.map(|i| to_dict(py, &i)).transpose()
    }

    /// Removes the intent with this id; the intent removed, or None.
    fn delete<'py>(&self, py: Python<'py>, id: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let gone = py.detach(|| self.store.delete(id)).map_err(store_error)?;
        gone.map(|i| to_dict(py, &i)).transpose()
    }

    /// Pairs of stored intents that intersect although the later was bound by the earlier
    /// (every pair, the exact 4D test): `[(later_id, earlier_id), …]`, always empty unless the
    /// store was written around skyplan.
    fn conflicts(&self, py: Python<'_>) -> PyResult<Vec<(String, String)>> {
        let all: Vec<OperationalIntent> = py.detach(|| self.store.list()).map_err(store_error)?;
        Ok(binding_conflicts(&all, PriorityRule::EqualOrHigher)
            .into_iter()
            .map(|(a, b)| (a.id, b.id))
            .collect())
    }

    /// Plans and reserves `missions` in order, as `skyplan fleet` does: a list of dicts with
    /// the mission file's fields (`id`, `start_ne`/`start_lla`, `goal_ne`/`goal_lla`, `alt_m`,
    /// `departure` — seconds after `start` or RFC 3339 or `{earliest, latest}` — `window_s`,
    /// `priority`, `owner`). `mode`: `"shift"` (departures moved), `"space_time"` (routes
    /// re-planned around the others) or `"reject_on_conflict"` (the baseline). `start`: what
    /// departures in seconds count from (RFC 3339; default: now rounded up to the next minute).
    /// `deadline_ms` (with `"space_time"`): a flight's answer is due this many milliseconds after
    /// its planning started; its search proves the earliest arrival over half the time left
    /// when it starts, then heads for the goal (the record's `arrival_gap_s` bounds what that may cost), and at
    /// four-fifths gives up: the flight is then `timed_out`, nothing reserved.
    ///
    /// Returns a dict: `flights` (one record per mission, as the CLI's JSON report), `summary`
    /// (share planned, delays, latency, intents checked) and `conflicts` (pairs of stored
    /// intents that intersect, brute force: 0).
    #[pyo3(signature = (planner, missions, *, mode = "shift", start = None, deadline_ms = None))]
    fn fleet<'py>(
        &self,
        py: Python<'py>,
        planner: &Planner,
        missions: &Bound<'py, PyAny>,
        mode: &str,
        start: Option<&str>,
        deadline_ms: Option<u64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let mode = Mode::of_key(mode).ok_or_else(|| {
            bad_input(format!(
                "mode: expected one of {}, got {mode:?}",
                Mode::keys()
            ))
        })?;
        needs_home(planner)?;
        let now = Timestamp::now();
        let start = match start {
            Some(text) => text
                .parse::<Timestamp>()
                .map_err(|e| bad_input(format!("start: {e}")))?,
            None => Timestamp::from_unix_ms((now.unix_ms().div_euclid(60_000) + 1) * 60_000),
        };
        let text = to_json(missions, "missions")?.to_string();
        let missions = parse_missions("missions", &text, Format::Json, Clock { start, now })
            .map_err(|e| bad_input(e.to_string()))?;
        let store = self.store.as_ref();
        if deadline_ms.is_some() && mode != Mode::SpaceTime {
            return Err(bad_input(
                "deadline_ms: only the space_time mode searches, so only it has a deadline",
            ));
        }
        let options = RunOptions {
            mode,
            search_deadline: deadline_ms.map(std::time::Duration::from_millis),
            ..RunOptions::default()
        };
        let run = planner.with_session(py, |session| {
            fly_fleet(
                session,
                store,
                &skyplan_plan::PlanRequest::default(),
                &missions,
                &options,
                |_, _| {},
            )
        })?;
        let records = run.map_err(|e| match e {
            skyplan_fleet::FleetError::Store { error, .. } => store_error(error),
            e => bad_input(e.to_string()),
        })?;
        let summary = Summary::of(&records);
        let stored = py.detach(|| store.list()).map_err(store_error)?;
        let conflicts = binding_conflicts(&stored, PriorityRule::EqualOrHigher).len();
        let report = json!({
            "mode": mode,
            "flights": records,
            "summary": summary,
            "conflicts": conflicts,
        });
        json_to_py(py, &report)
    }

    fn __repr__(&self) -> String {
        format!("skyplan.Airspace({:?})", self.url)
    }
}
