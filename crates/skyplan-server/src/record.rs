//! [`Recorder`]: the view's events as an MCAP file with Foxglove's JSON schemas, for Foxglove and
//! Lichtblick (`fly --record FLIGHT.mcap`).
//!
//! | topic | schema | from |
//! |---|---|---|
//! | `/vehicle/location` | `foxglove.LocationFix` | flight events (maps with a geodetic home) |
//! | `/vehicle/pose` | `foxglove.PoseInFrame` (frame `map`: x east, y north, z up) | flight events |
//! | `/vehicle/state` | `skyplan.FlightState` (the [`FlightEvent`](crate::FlightEvent)) | flight events |
//! | `/route` | `foxglove.PosesInFrame` (the waypoints) | route events |
//! | `/plans` | `skyplan.Plan` (the [`PlanEvent`](crate::PlanEvent)) | plan events |
//! | `/sensed` | `skyplan.SensedPoints` | sensor readings |
//! | `/trajectory` | `skyplan.Trajectory` (the [`TrajectoryEvent`](crate::TrajectoryEvent): method, duration, columns, samples) | route events with a trajectory |

use crate::events::ViewEvent;
use serde_json::{Value, json};
use skyplan_frames::{LocalFrame, Ned};
use skyplan_plan::World;
use std::collections::BTreeMap;
use std::io::{Seek, Write};

/// Why a recording failed.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// Writing the MCAP file failed.
    #[error("MCAP recording: {0}")]
    Mcap(#[from] mcap::McapError),
    /// A message could not be encoded.
    #[error("MCAP recording: {0}")]
    Json(#[from] serde_json::Error),
}

/// Channel ids of the topics.
struct Channels {
    location: u16,
    pose: u16,
    state: u16,
    route: u16,
    plans: u16,
    sensed: u16,
    trajectory: u16,
}

/// Writes [`ViewEvent`]s to an MCAP file (uncompressed chunks, JSON messages).
///
/// ```
/// use skyplan_server::{FlightEvent, Recorder, ViewEvent};
/// let mut bytes = std::io::Cursor::new(Vec::new());
/// let mut rec = Recorder::new(&mut bytes, &skyplan_plan::World::fcnd_city())?;
/// rec.record(&ViewEvent::Flight(FlightEvent {
///     time_s: 0.5, north_m: 1.0, east_m: 2.0, alt_m: 3.0, heading_deg: 90.0, speed_m_s: 1.0,
///     state: "TAKEOFF".into(), waypoint_index: None, armed: true,
/// }), 0.5)?;
/// rec.finish()?;
/// assert_eq!(&bytes.get_ref()[1..5], b"MCAP");
/// # Ok::<(), skyplan_server::RecordError>(())
/// ```
pub struct Recorder<W: Write + Seek> {
    writer: mcap::Writer<W>,
    frame: Option<LocalFrame>,
    channels: Channels,
    sequence: u32,
}

fn time_schema() -> Value {
    json!({ "type": "object", "properties": {
        "sec": { "type": "integer", "minimum": 0 },
        "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 } } })
}

fn pose_schema() -> Value {
    let xyz = |names: &[&str]| {
        let props: serde_json::Map<String, Value> = names
            .iter()
            .map(|n| (n.to_string(), json!({ "type": "number" })))
            .collect();
        json!({ "type": "object", "properties": props })
    };
    json!({ "type": "object", "properties": {
        "position": xyz(&["x", "y", "z"]),
        "orientation": xyz(&["x", "y", "z", "w"]) } })
}

fn schemas() -> [(&'static str, Value); 5] {
    [
        (
            "foxglove.LocationFix",
            json!({ "title": "foxglove.LocationFix", "type": "object", "properties": {
                "timestamp": time_schema(),
                "frame_id": { "type": "string" },
                "latitude": { "type": "number" },
                "longitude": { "type": "number" },
                "altitude": { "type": "number" },
                "position_covariance": { "type": "array", "items": { "type": "number" }, "minItems": 9, "maxItems": 9 },
                "position_covariance_type": { "type": "integer", "enum": [0, 1, 2, 3] } } }),
        ),
        (
            "foxglove.PoseInFrame",
            json!({ "title": "foxglove.PoseInFrame", "type": "object", "properties": {
                "timestamp": time_schema(), "frame_id": { "type": "string" }, "pose": pose_schema() } }),
        ),
        (
            "skyplan.FlightState",
            json!({ "title": "skyplan.FlightState", "type": "object", "properties": {
                "time_s": { "type": "number" }, "north_m": { "type": "number" },
                "east_m": { "type": "number" }, "alt_m": { "type": "number" },
                "heading_deg": { "type": "number" }, "speed_m_s": { "type": "number" },
                "state": { "type": "string" }, "waypoint_index": { "type": "integer" },
                "armed": { "type": "boolean" } } }),
        ),
        (
            "foxglove.PosesInFrame",
            json!({ "title": "foxglove.PosesInFrame", "type": "object", "properties": {
                "timestamp": time_schema(), "frame_id": { "type": "string" },
                "poses": { "type": "array", "items": pose_schema() } } }),
        ),
        (
            "skyplan.Plan",
            json!({ "title": "skyplan.Plan", "type": "object", "properties": {
                "request_id": { "type": "integer" }, "planner": { "type": "string" },
                "status": { "type": "string" }, "message": { "type": "string" },
                "cost_m": { "type": "number" },
                "waypoints": { "type": "array", "items": { "type": "array", "items": { "type": "number" } } },
                "wall_time_us": { "type": "integer" } } }),
        ),
    ]
}

fn stamp(time_s: f64) -> (u64, Value) {
    let ns = if time_s.is_finite() && time_s > 0.0 {
        (time_s * 1e9).round() as u64
    } else {
        0
    };
    (
        ns,
        json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 }),
    )
}

/// A pose in the `map` frame (x east, y north, z up) with the yaw of a heading (degrees
/// clockwise from north).
fn pose(north_m: f64, east_m: f64, alt_m: f64, heading_deg: f64) -> Value {
    let yaw = (90.0 - heading_deg).to_radians();
    json!({
        "position": { "x": east_m, "y": north_m, "z": alt_m },
        "orientation": { "x": 0.0, "y": 0.0, "z": (yaw / 2.0).sin(), "w": (yaw / 2.0).cos() },
    })
}

impl<W: Write + Seek> Recorder<W> {
    /// Starts a recording of flights over `world` (its home gives `/vehicle/location`).
    pub fn new(writer: W, world: &World) -> Result<Self, RecordError> {
        let mut writer = mcap::WriteOptions::new()
            .profile("")
            .library("skyplan")
            .create(writer)?;
        let mut ids = Vec::new();
        let topics = [
            "/vehicle/location",
            "/vehicle/pose",
            "/vehicle/state",
            "/route",
            "/plans",
        ];
        for ((name, schema), topic) in schemas().into_iter().zip(topics) {
            let schema_id = writer.add_schema(name, "jsonschema", &serde_json::to_vec(&schema)?)?;
            ids.push(writer.add_channel(schema_id, topic, "json", &BTreeMap::new())?);
        }
        // The sensed obstacle points: skyplan's own small schema (the SensedEvent as JSON).
        let sensed_schema = json!({
            "title": "skyplan.SensedPoints",
            "type": "object",
            "properties": {
                "time_s": { "type": "number" },
                "vehicle_ne": { "type": "array", "items": { "type": "number" } },
                "alt_m": { "type": "number" },
                "hits_ne": { "type": "array", "items": { "type": "array", "items": { "type": "number" } } },
            },
        });
        let sensed_id = writer.add_schema(
            "skyplan.SensedPoints",
            "jsonschema",
            &serde_json::to_vec(&sensed_schema)?,
        )?;
        let sensed = writer.add_channel(sensed_id, "/sensed", "json", &BTreeMap::new())?;
        let trajectory_schema = json!({
            "title": "skyplan.Trajectory",
            "type": "object",
            "properties": {
                "method": { "type": "string" },
                "duration_s": { "type": "number" },
                "columns": { "type": "array", "items": { "type": "string" } },
                "samples": { "type": "array", "items": { "type": "array", "items": { "type": "number" } } },
            },
        });
        let trajectory_id = writer.add_schema(
            "skyplan.Trajectory",
            "jsonschema",
            &serde_json::to_vec(&trajectory_schema)?,
        )?;
        let trajectory =
            writer.add_channel(trajectory_id, "/trajectory", "json", &BTreeMap::new())?;
        let channels = Channels {
            location: ids[0],
            pose: ids[1],
            state: ids[2],
            route: ids[3],
            plans: ids[4],
            sensed,
            trajectory,
        };
        Ok(Self {
            writer,
            frame: world.frame().copied(),
            channels,
            sequence: 0,
        })
    }

    fn write(
        &mut self,
        channel_id: u16,
        log_time: u64,
        message: &Value,
    ) -> Result<(), RecordError> {
        self.sequence = self.sequence.wrapping_add(1);
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time,
            publish_time: log_time,
        };
        self.writer
            .write_to_known_channel(&header, &serde_json::to_vec(message)?)?;
        Ok(())
    }

    /// Records `event` at `log_time_s` (seconds since the recording began; flight events use
    /// their own `time_s`).
    pub fn record(&mut self, event: &ViewEvent, log_time_s: f64) -> Result<(), RecordError> {
        match event {
            ViewEvent::Flight(f) => {
                let (ns, timestamp) = stamp(f.time_s);
                if let Some(frame) = self.frame {
                    let ned = Ned {
                        north_m: f.north_m,
                        east_m: f.east_m,
                        down_m: -f.alt_m,
                    };
                    // A position the frame cannot express (far off the map) has no fix.
                    if let Ok(lla) = frame.lla_from_ned(ned) {
                        let unknown_covariance = [0.0f64; 9];
                        let fix = json!({
                            "timestamp": timestamp, "frame_id": "map",
                            "latitude": lla.lat_deg, "longitude": lla.lon_deg, "altitude": lla.alt_m,
                            "position_covariance": unknown_covariance, "position_covariance_type": 0,
                        });
                        self.write(self.channels.location, ns, &fix)?;
                    }
                }
                let p = json!({ "timestamp": timestamp, "frame_id": "map",
                    "pose": pose(f.north_m, f.east_m, f.alt_m, f.heading_deg) });
                self.write(self.channels.pose, ns, &p)?;
                let state = serde_json::to_value(f)?;
                self.write(self.channels.state, ns, &state)?;
            }
            ViewEvent::Route(r) => {
                let (ns, timestamp) = stamp(log_time_s);
                let poses: Vec<Value> = r
                    .waypoints
                    .iter()
                    .map(|w| pose(w[0], w[1], w[2], 0.0))
                    .collect();
                let m = json!({ "timestamp": timestamp, "frame_id": "map", "poses": poses });
                self.write(self.channels.route, ns, &m)?;
                if let Some(t) = &r.trajectory {
                    let m = serde_json::to_value(t)?;
                    self.write(self.channels.trajectory, ns, &m)?;
                }
            }
            ViewEvent::Sensed(e) => {
                let (ns, _) = stamp(e.time_s);
                let m = serde_json::to_value(e)?;
                self.write(self.channels.sensed, ns, &m)?;
            }
            ViewEvent::Plan(p) => {
                let (ns, _) = stamp(log_time_s);
                let m = serde_json::to_value(p)?;
                self.write(self.channels.plans, ns, &m)?;
            }
            // The shared airspace is the server's, not a flight's: not recorded.
            ViewEvent::Intent(_) => {}
        }
        Ok(())
    }

    /// Writes the summary and ends the file.
    pub fn finish(mut self) -> Result<(), RecordError> {
        self.writer.finish()?;
        Ok(())
    }
}
