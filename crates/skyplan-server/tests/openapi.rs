//! `openapi.json` against what it describes. Its planner list (`PlannerName`) is generated from
//! the registry:
//!
//! ```text
//! SKYPLAN_BLESS=1 cargo test -p skyplan-server --test openapi openapi_json_is_what_the_registry_gives
//! ```
//!
//! rewrites it. The rest, written by hand, is checked against the types and the served answers
//! field by field: the request's properties against `PlanRequest` (names both ways, values of each documented type
//! taken, values outside it refused), every planner's served plan, the registry, the map and
//! the errors against their schemas, and the `Plan` type's fields against the `Plan` schema.

use axum::Router;
use axum::body::Body;
use axum::http::{Request, StatusCode};
use serde::Serialize;
use serde_json::{Map, Value, json};
use skyplan_plan::{MapKinds, PlanRequest, PlannerId, Session, World};
use skyplan_server::{ErrorKind, OPENAPI_JSON, ServerConfig, router};
use std::collections::BTreeSet;
use tower::ServiceExt;

/// The file, in the source tree.
const DOC_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/openapi.json");

/// The command that regenerates the file's generated parts: this file's generator test alone (the
/// others check the document compiled into the server, which predates the rewrite until the next
/// build).
const REGENERATE: &str = "SKYPLAN_BLESS=1 cargo test -p skyplan-server --test openapi openapi_json_is_what_the_registry_gives";

/// Where the generated planner list lives in the document.
const PLANNER_NAME: &str = "#/components/schemas/PlannerName";

// ---- the generated parts ------------------------------------------------------------------

/// The note on the document's first line.
fn note() -> String {
    format!(
        "Partly generated: components/schemas/PlannerName (every planner, with its summary) is \
         written from the planner registry (skyplan_plan::PlannerId) by `{REGENERATE}`; do not \
         edit it by hand. The rest is written by hand and checked against the types and the \
         served answers by the same test file (crates/skyplan-server/tests/openapi.rs)."
    )
}

/// A string of serde's spelling of `v` (`exact`, `any_grid`).
fn spelled(v: impl Serialize) -> String {
    serde_json::to_value(v)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

/// One planner's line in the `PlannerName` description.
fn planner_line(p: PlannerId) -> String {
    let i = p.info();
    format!(
        "- `{}` ({}D, {}, maps: {}): {}",
        i.name,
        i.dims,
        spelled(i.optimality),
        spelled(i.maps),
        i.summary
    )
}

/// The `PlannerName` schema: every planner of the registry, in its order, described by its
/// registry row.
fn planner_name_schema() -> Value {
    let names: Vec<&str> = PlannerId::ALL.iter().map(|p| p.name()).collect();
    let lines: Vec<String> = PlannerId::ALL.iter().map(|&p| planner_line(p)).collect();
    json!({
        "type": "string",
        "enum": names,
        "description": format!(
            "A planner, by its name in the registry (GET /api/planners lists them with what the \
             map takes); a request without one plans with `{}`. Generated from the registry: \
             do not edit.\n\n{}",
            PlannerId::default(),
            lines.join("\n")
        ),
    })
}

/// `v` as the file writes JSON: pretty, one space per level.
fn pretty(v: &Value) -> String {
    let mut out = Vec::new();
    let formatter = serde_json::ser::PrettyFormatter::with_indent(b" ");
    let mut ser = serde_json::Serializer::with_formatter(&mut out, formatter);
    v.serialize(&mut ser).expect("a JSON value serialises");
    String::from_utf8(out).expect("serde_json writes UTF-8")
}

/// Byte index just past the JSON object or array opening at `open`.
fn end_of_value(text: &str, open: usize) -> Option<usize> {
    let (mut depth, mut in_string, mut escaped) = (0usize, false, false);
    for (i, c) in text[open..].char_indices() {
        match (in_string, escaped, c) {
            (true, true, _) => escaped = false,
            (true, false, '\\') => escaped = true,
            (true, false, '"') => in_string = false,
            (true, false, _) => {}
            (false, _, '"') => in_string = true,
            (false, _, '{' | '[') => depth += 1,
            (false, _, '}' | ']') => {
                depth = depth.checked_sub(1)?;
                if depth == 0 {
                    return Some(open + i + 1);
                }
            }
            (false, _, _) => {}
        }
    }
    None
}

/// The document's text with its generated parts (the note on the first line, the
/// `PlannerName` schema) written from the registry; the hand-written rest byte for byte.
fn with_registry(text: &str) -> Result<String, String> {
    let body = (text.strip_prefix("{\n")).ok_or("openapi.json must start with `{` on a line")?;
    let body = match body.strip_prefix(" \"x-generated\": ") {
        Some(rest) => rest.split_once('\n').map_or("", |(_, r)| r),
        None => body,
    };
    let note = serde_json::to_string(&note()).map_err(|e| e.to_string())?;
    let text = format!("{{\n \"x-generated\": {note},\n{body}");
    let key = "\"PlannerName\": ";
    let at = match text.match_indices(key).map(|(i, _)| i).collect::<Vec<_>>()[..] {
        [at] => at,
        _ => return Err(format!("openapi.json needs exactly one {key}{{…}} schema")),
    };
    let open = at + key.len();
    let end = end_of_value(&text, open)
        .filter(|_| text[open..].starts_with('{'))
        .ok_or("openapi.json: PlannerName is not a JSON object")?;
    let indent = &text[text[..at].rfind('\n').map_or(0, |i| i + 1)..at];
    let schema = pretty(&planner_name_schema()).replace('\n', &format!("\n{indent}"));
    Ok(format!("{}{schema}{}", &text[..open], &text[end..]))
}

/// What differs between the document's planner list and the registry, planner by planner.
fn planner_differences(doc: &Value) -> Vec<String> {
    let schema = &doc["components"]["schemas"]["PlannerName"];
    let listed: Vec<&str> = (schema["enum"].as_array().into_iter().flatten())
        .filter_map(Value::as_str)
        .collect();
    let description = schema["description"].as_str().unwrap_or_default();
    let mut out = Vec::new();
    for &p in PlannerId::ALL {
        if !listed.contains(&p.name()) {
            out.push(format!(
                "planner {p} is in the registry but not in openapi.json"
            ));
        } else if !description.lines().any(|l| l == planner_line(p)) {
            out.push(format!(
                "planner {p}: openapi.json's description differs from its registry row"
            ));
        }
    }
    for name in &listed {
        if name.parse::<PlannerId>().is_err() {
            out.push(format!(
                "planner {name} is in openapi.json but not in the registry"
            ));
        }
    }
    out
}

#[test]
fn openapi_json_is_what_the_registry_gives() {
    let text = std::fs::read_to_string(DOC_PATH).expect("openapi.json is readable");
    let want = with_registry(&text).unwrap_or_else(|e| panic!("{e}"));
    if std::env::var("SKYPLAN_BLESS").as_deref() == Ok("1") && want != text {
        std::fs::write(DOC_PATH, &want).expect("openapi.json is writable");
        eprintln!("wrote {DOC_PATH}");
    }
    let text = std::fs::read_to_string(DOC_PATH).expect("openapi.json is readable");
    let doc: Value = serde_json::from_str(&text).expect("openapi.json is JSON");
    let differences = planner_differences(&doc);
    assert!(
        differences.is_empty(),
        "{}; regenerate with {REGENERATE}",
        differences.join("; ")
    );
    assert!(
        text == want,
        "openapi.json differs from what the registry gives (its first line or the PlannerName \
         schema); regenerate with {REGENERATE}"
    );
    assert!(
        text.lines().nth(1).is_some_and(|l| l.contains("generated")),
        "the first lines say what is generated"
    );
}

/// Every array of strings in `v` holding two or more planner names, by path.
fn name_lists(v: &Value, at: &str, out: &mut Vec<String>) {
    match v {
        Value::Array(items) => {
            let names = (items.iter().filter_map(Value::as_str))
                .filter(|s| s.parse::<PlannerId>().is_ok())
                .count();
            if names >= 2 {
                out.push(at.to_string());
            }
            for (i, x) in items.iter().enumerate() {
                name_lists(x, &format!("{at}/{i}"), out);
            }
        }
        Value::Object(o) => {
            for (k, x) in o {
                name_lists(x, &format!("{at}/{k}"), out);
            }
        }
        _ => {}
    }
}

#[test]
fn every_planner_in_the_document_refers_to_the_one_generated_list() {
    let doc = document();
    let mut lists = Vec::new();
    name_lists(&doc, "#", &mut lists);
    assert_eq!(lists, [format!("{PLANNER_NAME}/enum")], "planner lists");
    let schemas = &doc["components"]["schemas"];
    for planner in [
        &schemas["PlanRequest"]["properties"]["planner"],
        &schemas["Plan"]["properties"]["planner"],
        &schemas["Planners"]["properties"]["default"],
        &schemas["Planners"]["properties"]["planners"]["items"]["properties"]["name"],
    ] {
        assert_eq!(planner, &json!({ "$ref": PLANNER_NAME }));
    }
}

// ---- the hand-written rest against the types ----------------------------------------------

/// The served document.
fn document() -> Value {
    serde_json::from_str(OPENAPI_JSON).expect("openapi.json is JSON")
}

/// A schema with its `$ref` followed.
fn resolved<'a>(doc: &'a Value, schema: &'a Value) -> &'a Value {
    match schema["$ref"].as_str() {
        Some(r) => {
            let name = r
                .strip_prefix("#/components/schemas/")
                .expect("a local $ref");
            resolved(doc, &doc["components"]["schemas"][name])
        }
        None => schema,
    }
}

/// The number in `schema[key]`, if any.
fn bound(schema: &Value, key: &str) -> Option<f64> {
    schema[key].as_f64()
}

/// Where `v` breaks `schema` (empty when it conforms): types, enums, nullability, required
/// and (where `additionalProperties` is false) undocumented properties, array lengths, bounds.
fn violations(doc: &Value, schema: &Value, v: &Value, at: &str) -> Vec<String> {
    let s = resolved(doc, schema);
    if v.is_null() {
        let nullable = s["nullable"] == true;
        return (!nullable)
            .then(|| format!("{at}: null"))
            .into_iter()
            .collect();
    }
    let mut out = Vec::new();
    if let Some(allowed) = s["enum"].as_array()
        && !allowed.contains(v)
    {
        out.push(format!("{at}: {v} is not one of {}", s["enum"]));
    }
    let ty = s["type"].as_str().unwrap_or("any");
    let fits = match ty {
        "object" => v.is_object(),
        "array" => v.is_array(),
        "string" => v.is_string(),
        "number" => v.is_number(),
        "integer" => v.is_i64() || v.is_u64(),
        "boolean" => v.is_boolean(),
        _ => true,
    };
    if !fits {
        out.push(format!("{at}: {v} is not of type {ty}"));
        return out;
    }
    if let Some(x) = v.as_f64() {
        let low = bound(s, "minimum").is_some_and(|m| x < m);
        let high = bound(s, "maximum").is_some_and(|m| x > m);
        if low || high {
            out.push(format!("{at}: {v} is out of the documented range"));
        }
    }
    if let Some(o) = v.as_object() {
        out.extend(object_violations(doc, s, o, at));
    }
    if let Some(items) = v.as_array() {
        let n = items.len() as f64;
        let short = bound(s, "minItems").is_some_and(|m| n < m);
        let long = bound(s, "maxItems").is_some_and(|m| n > m);
        if short || long {
            out.push(format!("{at}: {} items", items.len()));
        }
        for (i, x) in items.iter().enumerate() {
            out.extend(violations(doc, &s["items"], x, &format!("{at}/{i}")));
        }
    }
    out
}

/// [`violations`] of an object's properties.
fn object_violations(doc: &Value, s: &Value, o: &Map<String, Value>, at: &str) -> Vec<String> {
    let mut out = Vec::new();
    for key in s["required"].as_array().into_iter().flatten() {
        if let Some(k) = key.as_str()
            && !o.contains_key(k)
        {
            out.push(format!("{at}: required {k} is missing"));
        }
    }
    for (k, x) in o {
        match s["properties"].get(k) {
            Some(p) => out.extend(violations(doc, p, x, &format!("{at}/{k}"))),
            None if s["additionalProperties"] == false => {
                out.push(format!("{at}: {k} is not documented"));
            }
            None => {}
        }
    }
    out
}

/// Values of a request property's documented schema: some the schema takes, some it refuses.
fn samples(doc: &Value, schema: &Value) -> (Vec<Value>, Vec<Value>) {
    let s = resolved(doc, schema);
    if let Some(allowed) = s["enum"].as_array() {
        return (allowed.clone(), vec![json!("no-such-value"), json!(1)]);
    }
    match s["type"].as_str().unwrap_or_default() {
        "number" => (vec![json!(2.5), json!(-7.25)], vec![json!("2.5")]),
        "boolean" => (vec![json!(true), json!(false)], vec![json!("yes")]),
        "string" => (vec![json!("text")], vec![json!(1)]),
        "integer" => {
            let (low, high) = (bound(s, "minimum"), bound(s, "maximum"));
            let mut taken = vec![json!(low.unwrap_or(-3.0) as i64)];
            taken.extend(high.map(|m| json!(m as i64)));
            let mut refused = vec![json!(2.5)];
            refused.extend(low.map(|m| json!(m as i64 - 1)));
            refused.extend(high.map(|m| json!(m as i64 + 1)));
            (taken, refused)
        }
        "array" => {
            let n = bound(s, "minItems").unwrap_or(1.0) as usize;
            let item = samples(doc, &s["items"]).0.remove(0);
            let mut refused = vec![json!(vec![item.clone(); n + 1]), json!("1,2")];
            if n > 0 {
                refused.push(json!(vec![item.clone(); n - 1]));
            }
            (vec![json!(vec![item; n])], refused)
        }
        other => panic!("no samples for a property of type {other:?}"),
    }
}

#[test]
fn the_request_schema_is_the_request_type_field_by_field() {
    let doc = document();
    let schema = &doc["components"]["schemas"]["PlanRequest"];
    assert_eq!(
        schema["additionalProperties"], false,
        "the type refuses other keys"
    );
    let documented: BTreeSet<String> = (schema["properties"]
        .as_object()
        .expect("properties")
        .keys()
        .cloned())
    .collect();
    let fields: BTreeSet<String> = serde_json::to_value(PlanRequest::default())
        .expect("serialisable")
        .as_object()
        .expect("an object")
        .keys()
        .cloned()
        .collect();
    let undocumented: Vec<_> = fields.difference(&documented).collect();
    let extra: Vec<_> = documented.difference(&fields).collect();
    assert!(
        undocumented.is_empty() && extra.is_empty(),
        "PlanRequest fields not in openapi.json: {undocumented:?}; documented but not fields: {extra:?}"
    );
    for (field, property) in schema["properties"].as_object().expect("properties") {
        let (taken, refused) = samples(&doc, property);
        for value in taken {
            let request: PlanRequest = serde_json::from_value(json!({ field: value }))
                .unwrap_or_else(|e| panic!("{field}: the documented {value} is refused: {e}"));
            let back = serde_json::to_value(&request).expect("serialisable");
            assert_eq!(back[field], value, "{field}: {value} does not round-trip");
        }
        for value in refused {
            let parsed = serde_json::from_value::<PlanRequest>(json!({ field: value }));
            assert!(
                parsed.is_err(),
                "{field}: {value}, outside the schema, is taken"
            );
        }
    }
}

async fn send(app: Router, method: &str, uri: &str, body: Value) -> (StatusCode, Value) {
    let body = if body.is_null() {
        Body::empty()
    } else {
        Body::from(body.to_string())
    };
    let request = Request::builder()
        .method(method)
        .uri(uri)
        .header("content-type", "application/json")
        .body(body)
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

/// The schema of `path`'s `method` answer with `status`.
fn answer_schema<'a>(doc: &'a Value, path: &str, method: &str, status: StatusCode) -> &'a Value {
    let schema = &doc["paths"][path][method]["responses"][status.as_str()]["content"]["application/json"]
        ["schema"];
    assert!(
        schema.is_object(),
        "{method} {path}: {status} is undocumented"
    );
    schema
}

/// A request for every planner that each plans on the city quickly (a 5 m grid: `ch`'s
/// preprocessing at 1 m takes minutes; 10 m for the planners of small grids, whose tables the
/// city at 5 m would outgrow), with the pictures' geometry and a trajectory.
fn quick_request(p: PlannerId) -> Value {
    let cell_m = if p.info().maps == MapKinds::SmallGrid {
        10.0
    } else {
        5.0
    };
    json!({ "planner": p.name(), "goal_ne": [60.0, 40.0], "cell_m": cell_m, "geometry": true, "trajectory": true })
}

#[tokio::test]
async fn every_planners_served_plan_matches_the_plan_schema() {
    let doc = document();
    let app = router(World::fcnd_city(), ServerConfig::default());
    let schema = answer_schema(&doc, "/api/plan", "post", StatusCode::OK);
    for &p in PlannerId::ALL {
        let (status, plan) = send(app.clone(), "POST", "/api/plan", quick_request(p)).await;
        assert_eq!(status, StatusCode::OK, "{p}: {plan}");
        let wrong = violations(&doc, schema, &plan, &format!("plan of {p}"));
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    }
}

#[test]
fn the_plan_schema_documents_every_field_of_the_plan_type() {
    let doc = document();
    let schema = &doc["components"]["schemas"]["Plan"];
    let documented: BTreeSet<String> = (schema["properties"]
        .as_object()
        .expect("properties")
        .keys()
        .cloned())
    .collect();
    // The server adds these two to the plan.
    let mut fields = BTreeSet::from(["wall_time_us".to_string(), "request_id".to_string()]);
    let mut session = Session::new(World::fcnd_city());
    for &p in PlannerId::ALL {
        let request: PlanRequest = serde_json::from_value(quick_request(p)).expect("a request");
        let plan = session
            .plan(&request)
            .unwrap_or_else(|e| panic!("{p}: {e}"));
        let json = serde_json::to_value(&plan).expect("serialisable");
        // Planner-specific details are extra keys (additionalProperties); the rest are fields.
        let keys = json.as_object().expect("an object").keys();
        fields.extend(keys.filter(|k| !plan.details.contains_key(*k)).cloned());
        for k in plan.details.keys() {
            assert!(
                !documented.contains(k),
                "{p}: detail {k} is documented as a field of every plan"
            );
        }
    }
    let undocumented: Vec<_> = fields.difference(&documented).collect();
    let extra: Vec<_> = documented.difference(&fields).collect();
    assert!(
        undocumented.is_empty() && extra.is_empty(),
        "Plan fields not in openapi.json: {undocumented:?}; documented but in no planner's plan: {extra:?}"
    );
}

#[tokio::test]
async fn the_registry_the_map_and_errors_match_their_schemas() {
    let doc = document();
    let city = router(World::fcnd_city(), ServerConfig::default());
    let grid = skyplan_cspace::Grid2::from_ascii("....\n....").expect("a grid");
    let tiny = router(World::from_grid("tiny", grid), ServerConfig::default());
    for app in [city.clone(), tiny] {
        let (status, v) = send(app, "GET", "/api/planners", Value::Null).await;
        let schema = answer_schema(&doc, "/api/planners", "get", status);
        let wrong = violations(&doc, schema, &v, "planners");
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
        // Each planner's keys are the registry row's and `available`, both ways.
        let item = &resolved(&doc, schema)["properties"]["planners"]["items"]["properties"];
        let documented: BTreeSet<&String> = item.as_object().expect("properties").keys().collect();
        for (p, served) in PlannerId::ALL
            .iter()
            .zip(v["planners"].as_array().expect("planners"))
        {
            let keys: BTreeSet<&String> = served.as_object().expect("an object").keys().collect();
            assert_eq!(keys, documented, "{p}");
            let row = serde_json::to_value(p.info()).expect("serialisable");
            assert!(
                row.as_object()
                    .expect("an object")
                    .iter()
                    .all(|(k, x)| &served[k] == x),
                "{p}"
            );
        }
    }
    // The status before any job (no recent duration: null) and, below, after some.
    let status_matches = |status: StatusCode, v: &Value| {
        let wrong = violations(
            &doc,
            answer_schema(&doc, "/api/status", "get", status),
            v,
            "status",
        );
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    };
    let (status, v) = send(city.clone(), "GET", "/api/status", Value::Null).await;
    assert!(v["recent_job_ms"].is_null(), "{v}");
    status_matches(status, &v);
    let (status, v) = send(
        city.clone(),
        "GET",
        "/api/map?alt_m=5&safety_m=5&cell_m=5",
        Value::Null,
    )
    .await;
    let wrong = violations(
        &doc,
        answer_schema(&doc, "/api/map", "get", status),
        &v,
        "map",
    );
    assert!(
        wrong.is_empty() && v["grid"].is_object(),
        "{}",
        wrong.join("\n")
    );
    for (body, want) in [
        (json!({ "planner": "rrt" }), StatusCode::BAD_REQUEST),
        (
            json!({ "goal_ne": [5000.0, 0.0] }),
            StatusCode::UNPROCESSABLE_ENTITY,
        ),
    ] {
        let (status, v) = send(city.clone(), "POST", "/api/plan", body).await;
        assert_eq!(status, want, "{v}");
        let wrong = violations(
            &doc,
            answer_schema(&doc, "/api/plan", "post", status),
            &v,
            "error",
        );
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    }
    let (status, v) = send(city, "GET", "/api/status", Value::Null).await;
    assert!(v["recent_job_ms"].is_u64(), "{v}");
    status_matches(status, &v);
}

/// Every error kind the server sends is in the document's list.
#[test]
fn every_error_kind_is_documented() {
    let doc = document();
    let listed = &doc["components"]["schemas"]["Error"]["properties"]["kind"]["enum"];
    let listed: Vec<&str> = listed
        .as_array()
        .expect("an enum")
        .iter()
        .filter_map(Value::as_str)
        .collect();
    for kind in [
        ErrorKind::TooLarge,
        ErrorKind::NotJson,
        ErrorKind::Busy,
        ErrorKind::OverBudget,
        ErrorKind::QueueTimeout,
        ErrorKind::NotFound,
        ErrorKind::MethodNotAllowed,
        ErrorKind::Conflict,
        ErrorKind::StoreUnavailable,
    ] {
        assert!(
            listed.contains(&kind.name()),
            "{} undocumented",
            kind.name()
        );
    }
}

#[tokio::test]
async fn the_served_document_is_the_file_and_documents_every_endpoint_and_status() {
    let (status, served) = send(
        router(World::fcnd_city(), ServerConfig::default()),
        "GET",
        "/api/openapi.json",
        Value::Null,
    )
    .await;
    assert_eq!(status, StatusCode::OK);
    let doc = document();
    assert_eq!(served, doc);
    assert_eq!(doc["openapi"], "3.0.3");
    for p in [
        "/",
        "/api/map",
        "/api/plan",
        "/api/planners",
        "/api/status",
        "/api/events",
        "/api/openapi.json",
        "/api/intents",
        "/api/intents/{id}",
    ] {
        assert!(doc["paths"][p].is_object(), "{p} undocumented");
    }
    // Every status the plan handler answers is documented.
    let responses = doc["paths"]["/api/plan"]["post"]["responses"]
        .as_object()
        .expect("responses");
    for code in ["200", "400", "413", "415", "422", "503", "504"] {
        assert!(responses.contains_key(code), "{code} undocumented");
    }
}

// ---- operational intents ------------------------------------------------------------------

/// A departure an hour from now, in whole seconds, and `s` seconds after it.
fn departure(s: i64) -> String {
    let now = skyplan_airspace::Timestamp::now().unix_ms();
    skyplan_airspace::Timestamp::from_unix_ms((now / 1000 + 3600 + s) * 1000).to_string()
}

/// An intent request over the city's default route.
fn intent_request(departure: Value, priority: u32, owner: &str) -> Value {
    json!({ "plan": { "goal_ne": [60.0, 40.0] }, "departure": departure, "priority": priority, "owner": owner })
}

fn matches_schema(doc: &Value, path: &str, method: &str, status: StatusCode, v: &Value) {
    let wrong = violations(
        doc,
        answer_schema(doc, path, method, status),
        v,
        &format!("{method} {path} {status}"),
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[tokio::test]
async fn intents_answer_201_409_404_as_documented() {
    let doc = document();
    let app = router(World::fcnd_city(), ServerConfig::default());
    let at = departure(0);
    // 201: reserved at the departure asked for, nothing in the way.
    let (status, first) = send(
        app.clone(),
        "POST",
        "/api/intents",
        intent_request(json!(at), 10, "op-a"),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{first}");
    matches_schema(&doc, "/api/intents", "post", status, &first);
    assert_eq!(
        (first["departure"].as_str(), first["delay_s"].as_f64()),
        (Some(at.as_str()), Some(0.0))
    );
    assert_eq!(
        (first["timing"].as_str(), first["intent"]["state"].as_str()),
        (Some("constant_speed"), Some("Accepted"))
    );
    let id = first["intent"]["id"].as_str().expect("an id").to_string();
    // 409: the same flight at the same instant, equal priority; the answer names the first.
    let (status, refused) = send(
        app.clone(),
        "POST",
        "/api/intents",
        intent_request(json!(at), 10, "op-b"),
    )
    .await;
    assert_eq!(status, StatusCode::CONFLICT, "{refused}");
    matches_schema(&doc, "/api/intents", "post", status, &refused);
    assert_eq!(refused["conflicts"], json!([{ "id": id, "version": 1 }]));
    assert!(message(&refused).contains(&id), "{refused}");
    // 201 with a window: the earliest free whole second, after the first's volumes.
    let window = json!({ "earliest": at, "latest": departure(3600) });
    let (status, later) = send(
        app.clone(),
        "POST",
        "/api/intents",
        intent_request(window, 10, "op-b"),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{later}");
    let delay = later["delay_s"].as_f64().expect("a delay");
    assert!(
        delay > 0.0 && delay.fract() == 0.0 && later["nearby_intents"] == 1,
        "{later}"
    );
    // More important: not bound by the others.
    let (status, urgent) = send(
        app.clone(),
        "POST",
        "/api/intents",
        intent_request(json!(at), 11, "op-c"),
    )
    .await;
    assert_eq!(
        (status, urgent["delay_s"].as_f64()),
        (StatusCode::CREATED, Some(0.0)),
        "{urgent}"
    );
    // The list, one, delete, then 404.
    let (status, list) = send(app.clone(), "GET", "/api/intents", Value::Null).await;
    matches_schema(&doc, "/api/intents", "get", status, &list);
    assert_eq!(list["intents"].as_array().map(Vec::len), Some(3));
    assert_eq!(list["intents"][0], first["intent"]);
    let one = format!("/api/intents/{id}");
    let (status, got) = send(app.clone(), "GET", &one, Value::Null).await;
    matches_schema(&doc, "/api/intents/{id}", "get", status, &got);
    assert_eq!(got, first["intent"]);
    let (status, gone) = send(app.clone(), "DELETE", &one, Value::Null).await;
    matches_schema(&doc, "/api/intents/{id}", "delete", status, &gone);
    assert_eq!(gone, first["intent"]);
    for method in ["GET", "DELETE"] {
        let (status, missing) = send(app.clone(), method, &one, Value::Null).await;
        assert_eq!(status, StatusCode::NOT_FOUND);
        matches_schema(
            &doc,
            "/api/intents/{id}",
            &method.to_lowercase(),
            status,
            &missing,
        );
    }
    // With the first gone, only the more important one is in the way at that instant.
    let (status, again) = send(
        app.clone(),
        "POST",
        "/api/intents",
        intent_request(json!(at), 10, "op-b"),
    )
    .await;
    assert_eq!(status, StatusCode::CONFLICT, "{again}");
    assert_eq!(
        again["conflicts"],
        json!([{ "id": urgent["intent"]["id"], "version": 1 }])
    );
}

#[tokio::test]
async fn intents_searched_in_space_and_time_keep_clear_as_documented() {
    let doc = document();
    let app = router(World::fcnd_city(), ServerConfig::default());
    let at = departure(0);
    let body = |departure: Value, search: &str| json!({ "plan": {}, "departure": departure, "priority": 0, "owner": "o", "search": search });
    let (status, first) = send(
        app.clone(),
        "POST",
        "/api/intents",
        body(json!(at), "departure"),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{first}");
    assert!(first.get("space_time").is_none());
    // The same route in a window that starts at the same instant: re-planned in space and time.
    let window = json!({ "earliest": at, "latest": departure(600) });
    let (status, second) = send(
        app.clone(),
        "POST",
        "/api/intents",
        body(window, "space_time"),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{second}");
    matches_schema(&doc, "/api/intents", "post", status, &second);
    assert_eq!(second["timing"], "space_time");
    let st = &second["space_time"];
    assert!(
        st["arrival_delay_s"].as_f64().expect("arrival delay") > 0.0,
        "{st}"
    );
    assert!(st["route_ne"].as_array().expect("route").len() >= 2);
    // The two intents as stored share no point in space and time (the exact 4D test).
    let intent = |v: &Value| -> skyplan_airspace::OperationalIntent {
        serde_json::from_value(v["intent"].clone()).expect("an intent")
    };
    let (a, b) = (intent(&first), intent(&second));
    assert_eq!(
        skyplan_airspace::first_conflict(&b.volumes, &a.volumes),
        None
    );
    // At the very instant, with no window, its start is under the first flight: 409 naming it.
    let (status, refused) = send(
        app.clone(),
        "POST",
        "/api/intents",
        body(json!(at), "space_time"),
    )
    .await;
    assert_eq!(status, StatusCode::CONFLICT, "{refused}");
    matches_schema(&doc, "/api/intents", "post", status, &refused);
    assert!(message(&refused).contains(&a.id), "{refused}");
    // Bad values name the field.
    for (body, want) in [
        (
            body(json!(departure(0)), "sideways"),
            "search: unknown variant `sideways`",
        ),
        (
            json!({ "plan": { "no_fly": ZONES, "departure": departure(0) }, "departure": departure(0), "priority": 0, "owner": "o", "search": "space_time" }),
            "plan.departure: an intent's departure (its window) says when it flies",
        ),
    ] {
        let (status, v) = send(app.clone(), "POST", "/api/intents", body).await;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
        assert!(message(&v).contains(want), "{want:?} not in {v}");
    }
    // With no-fly zones: re-routed around the others and out of the zones by the margin.
    let (status, zoned) = send(
        app.clone(),
        "POST",
        "/api/intents",
        json!({ "plan": { "no_fly": ZONES }, "departure": departure(7200), "priority": 0, "owner": "zones", "search": "space_time" }),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{zoned}");
    matches_schema(&doc, "/api/intents", "post", status, &zoned);
    let route: Vec<[f64; 2]> =
        serde_json::from_value(zoned["space_time"]["route_ne"].clone()).expect("route_ne");
    let home = skyplan_map::colliders::GeodeticHome {
        lat_deg: 37.792480,
        lon_deg: -122.397450,
    };
    let zones = skyplan_map::nofly::parse_no_fly(ZONES)
        .expect("zones")
        .project(home, None)
        .expect("projected");
    // Zones active at some moment of the hour after the departure (the sample's helipad
    // closed on 2026-12-03: flown over after that).
    let departure =
        skyplan_map::nofly::parse_rfc3339(zoned["departure"].as_str().expect("departure"))
            .expect("RFC 3339");
    let active = |z: &&skyplan_map::nofly::Zone| {
        z.start_unix_s.is_none_or(|s| s < departure + 3600)
            && z.end_unix_s.is_none_or(|e| e > departure)
    };
    for z in zones
        .iter()
        .filter(|z| z.meets_altitude(5.0, 5.0))
        .filter(active)
    {
        let c = route
            .windows(2)
            .map(|w| z.clearance_m(w[0], w[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(c >= 5.0 - 1e-3, "zone {}: {c:.3} m", z.feature);
    }
}

const ZONES: &str = include_str!("../../../data/no-fly-sample.geojson");

#[tokio::test]
async fn listing_intents_filters_by_time_altitude_and_area() {
    let doc = document();
    let app = router(World::fcnd_city(), ServerConfig::default());
    let mut ids = Vec::new();
    for (s, owner) in [(0, "early"), (1200, "late")] {
        let (status, v) = send(
            app.clone(),
            "POST",
            "/api/intents",
            intent_request(json!(departure(s)), 0, owner),
        )
        .await;
        assert_eq!(status, StatusCode::CREATED, "{v}");
        ids.push(v["intent"].clone());
    }
    let span = |i: &Value, which: &str| -> Vec<String> {
        i["volumes"]
            .as_array()
            .expect("volumes")
            .iter()
            .map(|v| v[which]["value"].as_str().expect("time").to_string())
            .collect()
    };
    let first_end = span(&ids[0], "time_end").into_iter().max().expect("an end");
    let owners = |v: &Value| -> Vec<String> {
        v["intents"]
            .as_array()
            .expect("intents")
            .iter()
            .map(|i| i["owner"].as_str().unwrap_or_default().to_string())
            .collect()
    };
    let get = |q: String| {
        let app = app.clone();
        async move { send(app, "GET", &format!("/api/intents{q}"), Value::Null).await }
    };
    let (status, all) = get(String::new()).await;
    matches_schema(&doc, "/api/intents", "get", status, &all);
    assert_eq!(owners(&all), ["early", "late"]);
    // Up to the first flight's end: only it (the second starts 20 minutes later).
    let (status, v) = get(format!("?time_end={first_end}")).await;
    assert_eq!(
        (status, owners(&v)),
        (StatusCode::OK, vec!["early".to_string()]),
        "{v}"
    );
    // From a second after it: only the second.
    let after = skyplan_airspace::Timestamp::from_unix_ms(
        first_end
            .parse::<skyplan_airspace::Timestamp>()
            .expect("time")
            .unix_ms()
            + 1000,
    );
    let (_, v) = get(format!("?time_start={after}")).await;
    assert_eq!(owners(&v), ["late"]);
    // Altitudes: the volumes are within 10 m of 5 m above home (at 0 m W84).
    let (_, v) = get("?altitude_lower=100".into()).await;
    assert!(owners(&v).is_empty(), "{v}");
    let (_, v) = get("?altitude_lower=-20&altitude_upper=0".into()).await;
    assert_eq!(owners(&v).len(), 2);
    // Area: a box around home holds both; one a few kilometres north neither.
    let (_, v) = get("?bbox=37.7920,-122.3980,37.7930,-122.3970".into()).await;
    assert_eq!(owners(&v).len(), 2, "{v}");
    let (_, v) = get("?bbox=37.85,-122.40,37.86,-122.39".into()).await;
    assert!(owners(&v).is_empty(), "{v}");
    // Area and time window together go through the store's index (or, over more index keys
    // than it takes, the whole list): the same answers, in the order stored.
    let whole_day = format!(
        "time_start={}&time_end={}",
        departure(-7200),
        departure(86_400)
    );
    let (_, v) = get(format!(
        "?bbox=37.7920,-122.3980,37.7930,-122.3970&{whole_day}"
    ))
    .await;
    assert_eq!(owners(&v), ["early", "late"], "{v}");
    let (_, v) = get(format!("?bbox=37.85,-122.40,37.86,-122.39&{whole_day}")).await;
    assert!(owners(&v).is_empty(), "{v}");
    let (_, v) = get(format!(
        "?bbox=37.7920,-122.3980,37.7930,-122.3970&time_start={after}&time_end={}",
        departure(86_400)
    ))
    .await;
    assert_eq!(owners(&v), ["late"], "{v}");
    let (status, v) = get(format!("?bbox=-80,-170,80,170&{whole_day}")).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert_eq!(owners(&v), ["early", "late"], "{v}");
    for (q, want) in [
        ("?bbox=1,2,3", "bbox: expected"),
        ("?bbox=37.9,-122.4,37.8,-122.3", "bbox: expected"),
        ("?time_start=soon", "time_start:"),
        ("?altitude_lower=50&altitude_upper=10", "altitude_upper:"),
        ("?colour=red", "colour"),
    ] {
        let (status, v) = get(q.to_string()).await;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{q}: {v}");
        matches_schema(&doc, "/api/intents", "get", status, &v);
        assert!(message(&v).contains(want), "{q}: {want:?} not in {v}");
    }
}

#[tokio::test]
async fn bad_intent_requests_get_400_naming_the_field_and_store_nothing() {
    let doc = document();
    let app = router(World::fcnd_city(), ServerConfig::default());
    let cases = [
        (
            intent_request(json!("2020-01-01T00:00:00Z"), 0, "o"),
            "departure: 2020-01-01T00:00:00Z is in the past",
        ),
        (
            intent_request(json!("2999-01-01T00:00:00Z"), 0, "o"),
            "beyond the horizon",
        ),
        (
            intent_request(json!("tomorrow"), 0, "o"),
            "departure: \"tomorrow\" is not an RFC 3339 date-time",
        ),
        (
            intent_request(
                json!({ "earliest": departure(60), "latest": departure(0) }),
                0,
                "o",
            ),
            "the window ends",
        ),
        (
            intent_request(json!({ "earliest": departure(0) }), 0, "o"),
            "departure.latest",
        ),
        (
            intent_request(json!(departure(0)), 101, "o"),
            "priority: 101 is above 100",
        ),
        (intent_request(json!(departure(0)), 0, "  "), "owner:"),
        (
            json!({ "departure": departure(0), "priority": 0, "owner": "o" }),
            "missing field `plan`",
        ),
        (
            json!({ "plan": { "alt_m": "high" }, "departure": departure(0), "priority": 0, "owner": "o" }),
            "plan.alt_m",
        ),
    ];
    for (body, want) in cases {
        let (status, v) = send(app.clone(), "POST", "/api/intents", body).await;
        assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
        matches_schema(&doc, "/api/intents", "post", status, &v);
        assert!(message(&v).contains(want), "{want:?} not in {v}");
    }
    // No route: 422, as for /api/plan.
    let no_route = json!({ "plan": { "goal_ne": [5000.0, 0.0] }, "departure": departure(0), "priority": 0, "owner": "o" });
    let (status, _) = send(app.clone(), "POST", "/api/intents", no_route).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    let (_, list) = send(app.clone(), "GET", "/api/intents", Value::Null).await;
    assert_eq!(list, json!({ "intents": [] }));
    // A map without a geodetic home has no latitude and longitude for intents.
    let grid = skyplan_cspace::Grid2::from_ascii("....\n....").expect("a grid");
    let tiny = router(World::from_grid("tiny", grid), ServerConfig::default());
    let body = json!({ "plan": { "start_ne": [0.5, 0.5], "goal_ne": [1.5, 3.5] }, "departure": departure(0), "priority": 0, "owner": "o" });
    let (status, v) = send(tiny, "POST", "/api/intents", body).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
    assert!(message(&v).contains("no geodetic home"), "{v}");
}

#[tokio::test]
async fn two_servers_on_one_sqlite_file_share_the_airspace_and_a_bad_store_is_503() {
    let doc = document();
    let dir = tempfile::tempdir().expect("a folder");
    let config = ServerConfig {
        airspace: format!("sqlite:{}", dir.path().join("airspace.db").display()),
        ..ServerConfig::default()
    };
    let one = router(World::fcnd_city(), config.clone());
    let two = router(World::fcnd_city(), config);
    let at = json!(departure(0));
    let (status, first) = send(
        one,
        "POST",
        "/api/intents",
        intent_request(at.clone(), 5, "one"),
    )
    .await;
    assert_eq!(status, StatusCode::CREATED, "{first}");
    let (status, refused) = send(
        two.clone(),
        "POST",
        "/api/intents",
        intent_request(at, 5, "two"),
    )
    .await;
    assert_eq!(status, StatusCode::CONFLICT, "{refused}");
    assert_eq!(refused["conflicts"][0]["id"], first["intent"]["id"]);
    let (_, list) = send(two, "GET", "/api/intents", Value::Null).await;
    assert_eq!(list["intents"], json!([first["intent"]]));
    // A store that cannot be opened: 503 store_unavailable, the rest of the API still serves.
    let broken = ServerConfig {
        airspace: "postgres://nowhere".into(),
        ..ServerConfig::default()
    };
    let app = router(World::fcnd_city(), broken);
    let (status, v) = send(app.clone(), "GET", "/api/intents", Value::Null).await;
    assert_eq!(
        (status, v["kind"].as_str()),
        (StatusCode::SERVICE_UNAVAILABLE, Some("store_unavailable")),
        "{v}"
    );
    matches_schema(&doc, "/api/intents", "get", status, &v);
    let (status, _) = send(app, "GET", "/api/planners", Value::Null).await;
    assert_eq!(status, StatusCode::OK);
}

/// An error answer's message ("" without one).
fn message(v: &Value) -> &str {
    v["message"].as_str().unwrap_or_default()
}
