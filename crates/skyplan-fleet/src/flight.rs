//! One flight against the store: its departure window read and checked, its plan turned into
//! volumes and reserved at the earliest free departure (the server's `POST /api/intents` and
//! the CLI's `fleet` share this).

use serde_json::Value;
use skyplan_airspace::{
    DepartureWindow, FlightVolumes, PriorityRule, Timestamp, VolumeOptions, volumes_from_plan,
};
use skyplan_airspace_store::{
    IntentStore, ReserveCounts, ReserveError, Reserved, new_id, reserve_counted,
};
use skyplan_plan::Plan;

/// Departures may be this far in the past (clocks differ), milliseconds.
pub const PAST_SLACK_MS: i64 = 60_000;

/// Departures may be at most this far ahead, milliseconds (30 days).
pub const HORIZON_MS: i64 = 30 * 86_400_000;

/// The departure grid's step, milliseconds.
pub const DEPARTURE_STEP_MS: i64 = 1000;

/// A field and what is wrong with it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {why}")]
pub struct FieldError {
    /// The field (`departure.earliest`).
    pub field: String,
    /// What is wrong.
    pub why: String,
}

fn field_error(field: &str, why: impl Into<String>) -> FieldError {
    FieldError {
        field: field.into(),
        why: why.into(),
    }
}

fn instant(v: &Value, field: &str) -> Result<Timestamp, FieldError> {
    let text = v
        .as_str()
        .ok_or_else(|| field_error(field, "expected an RFC 3339 date-time string"))?;
    text.parse().map_err(|e| field_error(field, format!("{e}")))
}

/// A departure written as an RFC 3339 instant or `{"earliest": …, "latest": …}` (field
/// `field`), checked against `now` ([`check_window`]).
///
/// ```
/// use skyplan_airspace::Timestamp;
/// let now: Timestamp = "2026-03-01T12:00:00Z".parse()?;
/// let w = skyplan_fleet::departure_window(&serde_json::json!({"earliest": "2026-03-01T12:00:00Z", "latest": "2026-03-01T12:10:00Z"}), "departure", now)?;
/// assert_eq!(w.latest.ms_since(w.earliest), 600_000);
/// let e = skyplan_fleet::departure_window(&serde_json::json!("2026-02-01T12:00:00Z"), "departure", now).unwrap_err();
/// assert!(e.to_string().starts_with("departure: 2026-02-01T12:00:00Z is in the past"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn departure_window(
    v: &Value,
    field: &str,
    now: Timestamp,
) -> Result<DepartureWindow, FieldError> {
    let window = match v {
        Value::String(_) => DepartureWindow::at(instant(v, field)?),
        Value::Object(o) => {
            if let Some(k) = o.keys().find(|k| *k != "earliest" && *k != "latest") {
                return Err(field_error(
                    &format!("{field}.{k}"),
                    "unknown field, expected earliest and latest",
                ));
            }
            DepartureWindow {
                earliest: instant(
                    o.get("earliest").unwrap_or(&Value::Null),
                    &format!("{field}.earliest"),
                )?,
                latest: instant(
                    o.get("latest").unwrap_or(&Value::Null),
                    &format!("{field}.latest"),
                )?,
            }
        }
        _ => {
            return Err(field_error(
                field,
                "expected an RFC 3339 date-time or {\"earliest\": …, \"latest\": …}",
            ));
        }
    };
    check_window(window, field, now)?;
    Ok(window)
}

/// Refuses a plan request that gives its own `departure`: an intent's departure (a window the
/// reservation may move it in) says when it flies, and the request's no-fly zones all apply
/// whatever their time windows.
///
/// ```
/// use skyplan_plan::PlanRequest;
/// assert!(skyplan_fleet::refuse_plan_departure(&PlanRequest::default()).is_ok());
/// let timed = PlanRequest { departure: Some("2026-12-03T17:00:00Z".into()), ..Default::default() };
/// assert!(skyplan_fleet::refuse_plan_departure(&timed).unwrap_err().starts_with("plan.departure"));
/// ```
pub fn refuse_plan_departure(request: &skyplan_plan::PlanRequest) -> Result<(), String> {
    match request.departure {
        None => Ok(()),
        Some(_) => Err(
            "plan.departure: an intent's departure (its window) says when it flies; \
             give it there, not in the plan (the plan's no-fly zones all apply whatever their \
             time windows)"
                .into(),
        ),
    }
}

/// Refuses a window that ends before it starts, starts more than [`PAST_SLACK_MS`] before
/// `now` or ends more than [`HORIZON_MS`] after it.
pub fn check_window(
    window: DepartureWindow,
    field: &str,
    now: Timestamp,
) -> Result<(), FieldError> {
    if window.latest < window.earliest {
        return Err(field_error(
            field,
            format!(
                "the window ends ({}) before it starts ({})",
                window.latest, window.earliest
            ),
        ));
    }
    if window.earliest < now.plus_ms(-PAST_SLACK_MS) {
        return Err(field_error(
            field,
            format!("{} is in the past (now {now})", window.earliest),
        ));
    }
    if window.latest > now.plus_ms(HORIZON_MS) {
        return Err(field_error(
            field,
            format!(
                "{} is beyond the horizon of 30 days (now {now})",
                window.latest
            ),
        ));
    }
    Ok(())
}

/// What to reserve for a planned flight, besides its plan.
#[derive(Debug, Clone, PartialEq)]
pub struct FlightRequest {
    /// When it may leave.
    pub window: DepartureWindow,
    /// Its priority (0 to [`skyplan_airspace::MAX_PRIORITY`]).
    pub priority: u32,
    /// Who flies it.
    pub owner: String,
    /// Which stored intents bind it.
    pub rule: PriorityRule,
    /// The departure grid's step, milliseconds.
    pub step_ms: i64,
    /// How its volumes are made.
    pub volumes: VolumeOptions,
    /// When the answer is due, for a search of its route around the others
    /// ([`crate::reserve_space_time`]): the search proves the earliest arrival over the first
    /// [`crate::space_time::EXACT_SHARE`] of the time left, then heads for the goal (the
    /// flight's `arrival_gap_s` bounds what that may cost), and gives up
    /// ([`ReserveError::Deadline`]) at [`crate::space_time::SEARCH_SHARE`] of it, leaving the
    /// rest for checking and storing the route. `None`: the search proves the earliest arrival
    /// and only its budget of states stops it.
    pub deadline: Option<std::time::Instant>,
}

impl FlightRequest {
    /// A request with the defaults: [`PriorityRule::EqualOrHigher`], [`DEPARTURE_STEP_MS`],
    /// [`VolumeOptions::default`].
    pub fn new(window: DepartureWindow, priority: u32, owner: String) -> Self {
        Self {
            window,
            priority,
            owner,
            rule: PriorityRule::EqualOrHigher,
            step_ms: DEPARTURE_STEP_MS,
            volumes: VolumeOptions::default(),
            deadline: None,
        }
    }
}

/// Why a planned flight was not reserved.
#[derive(Debug, thiserror::Error)]
pub enum FlightError {
    /// Its volumes could not be made from the plan.
    #[error("plan: {0}")]
    Volumes(skyplan_airspace::AirspaceError),
    /// The store refused it, or failed.
    #[error(transparent)]
    Reserve(#[from] ReserveError),
}

/// A planned flight reserved, with its volumes.
#[derive(Debug, Clone)]
pub struct ReservedFlight {
    /// The reservation.
    pub reserved: Reserved,
    /// The flight's volumes (departure at the epoch), its timing and duration.
    pub flight: FlightVolumes,
}

/// The volumes of `plan` under `request`'s options.
pub fn flight_volumes(plan: &Plan, request: &FlightRequest) -> Result<FlightVolumes, FlightError> {
    volumes_from_plan(plan, &request.volumes).map_err(FlightError::Volumes)
}

/// Reserves `flight` (the volumes of a plan) at the earliest free departure of the request's
/// window as a new intent (a fresh id), atomically against the store: what
/// `POST /api/intents` and `skyplan fleet` do after planning. The counts say how many stored
/// intents were read, also when the flight is refused.
pub fn reserve_flight(
    store: &dyn IntentStore,
    flight: &FlightVolumes,
    request: &FlightRequest,
) -> (Result<Reserved, ReserveError>, ReserveCounts) {
    let reservation = skyplan_airspace_store::Reservation {
        window: request.window,
        priority: request.priority,
        owner: request.owner.clone(),
        id: new_id(),
        rule: request.rule,
        step_ms: request.step_ms,
    };
    reserve_counted(store, flight, &reservation)
}

/// [`flight_volumes`] then [`reserve_flight`].
pub fn reserve_plan(
    store: &dyn IntentStore,
    plan: &Plan,
    request: &FlightRequest,
) -> Result<ReservedFlight, FlightError> {
    let flight = flight_volumes(plan, request)?;
    let reserved = reserve_flight(store, &flight, request).0?;
    Ok(ReservedFlight { reserved, flight })
}
