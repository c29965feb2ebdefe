//! The request handlers.

use crate::error::{ApiError, ErrorKind};
use crate::events::{Encoded, PlanEvent, ViewEvent};
use crate::map::{GridRuns, MapQuery, check_grid_size};
use crate::{AppState, OPENAPI_JSON, PAGE_HTML};
use axum::Json;
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, QueryRejection};
use axum::extract::{Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Response};
use futures_util::Stream;
use serde_json::{Value, json};
use skyplan_plan::{PlanRequest, PlannerId, World};
use std::convert::Infallible;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};
use tokio::sync::broadcast;

/// Most voxels a `voxel` request may ask for in this server.
const MAX_VOXELS: f64 = 8_000_000.0;

/// `GET /`.
pub(crate) async fn page() -> Html<&'static str> {
    Html(PAGE_HTML)
}

/// `GET /api/openapi.json`.
pub(crate) async fn openapi() -> Response {
    ([(header::CONTENT_TYPE, "application/json")], OPENAPI_JSON).into_response()
}

/// Unknown paths.
pub(crate) async fn not_found() -> ApiError {
    ApiError::new(
        ErrorKind::NotFound,
        "no such endpoint; see /api/openapi.json",
    )
}

/// Known paths, other methods.
pub(crate) async fn method_not_allowed() -> ApiError {
    ApiError::new(
        ErrorKind::MethodNotAllowed,
        "this endpoint does not take this method; see /api/openapi.json",
    )
}

/// The planner registry with what this map takes.
pub(crate) fn planners_json(world: &World) -> Value {
    let obstacles = world.colliders().is_some() || world.footprints().is_some();
    let planners: Vec<Value> = PlannerId::ALL
        .iter()
        .map(|p| {
            let mut v = serde_json::to_value(p.info()).unwrap_or(Value::Null);
            v["available"] = json!(PlannerId::for_maps(obstacles).any(|q| q == *p));
            v
        })
        .collect();
    json!({ "default": PlannerId::default(), "planners": planners })
}

/// `GET /api/planners`.
pub(crate) async fn planners(State(s): State<AppState>) -> Json<Value> {
    Json(s.planners.clone())
}

/// `GET /api/status`: the planning workers, the queue and their counters.
pub(crate) async fn status(State(s): State<AppState>) -> Json<crate::pool::PoolStatus> {
    Json(s.pool.status())
}

/// `GET /api/map`.
pub(crate) async fn map(
    State(s): State<AppState>,
    query: Result<Query<MapQuery>, QueryRejection>,
) -> Result<Json<Value>, ApiError> {
    let Query(q) = query.map_err(|e| ApiError::bad_request(e.body_text()))?;
    let mut info = s.map_info.clone();
    if let Some(request) = q.request() {
        let spec = request.spec()?;
        let (alt_m, safety_m, cell_m) = (spec.alt_m, spec.safety_m, spec.cell_m);
        check_grid_size(s.pool.world(), cell_m, "cell_m")?;
        let grid = s
            .pool
            .run([alt_m, safety_m, cell_m, f64::NAN], move |session| {
                session
                    .grid(alt_m, safety_m, cell_m)
                    .map(|g| GridRuns::new(&g, alt_m, safety_m))
            })
            .await??;
        info["grid"] = serde_json::to_value(grid).map_err(|e| ApiError::internal(e.to_string()))?;
    }
    Ok(Json(info))
}

/// A JSON body parsed into `T`, with the field named on errors (`alt_m: invalid type: …`).
pub(crate) fn parse_json<T: serde::de::DeserializeOwned>(body: &[u8]) -> Result<T, ApiError> {
    let de = &mut serde_json::Deserializer::from_slice(body);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        if path == "." || path.is_empty() {
            ApiError::bad_request(format!("request body: {inner}"))
        } else {
            ApiError::bad_request(format!("{path}: {inner}"))
        }
    })
}

/// The body of a request that must be JSON: 415 unless declared `application/json`, 413 over
/// the size limit.
pub(crate) fn json_body(
    headers: &HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<Bytes, ApiError> {
    let json = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.split(';').next())
        .is_some_and(|v| v.trim().eq_ignore_ascii_case("application/json"));
    if !json {
        return Err(ApiError::new(
            ErrorKind::NotJson,
            "send the request as JSON with Content-Type: application/json",
        ));
    }
    body.map_err(|e| {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::new(
                ErrorKind::TooLarge,
                format!("request body over {} bytes (1 MiB)", crate::MAX_BODY_BYTES),
            )
        } else {
            ApiError::bad_request(e.body_text())
        }
    })
}

/// A plan as `POST /api/plan` answers it: the plan's JSON with `wall_time_us` and `request_id`.
pub(crate) fn plan_json(
    plan: &skyplan_plan::Plan,
    wall_time_us: u64,
    request_id: u64,
) -> Result<Value, ApiError> {
    let mut v = serde_json::to_value(plan).map_err(|e| ApiError::internal(e.to_string()))?;
    v["wall_time_us"] = json!(wall_time_us);
    v["request_id"] = json!(request_id);
    Ok(v)
}

/// Refuses requests that would run past the server's budget or build more than it allows.
pub(crate) fn check_limits(s: &AppState, r: &PlanRequest) -> Result<(), ApiError> {
    let budget_ms = s.config.timeout.as_millis();
    if let Some(ms) = r.time_limit_ms
        && u128::from(ms) > budget_ms
    {
        return Err(ApiError::bad_request(format!(
            "time_limit_ms {ms}: more than this server's budget of {budget_ms} ms per request"
        )));
    }
    // The planning API resolves the request (defaults, ranges) and estimates what it builds.
    let world = s.pool.world();
    check_grid_size(world, r.spec()?.cell_m, "cell_m")?;
    if let Some((voxels, "voxels")) = world.estimate(r)?
        && voxels as f64 > MAX_VOXELS
    {
        return Err(ApiError::bad_request(format!(
            "voxel_m/layer_m: the lattice would have {voxels} voxels, more than this server's {MAX_VOXELS:.0}; use larger pitches"
        )));
    }
    Ok(())
}

/// The shape of what a request makes the session cache.
pub(crate) fn shape(r: &PlanRequest) -> [f64; 4] {
    [
        r.alt_m.unwrap_or(f64::NAN),
        r.safety_m.unwrap_or(f64::NAN),
        r.cell_m.unwrap_or(f64::NAN),
        r.max_alt_m.or(r.min_alt_m).unwrap_or(f64::NAN),
    ]
}

/// `POST /api/plan`.
pub(crate) async fn plan(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<Json<Value>, ApiError> {
    let t0 = Instant::now();
    let body = json_body(&headers, body)?;
    let request: PlanRequest = parse_json(&body)?;
    check_limits(&s, &request)?;
    let request_id = s.next_request_id.fetch_add(1, Ordering::Relaxed);
    let planner = request.planner.unwrap_or_default();
    let result = s
        .pool
        .run(shape(&request), move |session| session.plan(&request))
        .await?;
    let wall_time_us = u64::try_from(t0.elapsed().as_micros()).unwrap_or(u64::MAX);
    match result {
        Ok(plan) => {
            s.events.publish(&ViewEvent::Plan(PlanEvent {
                request_id,
                planner: planner.to_string(),
                status: "ok".into(),
                message: None,
                cost_m: Some(plan.cost_m),
                waypoints: plan.points_nea(),
                wall_time_us,
            }));
            Ok(Json(plan_json(&plan, wall_time_us, request_id)?))
        }
        Err(failure) => {
            s.events.publish(&ViewEvent::Plan(PlanEvent {
                request_id,
                planner: planner.to_string(),
                status: failure.kind.name().into(),
                message: Some(failure.message.clone()),
                cost_m: None,
                waypoints: Vec::new(),
                wall_time_us,
            }));
            Err(failure.into())
        }
    }
}

/// Keeps an event-stream slot while the stream lives: dropped when the client goes.
struct Subscription {
    rx: broadcast::Receiver<Arc<Encoded>>,
    first: std::vec::IntoIter<Arc<Encoded>>,
    _slot: tokio::sync::OwnedSemaphorePermit,
}

fn sse_event(e: &Encoded) -> Event {
    Event::default().event(e.name).data(e.json.as_str())
}

/// `GET /api/events`.
pub(crate) async fn events(
    State(s): State<AppState>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    let slot = Arc::clone(&s.event_slots)
        .try_acquire_owned()
        .map_err(|_| {
            ApiError::new(
                ErrorKind::Busy,
                format!(
                    "{} event-stream clients are connected, the most this server takes",
                    s.config.max_event_clients
                ),
            )
        })?;
    let (rx, retained) = s.events.subscribe();
    let sub = Subscription {
        rx,
        first: retained.into_iter(),
        _slot: slot,
    };
    let stream = futures_util::stream::unfold(sub, |mut sub| async move {
        if let Some(e) = sub.first.next() {
            return Some((Ok(sse_event(&e)), sub));
        }
        match sub.rx.recv().await {
            Ok(e) => Some((Ok(sse_event(&e)), sub)),
            Err(broadcast::error::RecvError::Lagged(n)) => {
                let note = Event::default().comment(format!("skipped {n} events"));
                Some((Ok(note), sub))
            }
            Err(broadcast::error::RecvError::Closed) => None,
        }
    });
    Ok(Sse::new(stream).keep_alive(KeepAlive::new().interval(Duration::from_secs(15))))
}
