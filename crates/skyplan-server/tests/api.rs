//! The HTTP API against the planning API it wraps: same plans, the documented statuses, the
//! limits and the event stream (the OpenAPI description against all of this: tests/openapi.rs).

use axum::Router;
use axum::body::Body;
use axum::http::{Request, StatusCode};
use serde_json::{Value, json};
use skyplan_plan::{MapKinds, Optimality, PlanRequest, PlannerId, Session, World};
use skyplan_server::{FlightEvent, RouteEvent, ServerConfig, ViewEvent, ViewServer, app, router};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};
use tower::ServiceExt;

fn city() -> Router {
    router(World::fcnd_city(), ServerConfig::default())
}

/// The city's API with a time budget per request of `timeout`.
fn city_with_budget(timeout: Duration) -> Router {
    let config = ServerConfig {
        timeout,
        ..ServerConfig::default()
    };
    router(World::fcnd_city(), config)
}

async fn send(app: Router, method: &str, uri: &str, body: impl Into<Body>) -> (StatusCode, Value) {
    let request = Request::builder()
        .method(method)
        .uri(uri)
        .header("content-type", "application/json")
        .body(body.into())
        .expect("a valid request");
    let response = app.oneshot(request).await.expect("the router answers");
    let status = response.status();
    let bytes = axum::body::to_bytes(response.into_body(), usize::MAX)
        .await
        .expect("a body");
    let value = serde_json::from_slice(&bytes)
        .unwrap_or_else(|_| Value::String(String::from_utf8_lossy(&bytes).into_owned()));
    (status, value)
}

async fn post_plan(app: Router, body: Value) -> (StatusCode, Value) {
    send(app, "POST", "/api/plan", body.to_string()).await
}

/// A response's content type ("" when it is not text).
fn content_type(response: &axum::http::Response<Body>) -> &str {
    response.headers()["content-type"]
        .to_str()
        .unwrap_or_default()
}

/// An error answer's message ("" without one).
fn message(v: &Value) -> &str {
    v["message"].as_str().unwrap_or_default()
}

/// The plan without the keys that differ from run to run (times in µs at any depth, request
/// numbers).
fn timeless(mut v: Value) -> Value {
    if let Some(o) = v.as_object_mut() {
        o.retain(|k, _| !k.ends_with("_us") && k != "request_id");
        for x in o.values_mut() {
            *x = timeless(x.take());
        }
    }
    v
}

#[tokio::test]
async fn plans_equal_the_planning_api_for_the_same_request() {
    for body in [
        json!({ "planner": "jps-plus", "goal_ne": [420.0, 390.0] }),
        json!({ "planner": "theta", "start_ne": [-200.0, 150.0], "goal_ne": [308.5, -250.5], "alt_m": 12.0, "safety_m": 3.0 }),
        json!({ "planner": "rrt-connect", "goal_ne": [60.0, 40.0], "goal_alt_m": 20.0, "seed": 7, "geometry": true }),
        // No-fly zones as the zone file's text: around a circle and a square across the route.
        json!({ "planner": "jps", "no_fly": include_str!("../../../data/no-fly-sample.geojson") }),
    ] {
        let (status, got) = post_plan(city(), body.clone()).await;
        assert_eq!(status, StatusCode::OK, "{got}");
        assert!(got["wall_time_us"].as_u64().is_some());
        let request: PlanRequest = serde_json::from_value(body).expect("a valid request");
        let want = Session::new(World::fcnd_city())
            .plan(&request)
            .expect("the API plans it");
        let want = serde_json::to_value(&want).expect("serialisable");
        assert!(want["cost_m"].as_f64().is_some_and(|c| c > 0.0));
        assert_eq!(timeless(got), timeless(want));
    }
}

/// Every planner of the registry whose route does not depend on how long it ran (RRT\* improves
/// until its time limit), on a 5 m grid (`ch`'s preprocessing at 1 m takes minutes).
#[tokio::test]
async fn every_planners_plan_equals_the_planning_api_for_the_same_request() {
    let mut session = Session::new(World::fcnd_city());
    // Not the planners for small grids: the city is too large for their tables.
    let timeless_planners = (PlannerId::ALL.iter())
        .filter(|p| p.info().optimality != Optimality::AsymptoticallyOptimal)
        .filter(|p| p.info().maps != MapKinds::SmallGrid);
    for p in timeless_planners {
        let body =
            json!({ "planner": p.name(), "goal_ne": [60.0, 40.0], "cell_m": 5.0, "seed": 3 });
        let (status, got) = post_plan(city(), body.clone()).await;
        assert_eq!(status, StatusCode::OK, "{p}: {got}");
        let request: PlanRequest = serde_json::from_value(body).expect("a valid request");
        // `auto` uses what the session keeps (here the JPS+ table of the jps-plus request
        // before it): compared with a fresh session, as the server's is.
        let want = match p {
            PlannerId::Auto => Session::new(World::fcnd_city()).plan(&request),
            _ => session.plan(&request),
        }
        .expect("the API plans it");
        let want = serde_json::to_value(&want).expect("serialisable");
        assert_eq!(got["planner"], p.name());
        assert_eq!(timeless(got), timeless(want), "{p}");
    }
}

#[tokio::test]
async fn malformed_requests_get_400_naming_the_field() {
    for (body, phrases) in [
        (r#"{"alt_m": "high"}"#, vec!["alt_m", "invalid type"]),
        (r#"{"safty_m": 3}"#, vec!["safty_m", "unknown field"]),
        (r#"{"start_ne": [1, 2, 3]}"#, vec!["start_ne"]),
        (r#"{"alt_m": 5"#, vec!["EOF"]),
        (r#"[1, 2]"#, vec!["invalid type"]),
        (r#"{"alt_m": -5}"#, vec!["alt_m -5"]),
    ] {
        let (status, v) = send(city(), "POST", "/api/plan", body).await;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{body}: {v}");
        assert_eq!(v["status"], "error");
        assert_eq!(v["kind"], "bad_request");
        let message = message(&v);
        for p in phrases {
            assert!(message.contains(p), "{body}: {message:?} lacks {p:?}");
        }
    }
}

#[tokio::test]
async fn plan_requests_must_say_they_are_json() {
    for content_type in [
        Some("text/plain"),
        Some("application/x-www-form-urlencoded"),
        None,
    ] {
        let mut request = Request::post("/api/plan");
        if let Some(c) = content_type {
            request = request.header("content-type", c);
        }
        let response = city()
            .oneshot(request.body(Body::from("{}")).expect("request"))
            .await
            .expect("answer");
        assert_eq!(
            response.status(),
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "{content_type:?}"
        );
    }
    let response = city()
        .oneshot(
            Request::post("/api/plan")
                .header("content-type", "Application/JSON; charset=utf-8")
                .body(Body::from("{}"))
                .expect("request"),
        )
        .await
        .expect("answer");
    assert_eq!(response.status(), StatusCode::OK);
}

#[tokio::test]
async fn an_unknown_planner_gets_400_listing_the_planners() {
    let (status, v) = post_plan(city(), json!({ "planner": "rrt" })).await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    let message = message(&v);
    assert!(message.starts_with("planner: unknown planner"), "{message}");
    for p in PlannerId::ALL {
        assert!(message.contains(p.name()), "{message} lacks {p}");
    }
}

#[tokio::test]
async fn no_route_failures_get_422_with_their_kind() {
    let (status, v) = post_plan(city(), json!({ "goal_ne": [5000.0, 0.0] })).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["kind"], "invalid_goal");
    // Inside a building's margin.
    let world = World::fcnd_city();
    let b = world.colliders().map(|m| m.boxes[100]).expect("boxes");
    let (status, v) = post_plan(city(), json!({ "start_ne": [b.north_m, b.east_m] })).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["kind"], "invalid_start");
}

#[tokio::test]
async fn bodies_over_one_mib_get_413() {
    let big = format!(r#"{{"planner": "jps", "pad": "{}"}}"#, "x".repeat(1 << 20));
    let (status, v) = send(city(), "POST", "/api/plan", big).await;
    assert_eq!(status, StatusCode::PAYLOAD_TOO_LARGE, "{v}");
    assert_eq!(v["kind"], "too_large");
    // Just under the limit is read (and refused for its content, not its size).
    let padded = format!("{{}}{}", " ".repeat((1 << 20) - 2));
    let (status, _) = send(city(), "POST", "/api/plan", padded).await;
    assert_eq!(status, StatusCode::OK);
}

#[tokio::test]
async fn without_a_queue_past_the_concurrency_limit_requests_get_503() {
    let config = ServerConfig {
        max_concurrent: 1,
        queue_depth: Some(0),
        ..ServerConfig::default()
    };
    let app = router(World::fcnd_city(), config);
    // RRT* keeps improving until its time limit: it holds the only worker for 1.5 s.
    let slow = tokio::spawn(post_plan(
        app.clone(),
        json!({ "planner": "rrt-star", "goal_ne": [420.0, 390.0], "time_limit_ms": 1500 }),
    ));
    tokio::time::sleep(Duration::from_millis(300)).await;
    let (status, v) = post_plan(app.clone(), json!({})).await;
    assert_eq!(status, StatusCode::SERVICE_UNAVAILABLE, "{v}");
    assert_eq!(v["kind"], "busy");
    let (status, v) = slow.await.expect("the slow plan ends");
    assert_eq!(status, StatusCode::OK, "{v}");
    // The worker is free again.
    let (status, _) = post_plan(app, json!({})).await;
    assert_eq!(status, StatusCode::OK);
}

#[tokio::test]
async fn a_burst_past_the_workers_waits_in_the_queue_and_every_request_is_planned() {
    // One worker, the default queue (64 per worker), a budget long enough for a debug build to
    // plan the burst one after another.
    let config = ServerConfig {
        max_concurrent: 1,
        timeout: Duration::from_secs(300),
        ..ServerConfig::default()
    };
    let app = router(World::fcnd_city(), config);
    let goals = [[420.0, 390.0], [308.5, -250.5], [60.0, 40.0]];
    let requests: Vec<Value> = ["theta", "jps-plus"]
        .iter()
        .flat_map(|p| goals.map(|g| json!({ "planner": p, "goal_ne": g, "cell_m": 5.0 })))
        .collect();
    let burst: Vec<_> = requests
        .iter()
        .map(|r| tokio::spawn(post_plan(app.clone(), r.clone())))
        .collect();
    let mut session = Session::new(World::fcnd_city());
    let mut planned = 0;
    for (task, request) in burst.into_iter().zip(&requests) {
        let (status, v) = task.await.expect("the request is answered");
        // The planning API's own answer for the same request, whatever it is.
        let request: PlanRequest = serde_json::from_value(request.clone()).expect("a request");
        match session.plan(&request) {
            Ok(plan) => {
                assert_eq!(status, StatusCode::OK, "{v}");
                let want = serde_json::to_value(&plan).expect("serialisable");
                assert_eq!(timeless(v), timeless(want));
                planned += 1;
            }
            Err(failure) => {
                assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
                assert_eq!(v["kind"], failure.kind.name());
            }
        }
    }
    assert!(planned >= 3, "{planned} of the burst planned");
    let (status, s) = send(app, "GET", "/api/status", Body::empty()).await;
    assert_eq!(status, StatusCode::OK, "{s}");
    assert_eq!(s["workers"], 1);
    assert_eq!(s["queue_depth"], 64);
    assert_eq!(s["budget_ms"], 300_000);
    // Every request was served by the worker; none refused, none timed out; nothing in flight.
    assert_eq!(s["served"], requests.len());
    for key in [
        "busy",
        "queued",
        "rejected",
        "queue_timeouts",
        "over_budget",
    ] {
        assert_eq!(s[key], 0, "{key}: {s}");
    }
    assert!(s["recent_job_ms"].is_u64(), "{s}");
}

#[tokio::test]
async fn past_the_time_budget_requests_get_504_and_long_limits_400() {
    let app = city_with_budget(Duration::from_millis(1));
    let (status, v) = post_plan(app, json!({ "cell_m": 0.5 })).await;
    assert_eq!(status, StatusCode::GATEWAY_TIMEOUT, "{v}");
    assert_eq!(v["kind"], "over_budget");
    let (status, v) = post_plan(city(), json!({ "planner": "prm", "time_limit_ms": 600000 })).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
    assert!(message(&v).contains("time_limit_ms 600000"), "{v}");
    let (status, v) = post_plan(city(), json!({ "cell_m": 0.01 })).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
    assert!(message(&v).contains("cell_m 0.01"), "{v}");
}

/// The `ch` planner's preprocessing takes minutes on the open city at 1 m: it gives up before
/// the budget with a `timeout` failure (422) instead of a 504 with the work left running.
#[tokio::test]
async fn preprocessing_past_the_budget_is_a_timeout_failure_not_a_504() {
    let app = city_with_budget(Duration::from_millis(3000));
    let (status, v) = post_plan(app.clone(), json!({ "planner": "ch" })).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{v}");
    assert_eq!(v["kind"], "timeout");
    assert!(
        message(&v).contains("did not finish within the time allowed"),
        "{v}"
    );
    // The worker is free again at once.
    let (status, _) = post_plan(app, json!({})).await;
    assert_eq!(status, StatusCode::OK);
}

#[tokio::test]
async fn the_map_has_its_boxes_and_on_request_the_grid_as_runs() {
    let (status, m) = send(city(), "GET", "/api/map", Body::empty()).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(m["obstacles"].as_array().map(Vec::len), Some(3845));
    assert!(m.get("grid").is_none());
    assert!((m["home"]["lat_deg"].as_f64().unwrap_or(0.0) - 37.79).abs() < 0.01);
    assert_eq!(m["default_goal_ne"], json!([420.0, 390.0]));

    let (status, m) = send(
        city(),
        "GET",
        "/api/map?alt_m=10&safety_m=3&cell_m=2",
        Body::empty(),
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{m}");
    let want = Session::new(World::fcnd_city())
        .grid(10.0, 3.0, 2.0)
        .expect("a grid");
    let g = &m["grid"];
    assert_eq!(g["rows"].as_u64(), Some(u64::from(want.rows())));
    assert_eq!(g["cols"].as_u64(), Some(u64::from(want.cols())));
    assert_eq!(
        g["blocked_cells"].as_u64(),
        Some(want.blocked_count() as u64)
    );
    // Decoding the runs gives the grid back, cell for cell.
    let mut decoded = Vec::new();
    for row in g["runs"].as_array().expect("rows") {
        let mut blocked = false;
        for len in row.as_array().expect("runs") {
            decoded.extend(std::iter::repeat_n(
                blocked,
                len.as_u64().unwrap_or(0) as usize,
            ));
            blocked = !blocked;
        }
    }
    assert_eq!(decoded, want.blocked_cells());

    for query in ["cell_m=0.001", "alt_m=high", "path=/etc/passwd"] {
        let (status, v) = send(city(), "GET", &format!("/api/map?{query}"), Body::empty()).await;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{query}: {v}");
        assert_eq!(v["kind"], "bad_request");
    }
}

#[tokio::test]
async fn the_registry_lists_every_planner_and_what_this_map_takes() {
    let (status, v) = send(city(), "GET", "/api/planners", Body::empty()).await;
    assert_eq!(status, StatusCode::OK);
    let names: Vec<&str> = v["planners"]
        .as_array()
        .expect("planners")
        .iter()
        .filter_map(|p| p["name"].as_str())
        .collect();
    let want: Vec<&str> = PlannerId::ALL.iter().map(|p| p.name()).collect();
    assert_eq!(names, want);
    assert_eq!(v["default"], "jps");
    // A grid map does not take the planners that need obstacles.
    let grid = skyplan_cspace::Grid2::from_ascii("....\n....").expect("a grid");
    let (_, v) = send(
        router(World::from_grid("tiny", grid), ServerConfig::default()),
        "GET",
        "/api/planners",
        Body::empty(),
    )
    .await;
    let available = |name: &str| {
        v["planners"]
            .as_array()
            .and_then(|ps| ps.iter().find(|p| p["name"] == name))
            .map(|p| p["available"].clone())
    };
    assert_eq!(available("jps"), Some(json!(true)));
    assert_eq!(available("rrt-star"), Some(json!(false)));
}

#[tokio::test]
async fn the_page_is_one_self_contained_file() {
    let response = city()
        .oneshot(Request::get("/").body(Body::empty()).expect("request"))
        .await
        .expect("answer");
    assert_eq!(response.status(), StatusCode::OK);
    assert!(content_type(&response).starts_with("text/html"));
    let page = String::from_utf8(
        axum::body::to_bytes(response.into_body(), usize::MAX)
            .await
            .expect("body")
            .to_vec(),
    )
    .expect("UTF-8");
    assert!(page.contains("<canvas"));
    assert!(page.contains("/api/events"));
    assert!(
        !page.contains("http://") && !page.contains("https://"),
        "no CDN"
    );
    assert!(!page.contains("webgl"));
    let (status, v) = send(city(), "GET", "/nowhere", Body::empty()).await;
    assert_eq!(
        (status, v["kind"].as_str()),
        (StatusCode::NOT_FOUND, Some("not_found"))
    );
    let (status, v) = send(city(), "GET", "/api/plan", Body::empty()).await;
    assert_eq!(
        (status, v["kind"].as_str()),
        (StatusCode::METHOD_NOT_ALLOWED, Some("method_not_allowed"))
    );
}

// ---- a real loopback server: the event stream -------------------------------------------------

/// Opens `GET /api/events` and reads the response head; the stream is then live.
/// The status code of an HTTP response's first line (0 if there is none).
fn status_code(response: &str) -> u16 {
    response
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0)
}

fn open_events(addr: std::net::SocketAddr) -> (u16, BufReader<TcpStream>) {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(10)))
        .expect("timeout");
    write!(
        s,
        "GET /api/events HTTP/1.1\r\nHost: {addr}\r\nAccept: text/event-stream\r\n\r\n"
    )
    .expect("write");
    let mut r = BufReader::new(s);
    let mut status = String::new();
    r.read_line(&mut status).expect("status line");
    let code = status_code(&status);
    loop {
        let mut line = String::new();
        r.read_line(&mut line).expect("header");
        if line == "\r\n" || line.is_empty() {
            break;
        }
    }
    (code, r)
}

/// Reads the stream until an `event: NAME` line; returns the data line after it.
fn next_event(r: &mut BufReader<TcpStream>, name: &str) -> String {
    let mut seen_name = false;
    loop {
        let mut line = String::new();
        assert!(r.read_line(&mut line).expect("read") > 0, "stream ended");
        let line = line.trim_end();
        if line == format!("event: {name}") {
            seen_name = true;
        } else if let (true, Some(data)) = (seen_name, line.strip_prefix("data: ")) {
            return data.to_string();
        }
    }
}

fn http(addr: std::net::SocketAddr, method: &str, path: &str, body: &str) -> (u16, String) {
    http_as(addr, &addr.to_string(), method, path, body)
}

/// As [`http`], with this `Host` header.
fn http_as(
    addr: std::net::SocketAddr,
    host: &str,
    method: &str,
    path: &str,
    body: &str,
) -> (u16, String) {
    let mut s = TcpStream::connect(addr).expect("connect");
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\nContent-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .expect("write");
    let mut text = String::new();
    s.read_to_string(&mut text).expect("read");
    let code = status_code(&text);
    (code, text)
}

#[test]
fn events_stream_plans_and_flights_and_disconnected_clients_are_freed() {
    let config = ServerConfig {
        max_event_clients: 2,
        ..ServerConfig::default()
    };
    let view = ViewServer::start_with(World::fcnd_city(), "127.0.0.1:0", config)
        .expect("a loopback server");
    let addr = view.addr();
    assert!(addr.ip().is_loopback());
    let (code, page) = http(addr, "GET", "/", "");
    assert_eq!(code, 200);
    assert!(page.contains("<canvas"));
    // DNS rebinding: another site's name pointed at the loopback address is refused.
    let (code, text) = http_as(addr, "attacker.example", "GET", "/api/map", "");
    assert_eq!(code, 403, "{text}");
    assert!(text.contains("DNS-rebinding"), "{text}");
    let (code, _) = http_as(addr, &format!("localhost:{}", addr.port()), "GET", "/", "");
    assert_eq!(code, 200);

    let (code, mut stream) = open_events(addr);
    assert_eq!(code, 200);
    let (code, _other) = open_events(addr);
    assert_eq!(code, 200);
    let (code, _) = open_events(addr);
    assert_eq!(code, 503, "a third client is over the limit of 2");

    let (code, body) = http(addr, "POST", "/api/plan", r#"{"planner": "jps-plus"}"#);
    assert_eq!(code, 200, "{body}");
    let plan: Value = serde_json::from_str(&next_event(&mut stream, "plan")).expect("JSON");
    assert_eq!(plan["type"], "plan");
    assert_eq!(plan["status"], "ok");
    assert_eq!(plan["planner"], "jps-plus");
    assert!((plan["cost_m"].as_f64().unwrap_or(0.0) - 1097.94).abs() < 0.01);

    view.publish(&ViewEvent::Flight(FlightEvent {
        time_s: 1.5,
        north_m: 10.0,
        east_m: -4.0,
        alt_m: 5.0,
        heading_deg: 90.0,
        speed_m_s: 3.0,
        state: "WAYPOINT".into(),
        waypoint_index: Some(2),
        armed: true,
    }));
    let flight: Value = serde_json::from_str(&next_event(&mut stream, "flight")).expect("JSON");
    assert_eq!(flight["state"], "WAYPOINT");
    assert_eq!(flight["waypoint_index"], 2);
    assert_eq!(view.sink().clients(), 2);

    // Both clients hang up: their receivers are dropped (noticed at the next write at the latest).
    drop(stream);
    drop(_other);
    let landed = ViewEvent::Flight(FlightEvent {
        time_s: 2.0,
        north_m: 0.0,
        east_m: 0.0,
        alt_m: 0.0,
        heading_deg: 0.0,
        speed_m_s: 0.0,
        state: "MANUAL".into(),
        waypoint_index: None,
        armed: false,
    });
    view.publish(&landed);
    let t0 = Instant::now();
    while view.sink().clients() > 0 && t0.elapsed() < Duration::from_secs(5) {
        view.publish(&landed);
        std::thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(view.sink().clients(), 0);
    // Their slots are free again, and a late client gets the latest route and flight state
    // first.
    view.publish(&ViewEvent::Route(RouteEvent {
        reason: "plan".into(),
        planner: "jps".into(),
        waypoints: vec![[0.0, 0.0, 5.0], [10.0, 0.0, 5.0]],
        trajectory: None,
    }));
    let (code, mut again) = open_events(addr);
    assert_eq!(code, 200);
    let flight: Value = serde_json::from_str(&next_event(&mut again, "flight")).expect("JSON");
    assert_eq!(flight["state"], "MANUAL");
    let route: Value = serde_json::from_str(&next_event(&mut again, "route")).expect("JSON");
    assert_eq!(
        route["waypoints"],
        json!([[0.0, 0.0, 5.0], [10.0, 0.0, 5.0]])
    );
}

#[tokio::test]
async fn app_events_reach_a_oneshot_stream() {
    let a = app(World::fcnd_city(), ServerConfig::default());
    assert_eq!(a.events.clients(), 0);
    let response = a
        .router
        .clone()
        .oneshot(
            Request::get("/api/events")
                .body(Body::empty())
                .expect("request"),
        )
        .await
        .expect("answer");
    assert_eq!(response.status(), StatusCode::OK);
    assert_eq!(content_type(&response), "text/event-stream");
    assert_eq!(a.events.clients(), 1);
    drop(response);
    assert_eq!(
        a.events.clients(),
        0,
        "dropping the response frees the subscription"
    );
}

/// A bad zone document is a 400 naming the feature and the field; a planner that cannot honour
/// zones says so.
#[tokio::test]
async fn bad_no_fly_zones_are_bad_requests() {
    let missing = r#"{"type": "FeatureCollection", "features": [{"type": "Feature",
        "properties": {"radius_m": 10}, "geometry": {"type": "Point", "coordinates": [-122.39, 37.79]}}]}"#;
    let (status, got) = post_plan(city(), json!({ "no_fly": missing })).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{got}");
    assert!(
        got.to_string()
            .contains("no_fly: feature 0, properties.floor_m: missing"),
        "{got}"
    );
    let zones = include_str!("../../../data/no-fly-sample.geojson");
    let (status, got) = post_plan(
        city(),
        json!({ "planner": "voronoi", "goal_ne": [60.0, 40.0], "no_fly": zones }),
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{got}");
    assert!(
        got.to_string().contains("does not honour no-fly zones"),
        "{got}"
    );
}
