//! Missions: a list read from JSON or TOML text (every field checked, errors naming the
//! entry and the field), or drawn at random on a map's grid.

use crate::flight::{DEPARTURE_STEP_MS, FieldError, HORIZON_MS, check_window, departure_window};
use rand::{RngExt, SeedableRng};
use serde::Serialize;
use serde_json::{Map, Value};
use skyplan_airspace::{DepartureWindow, MAX_PRIORITY, Timestamp};
use skyplan_cspace::Grid2;
use skyplan_search::MoveModel;
use std::collections::HashSet;

/// How much later than its departure a mission may leave when the file does not say
/// (`window_s`), seconds.
pub const DEFAULT_WINDOW_S: f64 = 900.0;

/// Longest window a mission may give, seconds (one day).
pub const MAX_WINDOW_S: f64 = 86_400.0;

/// Longest id or owner, characters.
pub const MAX_NAME_CHARS: usize = 200;

/// Where a mission starts or ends.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Place {
    /// `[north_m, east_m]` about the map's home.
    Ne([f64; 2]),
    /// `[lat_deg, lon_deg]`.
    Lla([f64; 2]),
}

/// One flight to plan and reserve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mission {
    /// Its name in the report (unique in a list).
    pub id: String,
    /// Where it starts.
    pub start: Place,
    /// Where it ends.
    pub goal: Place,
    /// Its flight altitude above home, metres (default: the run's).
    pub alt_m: Option<f64>,
    /// When it may leave.
    pub window: DepartureWindow,
    /// Its priority, 0 to 100 (higher is more important).
    pub priority: u32,
    /// Who flies it.
    pub owner: String,
}

impl Mission {
    /// `base` with this mission's start, goal and altitude.
    pub fn request(&self, base: &skyplan_plan::PlanRequest) -> skyplan_plan::PlanRequest {
        let mut r = base.clone();
        (r.start_ne, r.start_lla, r.goal_ne, r.goal_lla) = (None, None, None, None);
        match self.start {
            Place::Ne(p) => r.start_ne = Some(p),
            Place::Lla(p) => r.start_lla = Some(p),
        }
        match self.goal {
            Place::Ne(p) => r.goal_ne = Some(p),
            Place::Lla(p) => r.goal_lla = Some(p),
        }
        if self.alt_m.is_some() {
            r.alt_m = self.alt_m;
        }
        r
    }
}

/// A mission file's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// `[{…}, …]` or `{"missions": [{…}, …]}`.
    Json,
    /// `[[missions]]` tables.
    Toml,
}

impl Format {
    /// By the file name's extension (`.json`, `.toml`).
    pub fn of_name(name: &str) -> Option<Self> {
        let lower = name.to_ascii_lowercase();
        if lower.ends_with(".json") {
            Some(Self::Json)
        } else if lower.ends_with(".toml") {
            Some(Self::Toml)
        } else {
            None
        }
    }
}

/// Why a mission list was refused: the file, the entry (when one is to blame) and the field.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}: {}{why}", entry.as_ref().map(|e| format!("{e}: ")).unwrap_or_default())]
pub struct MissionsError {
    /// The file's name.
    pub file: String,
    /// `missions[3] (id "m4").goal_ne`, or none for the file as a whole.
    pub entry: Option<String>,
    /// What is wrong.
    pub why: String,
}

/// Where the missions' times are anchored: departures written as numbers are seconds after
/// `start`; written times are checked against `now`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Clock {
    /// What a numeric departure counts from.
    pub start: Timestamp,
    /// The present, for the past and horizon checks.
    pub now: Timestamp,
}

const FIELDS: &str =
    "id, start_ne | start_lla, goal_ne | goal_lla, alt_m, departure, window_s, priority, owner";

/// The missions of `text` (a file called `name`).
///
/// A mission: `id` (text, default `m1`, `m2`, … by position; unique), `start_ne` `[north_m,
/// east_m]` or `start_lla` `[lat, lon]`, `goal_ne` or `goal_lla` likewise, `alt_m` (optional),
/// `departure` — seconds after the run's start (a number ≥ 0, default 0), an RFC 3339 time
/// (quoted in TOML), or `{"earliest": …, "latest": …}` — `window_s` (how much later than a
/// number or time departure it may leave, default [`DEFAULT_WINDOW_S`]; not with the object
/// form), `priority` (0 to 100, default 0), `owner` (text, default `fleet`).
///
/// ```
/// use skyplan_fleet::{Clock, Format, parse_missions};
/// let t: skyplan_airspace::Timestamp = "2026-03-01T12:00:00Z".parse()?;
/// let clock = Clock { start: t, now: t };
/// let text = r#"[[missions]]
/// start_ne = [100.0, 100.0]
/// goal_ne = [700.0, 600.0]
/// departure = 60
/// "#;
/// let m = parse_missions("fleet.toml", text, Format::Toml, clock)?;
/// assert_eq!((m[0].id.as_str(), m[0].window.earliest.ms_since(t)), ("m1", 60_000));
/// let bad = parse_missions("fleet.json", r#"[{"start_ne": [1, 2], "goal_ne": [3]}]"#, Format::Json, clock).unwrap_err();
/// assert_eq!(bad.to_string(), "fleet.json: missions[0] (id \"m1\").goal_ne: expected [north_m, east_m], two numbers");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parse_missions(
    name: &str,
    text: &str,
    format: Format,
    clock: Clock,
) -> Result<Vec<Mission>, MissionsError> {
    let whole = |why: String| MissionsError {
        file: name.into(),
        entry: None,
        why,
    };
    let root: Value = match format {
        Format::Json => serde_json::from_str(text).map_err(|e| whole(format!("not JSON: {e}")))?,
        Format::Toml => {
            let table: toml::Table = text
                .parse()
                .map_err(|e: toml::de::Error| whole(format!("not TOML: {}", e.message())))?;
            toml_to_json(toml::Value::Table(table))
        }
    };
    let list = match &root {
        Value::Array(list) => list,
        Value::Object(o) => match (o.get("missions"), o.keys().find(|k| *k != "missions")) {
            (_, Some(k)) => {
                return Err(whole(format!(
                    "unknown top-level field \"{k}\": expected only missions"
                )));
            }
            (Some(Value::Array(list)), None) => list,
            _ => return Err(whole("expected a list of missions under `missions`".into())),
        },
        _ => return Err(whole("expected a list of missions".into())),
    };
    if list.is_empty() {
        return Err(whole("no missions".into()));
    }
    let mut seen = HashSet::new();
    let mut out = Vec::with_capacity(list.len());
    for (k, v) in list.iter().enumerate() {
        let default_id = format!("m{}", k + 1);
        let id = v
            .get("id")
            .and_then(Value::as_str)
            .map_or(default_id, str::to_string);
        let blame = |e: FieldError| MissionsError {
            file: name.into(),
            entry: Some(format!("missions[{k}] (id \"{id}\").{}", e.field)),
            why: e.why,
        };
        let mission = mission(k, v, clock).map_err(blame)?;
        if !seen.insert(mission.id.clone()) {
            return Err(blame(FieldError {
                field: "id".into(),
                why: format!("\"{}\" is used by an earlier mission", mission.id),
            }));
        }
        out.push(mission);
    }
    Ok(out)
}

fn err(field: &str, why: impl Into<String>) -> FieldError {
    FieldError {
        field: field.into(),
        why: why.into(),
    }
}

fn text_field(o: &Map<String, Value>, field: &str, default: &str) -> Result<String, FieldError> {
    match o.get(field) {
        None => Ok(default.into()),
        Some(Value::String(s)) => {
            let s = s.trim();
            if s.is_empty() || s.chars().count() > MAX_NAME_CHARS {
                Err(err(
                    field,
                    format!("expected 1 to {MAX_NAME_CHARS} characters"),
                ))
            } else {
                Ok(s.into())
            }
        }
        Some(_) => Err(err(field, "expected text")),
    }
}

fn number(v: &Value, field: &str, lo: f64, hi: f64) -> Result<f64, FieldError> {
    match v.as_f64() {
        Some(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
        _ => Err(err(field, format!("expected a number from {lo} to {hi}"))),
    }
}

fn place(o: &Map<String, Value>, which: &str) -> Result<Place, FieldError> {
    let (ne, lla) = (format!("{which}_ne"), format!("{which}_lla"));
    let pair = |field: &str, v: &Value, what: &str| -> Result<[f64; 2], FieldError> {
        let bad = || err(field, format!("expected [{what}], two numbers"));
        let list = v.as_array().filter(|l| l.len() == 2).ok_or_else(bad)?;
        let a = list[0].as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
        let b = list[1].as_f64().filter(|x| x.is_finite()).ok_or_else(bad)?;
        Ok([a, b])
    };
    match (o.get(&ne), o.get(&lla)) {
        (Some(_), Some(_)) => Err(err(&ne, format!("give {ne} or {lla}, not both"))),
        (Some(v), None) => Ok(Place::Ne(pair(&ne, v, "north_m, east_m")?)),
        (None, Some(v)) => {
            let [lat, lon] = pair(&lla, v, "lat_deg, lon_deg")?;
            if !(-90.0..=90.0).contains(&lat) || !(-180.0..=180.0).contains(&lon) {
                return Err(err(
                    &lla,
                    "expected a latitude within ±90 and a longitude within ±180",
                ));
            }
            Ok(Place::Lla([lat, lon]))
        }
        (None, None) => Err(err(&ne, format!("missing: give {ne} or {lla}"))),
    }
}

fn mission(k: usize, v: &Value, clock: Clock) -> Result<Mission, FieldError> {
    let o = v
        .as_object()
        .ok_or_else(|| err("", format!("expected a table or object with {FIELDS}")))?;
    let known = [
        "id",
        "start_ne",
        "start_lla",
        "goal_ne",
        "goal_lla",
        "alt_m",
        "departure",
        "window_s",
        "priority",
        "owner",
    ];
    if let Some(key) = o.keys().find(|key| !known.contains(&key.as_str())) {
        return Err(err(key, format!("unknown field, expected {FIELDS}")));
    }
    let id = text_field(o, "id", &format!("m{}", k + 1))?;
    let start = place(o, "start")?;
    let goal = place(o, "goal")?;
    let alt_m = o
        .get("alt_m")
        .map(|v| number(v, "alt_m", 0.0, skyplan_plan::MAX_ALT_M))
        .transpose()?;
    let window_s = o
        .get("window_s")
        .map(|v| number(v, "window_s", 0.0, MAX_WINDOW_S))
        .transpose()?;
    let ms = |s: f64| (s * 1000.0).round() as i64;
    let window = match o.get("departure") {
        Some(v @ Value::Object(_)) => {
            if window_s.is_some() {
                return Err(err(
                    "window_s",
                    "not with a departure window {earliest, latest}: the window says it",
                ));
            }
            departure_window(v, "departure", clock.now)?
        }
        Some(v @ Value::String(_)) => {
            let at = departure_window(v, "departure", clock.now)?.earliest;
            let latest = at.plus_ms(ms(window_s.unwrap_or(DEFAULT_WINDOW_S)));
            let w = DepartureWindow {
                earliest: at,
                latest,
            };
            check_window(w, "departure", clock.now)?;
            w
        }
        None | Some(Value::Number(_)) => {
            let after_s = o
                .get("departure")
                .map(|v| number(v, "departure", 0.0, HORIZON_MS as f64 / 1000.0))
                .transpose()?
                .unwrap_or(0.0);
            let earliest = clock.start.plus_ms(ms(after_s));
            let w = DepartureWindow {
                earliest,
                latest: earliest.plus_ms(ms(window_s.unwrap_or(DEFAULT_WINDOW_S))),
            };
            check_window(w, "departure", clock.now)?;
            w
        }
        Some(_) => {
            return Err(err(
                "departure",
                "expected seconds after the start, an RFC 3339 time or {earliest, latest}",
            ));
        }
    };
    let priority = match o.get("priority") {
        None => 0,
        Some(v) => v
            .as_u64()
            .filter(|&p| p <= u64::from(MAX_PRIORITY))
            .and_then(|p| u32::try_from(p).ok())
            .ok_or_else(|| {
                err(
                    "priority",
                    format!("expected a whole number from 0 to {MAX_PRIORITY}"),
                )
            })?,
    };
    let owner = text_field(o, "owner", "fleet")?;
    Ok(Mission {
        id,
        start,
        goal,
        alt_m,
        window,
        priority,
        owner,
    })
}

/// TOML as JSON (dates and times as their RFC 3339 text).
fn toml_to_json(v: toml::Value) -> Value {
    match v {
        toml::Value::String(s) => Value::String(s),
        toml::Value::Integer(i) => Value::from(i),
        toml::Value::Float(f) => serde_json::Number::from_f64(f).map_or(Value::Null, Value::Number),
        toml::Value::Boolean(b) => Value::Bool(b),
        toml::Value::Datetime(d) => Value::String(d.to_string()),
        toml::Value::Array(a) => Value::Array(a.into_iter().map(toml_to_json).collect()),
        toml::Value::Table(t) => {
            Value::Object(t.into_iter().map(|(k, v)| (k, toml_to_json(v))).collect())
        }
    }
}

/// How random missions are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RandomMissions {
    /// How many.
    pub count: usize,
    /// Their seed.
    pub seed: u64,
    /// Least start–goal distance, metres.
    pub min_distance_m: f64,
    /// Departures are spread uniformly over this many seconds after the start (whole seconds).
    pub spread_s: f64,
    /// How much later than its departure each may leave, seconds.
    pub window_s: f64,
    /// The start of the run.
    pub start: Timestamp,
}

/// `r.count` reproducible missions between free cells of the grid's largest connected region
/// (cell centres, at least `min_distance_m` apart), priority 0, owner `fleet`, ids `r1`, `r2`, ….
pub fn random_missions(grid: &Grid2, model: MoveModel, r: &RandomMissions) -> Vec<Mission> {
    let cells = skyplan_bench::random_far_queries(
        grid,
        model,
        r.count,
        r.seed,
        r.min_distance_m / grid.frame().cell_m.max(1e-9),
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(r.seed ^ 0x5eed_f1ee7);
    let step_s = DEPARTURE_STEP_MS as f64 / 1000.0;
    let slots = (r.spread_s / step_s).floor().max(0.0) as u64;
    cells
        .into_iter()
        .enumerate()
        .map(|(k, (a, b))| {
            let (an, ae) = grid.center_ne(a);
            let (bn, be) = grid.center_ne(b);
            let slot = rng.random_range(0..=slots);
            let earliest = r.start.plus_ms(slot as i64 * DEPARTURE_STEP_MS);
            Mission {
                id: format!("r{}", k + 1),
                start: Place::Ne([an, ae]),
                goal: Place::Ne([bn, be]),
                alt_m: None,
                window: DepartureWindow {
                    earliest,
                    latest: earliest.plus_ms((r.window_s * 1000.0).round() as i64),
                },
                priority: 0,
                owner: "fleet".into(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clock() -> Clock {
        let t: Timestamp = "2026-03-01T12:00:00Z"
            .parse()
            .unwrap_or_else(|e| panic!("{e}"));
        Clock { start: t, now: t }
    }

    fn one(fields: &str) -> Result<Mission, MissionsError> {
        let text = format!(r#"[{{"start_ne": [0, 0], "goal_lla": [37.79, -122.39]{fields}}}]"#);
        parse_missions("m.json", &text, Format::Json, clock()).map(|mut m| m.remove(0))
    }

    #[test]
    fn each_departure_form_gives_its_window() {
        let t = clock().start;
        let m = one("").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.window.earliest, t);
        assert_eq!(m.window.latest.ms_since(t), 900_000);
        assert_eq!(m.goal, Place::Lla([37.79, -122.39]));
        let m = one(r#", "departure": 90.5, "window_s": 0"#).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (m.window.earliest.ms_since(t), m.window.latest.ms_since(t)),
            (90_500, 90_500)
        );
        let m = one(r#", "departure": "2026-03-01T13:00:00Z", "window_s": 60"#)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.window.earliest.ms_since(t), 3_600_000);
        assert_eq!(m.window.latest.ms_since(t), 3_660_000);
        let m = one(
            r#", "departure": {"earliest": "2026-03-01T12:10:00Z", "latest": "2026-03-01T12:20:00Z"}"#,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.window.latest.ms_since(m.window.earliest), 600_000);
    }

    #[test]
    fn contradictions_and_ranges_are_refused_naming_the_field() {
        let cases = [
            (
                r#", "departure": {"earliest": "2026-03-01T12:10:00Z", "latest": "2026-03-01T12:20:00Z"}, "window_s": 5"#,
                "window_s: not with a departure window",
            ),
            (
                r#", "departure": {"earliest": "2026-03-01T12:20:00Z", "latest": "2026-03-01T12:10:00Z"}"#,
                "departure: the window ends (2026-03-01T12:10:00Z) before it starts",
            ),
            (
                r#", "departure": -1"#,
                "departure: expected a number from 0",
            ),
            (
                r#", "departure": 3000000"#,
                "departure: expected a number from 0",
            ),
            (
                r#", "window_s": 90000"#,
                "window_s: expected a number from 0 to 86400",
            ),
            (
                r#", "start_lla": [1, 2]"#,
                "start_ne: give start_ne or start_lla, not both",
            ),
            (r#", "priority": 1.5"#, "priority: expected a whole number"),
            (r#", "owner": "  ""#, "owner: expected 1 to 200 characters"),
            (r#", "alt_m": "high""#, "alt_m: expected a number"),
        ];
        for (fields, want) in cases {
            let e = one(fields).err().map(|e| e.to_string()).unwrap_or_default();
            let want = format!("m.json: missions[0] (id \"m1\").{want}");
            assert!(
                e.starts_with(&want),
                "{fields}: {e:?} does not start with {want:?}"
            );
        }
    }

    #[test]
    fn random_missions_are_reproducible_and_far_apart() {
        let grid = Grid2::from_ascii(&format!("{}\n", ".".repeat(400)).repeat(3))
            .unwrap_or_else(|e| panic!("{e}"));
        let r = RandomMissions {
            count: 20,
            seed: 3,
            min_distance_m: 200.0,
            spread_s: 600.0,
            window_s: 60.0,
            start: clock().start,
        };
        let a = random_missions(&grid, MoveModel::default(), &r);
        assert_eq!(a, random_missions(&grid, MoveModel::default(), &r));
        assert_eq!(a.len(), 20);
        for m in &a {
            let (Place::Ne(s), Place::Ne(g)) = (m.start, m.goal) else {
                panic!("random missions are in metres")
            };
            assert!((s[0] - g[0]).hypot(s[1] - g[1]) >= 200.0);
            let after = m.window.earliest.ms_since(r.start);
            assert!((0..=600_000).contains(&after) && after % 1000 == 0);
            assert_eq!(m.window.latest.ms_since(m.window.earliest), 60_000);
        }
    }
}
