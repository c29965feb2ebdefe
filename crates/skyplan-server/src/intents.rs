//! `/api/intents`: operational intents planned, reserved in the shared airspace, listed,
//! read and deleted.

use crate::AppState;
use crate::error::{ApiError, ErrorKind};
use crate::handlers::{json_body, parse_json, plan_json};
use axum::Json;
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, PathRejection};
use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode};
use serde::Deserialize;
use serde_json::{Value, json};
use skyplan_airspace::{DepartureWindow, MAX_PRIORITY, OperationalIntent, Timestamp};
use skyplan_airspace_store::{IntentStore, ReserveError, StoreError};
use skyplan_fleet::FlightRequest;
use skyplan_plan::PlanRequest;
use std::sync::Arc;
use std::time::Instant;

pub use skyplan_fleet::{DEPARTURE_STEP_MS, HORIZON_MS, PAST_SLACK_MS};

/// Longest owner name, characters.
pub const MAX_OWNER_CHARS: usize = 200;

/// `POST /api/intents`'s body.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct IntentRequest {
    /// The route to plan, as `POST /api/plan` takes it.
    plan: PlanRequest,
    /// An RFC 3339 instant, or `{"earliest": …, "latest": …}`.
    departure: Value,
    /// 0 to 100; higher is more important.
    priority: u32,
    /// Who flies it.
    owner: String,
    /// How a conflict is resolved: `departure` (the default: the planned route, its departure
    /// moved within the window) or `space_time` (the route re-planned around the others:
    /// a later departure, hovering, detours; the earliest arrival).
    #[serde(default)]
    search: Search,
}

/// `IntentRequest::search`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Search {
    #[default]
    Departure,
    SpaceTime,
}

fn bad(message: String) -> ApiError {
    ApiError::bad_request(message)
}

/// The request's departure window, checked against `now`: not in the past (more than a minute),
/// not beyond the horizon, not ending before it starts.
fn window(v: &Value, now: Timestamp) -> Result<DepartureWindow, ApiError> {
    skyplan_fleet::departure_window(v, "departure", now).map_err(|e| bad(e.to_string()))
}

/// The store, or 503 when it could not be opened.
fn store(s: &AppState) -> Result<Arc<dyn IntentStore>, ApiError> {
    s.airspace
        .clone()
        .map_err(|why| ApiError::new(ErrorKind::StoreUnavailable, why))
}

fn store_error(e: StoreError) -> ApiError {
    match e {
        StoreError::Invalid(e) => bad(e.to_string()),
        e => ApiError::new(ErrorKind::StoreUnavailable, e.to_string()),
    }
}

/// Runs a store call on a blocking thread.
async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, ApiError> + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(|e| ApiError::internal(format!("the store's thread: {e}")))?
}

/// `POST /api/intents`: plans the route, then reserves the earliest free departure of the
/// window (201), or names the intents that block it (409).
pub(crate) async fn create(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<(StatusCode, Json<Value>), ApiError> {
    let t0 = Instant::now();
    let body = json_body(&headers, body)?;
    let request: IntentRequest = parse_json(&body)?;
    let window = window(&request.departure, Timestamp::now())?;
    if request.priority > MAX_PRIORITY {
        return Err(bad(format!(
            "priority: {} is above {MAX_PRIORITY}",
            request.priority
        )));
    }
    let owner = request.owner.trim().to_string();
    if owner.is_empty() || owner.chars().count() > MAX_OWNER_CHARS {
        return Err(bad(format!(
            "owner: expected 1 to {MAX_OWNER_CHARS} characters"
        )));
    }
    crate::handlers::check_limits(&s, &request.plan)?;
    if s.pool.world().frame().is_none() {
        return Err(bad(format!(
            "plan: the map {} has no geodetic home, so its routes have no latitude and longitude for an operational intent",
            s.pool.world().name()
        )));
    }
    let store = store(&s)?;
    let plan_request = request.plan;
    skyplan_fleet::refuse_plan_departure(&plan_request).map_err(bad)?;
    let shape = crate::handlers::shape(&plan_request);
    let space_time = request.search == Search::SpaceTime;
    let planned = s
        .pool
        .run(shape, move |session| {
            let plan = session.plan(&plan_request)?;
            // The space-time search's grid, built in the session (and kept there).
            let grid = if space_time {
                skyplan_fleet::search_grid(session, &plan_request, &plan)?
            } else {
                None
            };
            Ok::<_, skyplan_plan::PlanFailure>((plan, grid))
        })
        .await?;
    let (plan, grid) = planned.map_err(ApiError::from)?;
    let mut flight_request = FlightRequest::new(window, request.priority, owner);
    // The search around the others keeps to the request's budget, as planning does.
    flight_request.deadline = Some(s.pool.deadline_from(t0));
    let reserved = if space_time {
        let Some(grid) = grid else {
            return Err(bad(format!(
                "search: space_time needs a 2D grid planner's plan; {} has no grid",
                plan.planner.name()
            )));
        };
        let plan = plan.clone();
        let shared = s.clone();
        blocking(move || {
            let store = store.as_ref();
            let r = skyplan_fleet::reserve_space_time_shared(
                store,
                &grid,
                &plan,
                &flight_request,
                &shared.space_time_cache,
            )
            .0
            .map_err(reserve_error)?;
            let search = r.search_json();
            Ok(Reserved {
                intent: r.intent,
                departure: r.departure,
                delay_ms: r.delay_ms,
                nearby: r.nearby,
                duration_s: r.flight.duration_s,
                timing: r.flight.timing,
                space_time: Some(search),
            })
        })
        .await?
    } else {
        let flight = skyplan_fleet::flight_volumes(&plan, &flight_request)
            .map_err(|e| bad(e.to_string()))?;
        blocking(move || {
            let r = skyplan_fleet::reserve_flight(store.as_ref(), &flight, &flight_request)
                .0
                .map_err(reserve_error)?;
            Ok(Reserved {
                intent: r.intent,
                departure: r.departure,
                delay_ms: r.delay_ms,
                nearby: r.nearby,
                duration_s: flight.duration_s,
                timing: flight.timing,
                space_time: None,
            })
        })
        .await?
    };
    let request_id = s
        .next_request_id
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let wall_time_us = u64::try_from(t0.elapsed().as_micros()).unwrap_or(u64::MAX);
    s.events
        .publish(&crate::ViewEvent::Intent(crate::IntentEvent::of(
            "accepted",
            &reserved.intent,
        )));
    let mut answer = json!({
        "status": "ok",
        "intent": reserved.intent,
        "departure": reserved.departure,
        "delay_s": reserved.delay_ms as f64 / 1000.0,
        "duration_s": reserved.duration_s,
        "timing": reserved.timing,
        "nearby_intents": reserved.nearby,
        "plan": plan_json(&plan, wall_time_us, request_id)?,
    });
    if let (Some(extra), Some(map)) = (reserved.space_time, answer.as_object_mut()) {
        map.insert("space_time".into(), extra);
    }
    Ok((StatusCode::CREATED, Json(answer)))
}

/// A reservation as the answer reports it.
struct Reserved {
    intent: OperationalIntent,
    departure: Timestamp,
    delay_ms: i64,
    nearby: usize,
    duration_s: f64,
    timing: skyplan_airspace::Timing,
    space_time: Option<Value>,
}

fn reserve_error(e: ReserveError) -> ApiError {
    match e {
        ReserveError::Blocked(b) => {
            ApiError::new(ErrorKind::Conflict, b.to_string()).with_conflicts(b.blocking)
        }
        ReserveError::Invalid(e) => bad(e.to_string()),
        ReserveError::Store(e) => store_error(e),
        // Only the space-time search has a deadline: the request's time budget.
        e @ ReserveError::Deadline { .. } => ApiError::new(
            ErrorKind::OverBudget,
            format!(
                "{e} (the server's time budget); \"search\": \"departure\" (shifting the departure only) answers at once"
            ),
        ),
    }
}

/// `GET /api/intents`'s filters: an intent is listed when one of its volumes meets all those
/// given (closed sets, as the conflict test).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ListQuery {
    /// `lat_min,lng_min,lat_max,lng_max`, degrees.
    bbox: Option<String>,
    /// Lowest altitude, W84 metres.
    altitude_lower: Option<f64>,
    /// Highest altitude, W84 metres.
    altitude_upper: Option<f64>,
    /// From (RFC 3339).
    time_start: Option<String>,
    /// Until (RFC 3339).
    time_end: Option<String>,
}

/// The checked filters of a [`ListQuery`].
struct Filter {
    bbox: Option<skyplan_airspace::Volume4D>,
    altitudes: (f64, f64),
    times: (Timestamp, Timestamp),
    /// Both ends of the time window given.
    bounded: bool,
}

impl Filter {
    fn of(q: &ListQuery) -> Result<Self, ApiError> {
        let time = |field: &str, v: &Option<String>, default: Timestamp| match v {
            Some(text) => text
                .parse::<Timestamp>()
                .map_err(|e| bad(format!("{field}: {e}"))),
            None => Ok(default),
        };
        let times = (
            time(
                "time_start",
                &q.time_start,
                Timestamp::from_unix_ms(i64::MIN / 2),
            )?,
            time(
                "time_end",
                &q.time_end,
                Timestamp::from_unix_ms(i64::MAX / 2),
            )?,
        );
        if times.1 < times.0 {
            return Err(bad("time_end: before time_start".into()));
        }
        let altitudes = (
            q.altitude_lower.unwrap_or(f64::NEG_INFINITY),
            q.altitude_upper.unwrap_or(f64::INFINITY),
        );
        if altitudes.0.is_nan() || altitudes.1.is_nan() || altitudes.1 < altitudes.0 {
            return Err(bad(
                "altitude_upper: expected numbers with altitude_lower ≤ altitude_upper".into(),
            ));
        }
        let bbox = match &q.bbox {
            None => None,
            Some(text) => {
                let v: Vec<f64> = text
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .unwrap_or_default();
                let ok = v.len() == 4
                    && v.iter().all(|x| x.is_finite())
                    && (-90.0..=90.0).contains(&v[0])
                    && (-90.0..=90.0).contains(&v[2])
                    && (-180.0..=180.0).contains(&v[1])
                    && (-180.0..=180.0).contains(&v[3])
                    && v[0] < v[2]
                    && v[1] < v[3];
                if !ok {
                    return Err(bad(format!(
                        "bbox: expected lat_min,lng_min,lat_max,lng_max in degrees with min < max, got {text:?}"
                    )));
                }
                let corner = |lat, lng| skyplan_airspace::LatLng { lat, lng };
                let at = skyplan_airspace::Altitude::w84_m(0.0);
                let now: skyplan_airspace::Time = Timestamp::from_unix_ms(0).into();
                Some(skyplan_airspace::Volume4D {
                    volume: skyplan_airspace::Volume3D {
                        outline_polygon: skyplan_airspace::Polygon {
                            vertices: vec![
                                corner(v[0], v[1]),
                                corner(v[0], v[3]),
                                corner(v[2], v[3]),
                                corner(v[2], v[1]),
                            ],
                        },
                        altitude_lower: at,
                        altitude_upper: at,
                    },
                    time_start: now,
                    time_end: now,
                })
            }
        };
        Ok(Self {
            bbox,
            altitudes,
            times,
            bounded: q.time_start.is_some() && q.time_end.is_some(),
        })
    }

    /// The area and time window as one volume for the store's index (a superset of what the
    /// filter keeps), when both are given.
    fn probe(&self) -> Option<skyplan_airspace::Volume4D> {
        let mut v = self.bbox.clone().filter(|_| self.bounded)?;
        v.time_start = self.times.0.into();
        v.time_end = self.times.1.into();
        Some(v)
    }

    fn keeps(&self, intent: &OperationalIntent) -> bool {
        intent.volumes.iter().any(|v| {
            v.time_end.value >= self.times.0
                && v.time_start.value <= self.times.1
                && v.volume.altitude_upper.value >= self.altitudes.0
                && v.volume.altitude_lower.value <= self.altitudes.1
                && self
                    .bbox
                    .as_ref()
                    .is_none_or(|b| skyplan_airspace::footprints_intersect(v, b))
        })
    }
}

/// `GET /api/intents`: every stored intent in the order accepted, or those meeting the filters.
pub(crate) async fn list(
    State(s): State<AppState>,
    query: Result<axum::extract::Query<ListQuery>, axum::extract::rejection::QueryRejection>,
) -> Result<Json<Value>, ApiError> {
    let axum::extract::Query(q) = query.map_err(|e| bad(e.body_text()))?;
    let filter = Filter::of(&q)?;
    let store = store(&s)?;
    let probe = filter.probe();
    let mut intents = blocking(move || {
        // An area and a time window: the intents the index files there (in the order stored),
        // unless they cover more index keys than it takes: then every intent.
        if let Some(v) = probe {
            match store.nearby(std::slice::from_ref(&v), 0) {
                Ok(found) => return Ok(found),
                Err(skyplan_airspace_store::StoreError::TooLarge(_)) => {}
                Err(e) => return Err(store_error(e)),
            }
        }
        store.list().map_err(store_error)
    })
    .await?;
    intents.retain(|i| filter.keeps(i));
    Ok(Json(json!({ "intents": intents })))
}

fn id_of(path: Result<Path<String>, PathRejection>) -> Result<String, ApiError> {
    path.map(|Path(id)| id)
        .map_err(|e| bad(format!("id: {}", e.body_text())))
}

fn no_such(id: &str) -> ApiError {
    ApiError::new(ErrorKind::NotFound, format!("no intent with id {id:?}"))
}

/// The intent `path` names, after `op` (read or remove) on the store; 404 when there is none.
async fn one_intent(
    s: &AppState,
    path: Result<Path<String>, PathRejection>,
    op: fn(&dyn IntentStore, &str) -> Result<Option<OperationalIntent>, StoreError>,
) -> Result<Json<Value>, ApiError> {
    let id = id_of(path)?;
    let store = store(s)?;
    let key = id.clone();
    let found = blocking(move || op(store.as_ref(), &key).map_err(store_error)).await?;
    let intent = found.ok_or_else(|| no_such(&id))?;
    Ok(Json(
        serde_json::to_value(intent).map_err(|e| ApiError::internal(e.to_string()))?,
    ))
}

/// `GET /api/intents/{id}`.
pub(crate) async fn get(
    State(s): State<AppState>,
    path: Result<Path<String>, PathRejection>,
) -> Result<Json<Value>, ApiError> {
    one_intent(&s, path, |store, id| store.get(id)).await
}

/// `DELETE /api/intents/{id}`: the intent removed.
pub(crate) async fn delete(
    State(s): State<AppState>,
    path: Result<Path<String>, PathRejection>,
) -> Result<Json<Value>, ApiError> {
    let gone = one_intent(&s, path, |store, id| store.delete(id)).await?;
    if let Ok(intent) = serde_json::from_value::<OperationalIntent>(gone.0.clone()) {
        s.events
            .publish(&crate::ViewEvent::Intent(crate::IntentEvent::of(
                "deleted", &intent,
            )));
    }
    Ok(gone)
}
