//! [`ViewEvent`]: what `GET /api/events` streams (plan results, and the vehicle's state and
//! routes from `fly --view` / `sim --view`), and [`EventSink`], the handle that publishes them
//! from any thread.

use serde::Serialize;
use std::sync::{Arc, Mutex};
use tokio::sync::broadcast;

/// One event of the stream. In the server-sent-events stream the SSE event name is `type`
/// (`plan`, `flight`, `route`, `sensed`) and the data is this object as JSON.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ViewEvent {
    /// A plan answered by `POST /api/plan` (made or failed).
    Plan(PlanEvent),
    /// The vehicle's state (`fly --view`, `sim --view`), published at ≥ 5 Hz.
    Flight(FlightEvent),
    /// The route the vehicle flies: the first plan and every replan.
    Route(RouteEvent),
    /// What the vehicle's obstacle sensor saw last (`OBSTACLE_DISTANCE`).
    Sensed(SensedEvent),
    /// An operational intent accepted or deleted (`POST`/`DELETE /api/intents`).
    Intent(IntentEvent),
}

impl ViewEvent {
    /// The SSE event name (`plan`, `flight`, `route`, `sensed`).
    pub fn name(&self) -> &'static str {
        match self {
            ViewEvent::Plan(_) => "plan",
            ViewEvent::Flight(_) => "flight",
            ViewEvent::Route(_) => "route",
            ViewEvent::Sensed(_) => "sensed",
            ViewEvent::Intent(_) => "intent",
        }
    }
}

/// A plan result, as `POST /api/plan` answered it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanEvent {
    /// Increasing number of the request in this server.
    pub request_id: u64,
    /// The planner (CLI spelling).
    pub planner: String,
    /// `ok`, or the failure's kind (`no_path`, `invalid_goal`, …).
    pub status: String,
    /// The failure's message (failures only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    /// The route's length, metres (made plans only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cost_m: Option<f64>,
    /// Waypoints `[north_m, east_m, alt_m]` (empty for failures).
    pub waypoints: Vec<[f64; 3]>,
    /// Wall time of the request in the server, microseconds.
    pub wall_time_us: u64,
}

/// The vehicle's state at one instant.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlightEvent {
    /// Seconds since the flight began.
    pub time_s: f64,
    /// Metres north of the map's origin.
    pub north_m: f64,
    /// Metres east of the map's origin.
    pub east_m: f64,
    /// Altitude above home, metres.
    pub alt_m: f64,
    /// Heading, degrees clockwise from north.
    pub heading_deg: f64,
    /// Ground speed, metres per second.
    pub speed_m_s: f64,
    /// The flight state machine's state (`MANUAL`, `ARMING`, `TAKEOFF`, `WAYPOINT`, `LANDING`,
    /// `DISARMING`, …).
    pub state: String,
    /// Index of the waypoint being flown to, when flying a route.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub waypoint_index: Option<usize>,
    /// Whether the motors are armed.
    pub armed: bool,
}

/// A route being flown.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RouteEvent {
    /// Why this route: `plan` for the first, `replan: …` for later ones.
    pub reason: String,
    /// The planner (CLI spelling).
    pub planner: String,
    /// Waypoints `[north_m, east_m, alt_m]`.
    pub waypoints: Vec<[f64; 3]>,
    /// The route's trajectory (flights with `--trajectory`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trajectory: Option<TrajectoryEvent>,
}

/// A trajectory's samples, as `plan --json` gives them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrajectoryEvent {
    /// How it was made: `minimum_jerk` or `stop_at_waypoints`.
    pub method: &'static str,
    /// Total duration, seconds.
    pub duration_s: f64,
    /// The samples' columns (`t_s`, `north_m`, … `yaw_deg`).
    pub columns: [&'static str; 11],
    /// The samples, one row per instant.
    pub samples: Vec<[f64; 11]>,
}

impl TrajectoryEvent {
    /// The event of a plan's trajectory, if it has one.
    pub fn of(plan: &skyplan_plan::Plan) -> Option<Self> {
        plan.trajectory.as_ref().map(|t| TrajectoryEvent {
            method: t.trajectory.method.name(),
            duration_s: t.duration_s,
            columns: t.columns,
            samples: t.samples.clone(),
        })
    }
}

/// An operational intent that changed in the shared airspace: clients re-read
/// `GET /api/intents` (the page draws the others' intents on a time slider).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IntentEvent {
    /// `accepted` or `deleted`.
    pub action: &'static str,
    /// The intent's id.
    pub id: String,
    /// Its version.
    pub version: u64,
    /// Who flies it.
    pub owner: String,
    /// Its priority.
    pub priority: u32,
    /// When its first volume starts and its last ends (RFC 3339).
    pub time_start: Option<String>,
    /// See `time_start`.
    pub time_end: Option<String>,
}

impl IntentEvent {
    /// The event for `intent` and `action`.
    pub fn of(action: &'static str, intent: &skyplan_airspace::OperationalIntent) -> Self {
        let bounds = intent.time_bounds();
        Self {
            action,
            id: intent.id.clone(),
            version: intent.version,
            owner: intent.owner.clone(),
            priority: intent.priority,
            time_start: bounds.map(|b| b.0.to_string()),
            time_end: bounds.map(|b| b.1.to_string()),
        }
    }
}

/// One sweep of the vehicle's obstacle sensor: where it was, and where it saw obstacles.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensedEvent {
    /// Seconds since the flight (or the simulator) began.
    pub time_s: f64,
    /// The vehicle then: metres north and east of the map's origin.
    pub vehicle_ne: [f64; 2],
    /// Altitude above home then, metres (the sweep is horizontal, at this altitude).
    pub alt_m: f64,
    /// The points where the sensor saw an obstacle: `[north_m, east_m]`.
    pub hits_ne: Vec<[f64; 2]>,
}

/// An event serialised once for every subscriber.
#[derive(Debug, Clone)]
pub(crate) struct Encoded {
    pub name: &'static str,
    pub json: String,
}

/// Publishes [`ViewEvent`]s to every connected `/api/events` client. Cheap to clone; callable
/// from any thread, async or not. Events published with no client connected are dropped.
///
/// The latest `route` and `flight` events are kept and sent first to clients that connect
/// later, so a page opened mid-flight shows the route and the vehicle at once.
#[derive(Debug, Clone)]
pub struct EventSink {
    pub(crate) tx: broadcast::Sender<Arc<Encoded>>,
    retained: Arc<Mutex<Vec<Arc<Encoded>>>>,
}

/// How many events a slow client may fall behind before it skips some.
const EVENT_BUFFER: usize = 256;

impl EventSink {
    pub(crate) fn new() -> Self {
        let (tx, _) = broadcast::channel(EVENT_BUFFER);
        Self {
            tx,
            retained: Arc::new(Mutex::new(Vec::new())),
        }
    }

    /// A new client's receiver, and the retained events to send it first.
    pub(crate) fn subscribe(&self) -> (broadcast::Receiver<Arc<Encoded>>, Vec<Arc<Encoded>>) {
        let retained = self.lock_retained();
        (self.tx.subscribe(), retained.clone())
    }

    fn lock_retained(&self) -> std::sync::MutexGuard<'_, Vec<Arc<Encoded>>> {
        // Only whole values are stored under the lock: a poisoned one is still consistent.
        self.retained.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Sends `event` to every connected client (none: dropped).
    pub fn publish(&self, event: &ViewEvent) {
        // Serialising plain numbers and strings cannot fail; a failure would drop one event.
        if let Ok(json) = serde_json::to_string(event) {
            let encoded = Arc::new(Encoded {
                name: event.name(),
                json,
            });
            if !matches!(event, ViewEvent::Plan(_)) {
                // Under the lock, so that a client subscribing now gets it once or retained.
                let mut retained = self.lock_retained();
                retained.retain(|e| e.name != encoded.name);
                retained.push(Arc::clone(&encoded));
                let _ = self.tx.send(encoded);
                return;
            }
            // An error only means nobody is listening.
            let _ = self.tx.send(encoded);
        }
    }

    /// How many event-stream clients are connected now.
    pub fn clients(&self) -> usize {
        self.tx.receiver_count()
    }
}
