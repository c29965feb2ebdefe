//! [`PlanRequest`]: what to plan, as plain serialisable options. Its keys are the CLI's long
//! options with underscores (the TOML config, the HTTP API and the Python keywords use the same
//! names); every field is optional and has a documented default.

#[cfg(feature = "clap")]
use crate::cli;
use crate::failure::{FailureKind, PlanFailure};
use crate::navfn::CostmapOptions;
use crate::plan::PlanSpec;
use crate::planner_id::{OptionGroup, PlannerId};
use serde::{Deserialize, Serialize};
use skyplan_trajectory::Limits as TrajectoryLimits;
use std::time::Duration;

/// Collinearity pruning of grid paths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum PruneMode {
    /// Exact integer collinearity on grid cells.
    Collinear,
    /// Keep every cell of the grid path.
    None,
}

/// What the wavefront's distance field counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum FieldMode {
    /// Path length (octile Dijkstra; descends along shortest grid paths).
    Length,
    /// Number of moves (breadth-first wavefront).
    Steps,
}

/// A saved PRM roadmap to start from, and whether to return the roadmap for saving.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RoadmapIo {
    /// The bytes of a roadmap saved earlier (`Plan::saved_roadmap`), with a name for messages.
    pub load: Option<(String, Vec<u8>)>,
    /// Return the roadmap in `Plan::saved_roadmap`.
    pub save: bool,
}

/// One planning request. Every field is optional; `None` takes the default in brackets.
///
/// With the `clap` feature the request is also the command line's route options (each key as
/// `--key-with-dashes`, its doc as the help; `shortcut` as `--no-shortcut`; `geometry` and
/// `roadmap` are not options), so the CLI, the TOML config, the HTTP API and the Python keywords
/// share one definition.
///
/// ```
/// use skyplan_plan::{PlanRequest, PlannerId};
/// let r: PlanRequest = serde_json::from_str(
///     r#"{"planner": "jps-plus", "goal_ne": [420, 390], "alt_m": 10}"#).unwrap();
/// assert_eq!(r.planner, Some(PlannerId::JpsPlus));
/// assert!(serde_json::from_str::<PlanRequest>(r#"{"safty_m": 3}"#).is_err()); // typos are refused
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields, default)]
pub struct PlanRequest {
    /// The planner [default: jps].
    #[serde(alias = "method")]
    #[cfg_attr(feature = "clap", arg(long, value_name = "PLANNER"))]
    pub planner: Option<PlannerId>,
    /// Flight altitude above home, metres [default: 5].
    #[serde(alias = "target_altitude")]
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true))]
    pub alt_m: Option<f64>,
    /// Over terrain (a map given a DEM, `--terrain FILE`): keep the route this many metres above
    /// the ground everywhere along it, climbing and descending within `max_climb_m_s` and
    /// `max_descent_m_s` at `max_speed_m_s`; buildings' heights count from the ground under
    /// them [default: alt_m].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true))]
    pub alt_agl_m: Option<f64>,
    /// Safety margin around obstacles, metres [default: 5].
    #[serde(alias = "safety_distance")]
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true))]
    pub safety_m: Option<f64>,
    /// Grid cell size of colliders maps, metres [default: 1].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true))]
    pub cell_m: Option<f64>,
    /// Start as local metres north,east of the map's origin [default: the map's default start; the home on colliders maps].
    #[cfg_attr(feature = "clap", arg(long, value_name = "N,E", value_parser = cli::pair, conflicts_with = "start_lla", allow_hyphen_values = true))]
    pub start_ne: Option<[f64; 2]>,
    /// Start as latitude,longitude in degrees (the vehicle's current global position).
    #[cfg_attr(feature = "clap", arg(long, value_name = "LAT,LON", value_parser = cli::pair, allow_hyphen_values = true))]
    pub start_lla: Option<[f64; 2]>,
    /// Goal as local metres north,east of the map's origin [default: the map's; 420,390 on the bundled map].
    #[cfg_attr(feature = "clap", arg(long, value_name = "N,E", value_parser = cli::pair, conflicts_with = "goal_lla", allow_hyphen_values = true))]
    pub goal_ne: Option<[f64; 2]>,
    /// Goal as latitude,longitude in degrees.
    #[cfg_attr(feature = "clap", arg(long, value_name = "LAT,LON", value_parser = cli::pair, allow_hyphen_values = true))]
    pub goal_lla: Option<[f64; 2]>,
    /// Heading of the first waypoint, degrees clockwise from north [default: 0].
    #[cfg_attr(feature = "clap", arg(long, value_name = "DEG", value_parser = cli::finite, allow_hyphen_values = true))]
    pub start_heading_deg: Option<f64>,
    /// Seed of the sampling planners, of a random workspace and of `fly`'s random hidden buildings [default: 1].
    #[cfg_attr(feature = "clap", arg(long, value_name = "S"))]
    pub seed: Option<u64>,
    /// Grid connectivity: 8 (diagonals cost √2) or 4 [default: 8].
    #[cfg_attr(feature = "clap", arg(long, value_name = "4|8", value_parser = clap::value_parser!(u8).range(4..=8), help_heading = cli::GRID))]
    pub connectivity: Option<u8>,
    /// Let diagonal moves pass between two blocked cells (the FCND move model) [default: false].
    #[cfg_attr(feature = "clap", arg(long, num_args = 0..=1, value_name = "BOOL", default_missing_value = "true", hide_possible_values = true, help_heading = cli::GRID))]
    pub corner_cutting: Option<bool>,
    /// Collinearity pruning of the grid path [default: collinear].
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = cli::GRID))]
    pub prune: Option<PruneMode>,
    /// The FCND determinant collinearity test with this tolerance (cells²) instead of exact pruning.
    #[cfg_attr(feature = "clap", arg(long, value_name = "EPS", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::GRID))]
    pub epsilon: Option<f64>,
    /// Line-of-sight shortcut of grid paths [default: true].
    #[cfg_attr(feature = "clap", arg(long = "no-shortcut", num_args = 0, default_missing_value = "false", help = "Skip the line-of-sight shortcut of grid paths", help_heading = cli::GRID))]
    pub shortcut: Option<bool>,
    /// wavefront: what the field counts [default: length].
    #[cfg_attr(feature = "clap", arg(long, value_enum, help_heading = cli::NAVFN))]
    pub field: Option<FieldMode>,
    /// costmap: radius inscribed in the vehicle's footprint, metres: cells within it are lethal [default: 0].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::NAVFN))]
    pub inscribed_radius_m: Option<f64>,
    /// costmap: distance up to which costs are raised, metres [default: 10 cells].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::NAVFN))]
    pub inflation_radius_m: Option<f64>,
    /// costmap: decay k of 252·exp(−k·(d − r_inscribed)), per metre [default: 3 / inflation radius].
    #[cfg_attr(feature = "clap", arg(long, value_name = "K", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::NAVFN))]
    pub cost_scaling: Option<f64>,
    /// costmap: weight of the cost in length + weight · cost [default: 2].
    #[cfg_attr(feature = "clap", arg(long, value_name = "W", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::NAVFN))]
    pub cost_weight: Option<f64>,
    /// Start altitude above home, metres [default: the flight altitude].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::three_d()))]
    pub start_alt_m: Option<f64>,
    /// Goal altitude above home, metres [default: the flight altitude].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::three_d()))]
    pub goal_alt_m: Option<f64>,
    /// Time budget, milliseconds, 1 to 600000 (rrt-star uses all of it; the others stop at the first path) [default: 1000]; with ch, how long building its hierarchy may take [default: no limit].
    #[cfg_attr(feature = "clap", arg(long, value_name = "MS", help_heading = cli::three_d()))]
    pub time_limit_ms: Option<u64>,
    /// Floor of the flight volume: nothing flies lower, metres [default: 0, the ground].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::three_d()))]
    pub min_alt_m: Option<f64>,
    /// Ceiling of the flight volume, metres [default: 120, at least 10 m above both ends].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::three_d()))]
    pub max_alt_m: Option<f64>,
    /// voxel: extra cost per metre climbed (0: shortest path) [default: 1].
    #[cfg_attr(feature = "clap", arg(long, value_name = "W", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::three_d()))]
    pub climb_weight: Option<f64>,
    /// voxel: horizontal pitch of the voxel lattice, metres [default: 5].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_negative_numbers = true, help_heading = cli::three_d()))]
    pub voxel_m: Option<f64>,
    /// voxel: vertical pitch between altitude layers, metres [default: 5].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = cli::finite, allow_negative_numbers = true, help_heading = cli::three_d()))]
    pub layer_m: Option<f64>,
    /// Make a smooth, time-parametrised trajectory of the route: minimum jerk in a corridor of free boxes, within the limits below, proven inside free space [default: false].
    #[cfg_attr(feature = "clap", arg(long, num_args = 0..=1, value_name = "BOOL", default_missing_value = "true", hide_possible_values = true, help_heading = cli::TRAJECTORY))]
    pub trajectory: Option<bool>,
    /// Largest speed, m/s, above 0 and at most 100 [default: 10].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M/S", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::TRAJECTORY))]
    pub max_speed_m_s: Option<f64>,
    /// Largest acceleration, m/s², above 0 and at most 50 [default: 4].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M/S2", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::TRAJECTORY))]
    pub max_accel_m_s2: Option<f64>,
    /// Largest jerk, m/s³, above 0 and at most 1000 [default: 10].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M/S3", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::TRAJECTORY))]
    pub max_jerk_m_s3: Option<f64>,
    /// Largest climb rate, m/s, above 0 and at most 100 [default: 3].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M/S", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::TRAJECTORY))]
    pub max_climb_m_s: Option<f64>,
    /// Largest descent rate, m/s, above 0 and at most 100 [default: 1.5].
    #[cfg_attr(feature = "clap", arg(long, value_name = "M/S", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::TRAJECTORY))]
    pub max_descent_m_s: Option<f64>,
    /// Largest yaw rate, degrees per second, above 0 and at most 3600 [default: 90].
    #[cfg_attr(feature = "clap", arg(long, value_name = "DEG/S", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::TRAJECTORY))]
    pub max_yaw_rate_deg_s: Option<f64>,
    /// Trajectory samples per second in outputs, above 0 and at most 1000 [default: 10].
    #[cfg_attr(feature = "clap", arg(long, value_name = "HZ", value_parser = cli::finite, allow_hyphen_values = true, help_heading = cli::TRAJECTORY))]
    pub sample_hz: Option<f64>,
    /// Return the geometry pictures need (grid path, roadmap, trees, field) [default: false].
    #[cfg_attr(feature = "clap", arg(skip))]
    pub geometry: Option<bool>,
    /// No-fly zones: the text of a GeoJSON FeatureCollection of zones (see
    /// [`skyplan_map::nofly`]) or of a QGroundControl `.plan` file (its `geoFence`). The CLI's
    /// `--no-fly FILE` reads the file into it. Honoured by the 2D planners on colliders and
    /// footprint maps; the 3D planners and Voronoi refuse it.
    #[cfg_attr(feature = "clap", arg(skip))]
    pub no_fly: Option<String>,
    /// When the flight leaves, an RFC 3339 time (`2026-12-03T17:00:00Z`): a no-fly zone with
    /// a time window then applies only when that window meets the flight's, from the departure
    /// to the latest arrival ([`latest_arrival_s`](crate::latest_arrival_s)). Without it every
    /// timed zone applies whatever its times (the safe side). Used only with `no_fly`.
    #[cfg_attr(feature = "clap", arg(long, value_name = "TIME"))]
    pub departure: Option<String>,
    /// A saved PRM roadmap to start from / return the roadmap (Rust callers only).
    #[serde(skip)]
    #[cfg_attr(feature = "clap", arg(skip))]
    pub roadmap: RoadmapIo,
}

macro_rules! merge_fields {
    ($a:ident, $b:ident; $($f:ident),* $(,)?) => {
        PlanRequest { $($f: $a.$f.or($b.$f),)* roadmap: if $a.roadmap == RoadmapIo::default() { $b.roadmap } else { $a.roadmap } }
    };
}

impl PlanRequest {
    /// The seed, or its default (1): the sampling planners', and the one front ends draw a
    /// random workspace or random hidden buildings with.
    pub fn seed_or_default(&self) -> u64 {
        self.seed.unwrap_or(1)
    }

    /// Whether the request's field counts steps (not lengths).
    pub fn counts_steps(&self) -> bool {
        self.field == Some(FieldMode::Steps)
    }

    /// Field by field, `self` where set, else `fallback` (command line over config file); a
    /// start or goal counts as one field whichever form it is given in (a goal as `goal_ne`
    /// here replaces the fallback's `goal_lla`).
    pub fn or(self, mut fallback: PlanRequest) -> PlanRequest {
        if self.start_ne.is_some() || self.start_lla.is_some() {
            (fallback.start_ne, fallback.start_lla) = (None, None);
        }
        if self.goal_ne.is_some() || self.goal_lla.is_some() {
            (fallback.goal_ne, fallback.goal_lla) = (None, None);
        }
        let (a, b) = (self, fallback);
        merge_fields!(a, b; planner, alt_m, alt_agl_m, safety_m, cell_m, start_ne, start_lla, goal_ne,
            goal_lla, start_alt_m, goal_alt_m, start_heading_deg, connectivity, corner_cutting,
            prune, epsilon, shortcut, time_limit_ms, seed, min_alt_m, max_alt_m, climb_weight,
            voxel_m, layer_m, field, inscribed_radius_m, inflation_radius_m, cost_scaling,
            cost_weight, trajectory, max_speed_m_s, max_accel_m_s2, max_jerk_m_s3, max_climb_m_s,
            max_descent_m_s, max_yaw_rate_deg_s, sample_hz, geometry, no_fly, departure)
    }

    /// The trajectory limits given, each over its default.
    pub fn trajectory_limits(&self) -> TrajectoryLimits {
        let d = TrajectoryLimits::default();
        TrajectoryLimits {
            max_speed_m_s: self.max_speed_m_s.unwrap_or(d.max_speed_m_s),
            max_accel_m_s2: self.max_accel_m_s2.unwrap_or(d.max_accel_m_s2),
            max_jerk_m_s3: self.max_jerk_m_s3.unwrap_or(d.max_jerk_m_s3),
            max_climb_m_s: self.max_climb_m_s.unwrap_or(d.max_climb_m_s),
            max_descent_m_s: self.max_descent_m_s.unwrap_or(d.max_descent_m_s),
            max_yaw_rate_deg_s: self.max_yaw_rate_deg_s.unwrap_or(d.max_yaw_rate_deg_s),
        }
    }

    /// The request's altitude, margin, cell size, move model and flight volume with the
    /// defaults applied and every value checked (as a plan would use them); a bad value is a
    /// bad request naming the field and its range.
    pub fn spec(&self) -> Result<PlanSpec, PlanFailure> {
        Resolved::new(self).map(|r| r.spec())
    }

    /// The request with another start (replanning from where the vehicle is now).
    pub fn from_start_ne(&self, north_m: f64, east_m: f64) -> PlanRequest {
        PlanRequest {
            start_ne: Some([north_m, east_m]),
            start_lla: None,
            ..self.clone()
        }
    }
}

/// The flight altitude when none is given, metres above home.
const DEFAULT_ALT_M: f64 = 5.0;
/// The safety margin when none is given, metres.
const DEFAULT_SAFETY_M: f64 = 5.0;
/// The cell size of colliders grids when none is given, metres.
const DEFAULT_CELL_M: f64 = 1.0;

impl Default for PlanSpec {
    /// The spec of a request that gives nothing: 5 m altitude and margin, 1 m cells, 8-connected
    /// without corner cutting, the flight volume 0 to 120 m.
    ///
    /// ```
    /// use skyplan_plan::{PlanRequest, PlanSpec};
    /// assert_eq!(PlanSpec::default(), PlanRequest::default().spec()?);
    /// # Ok::<(), skyplan_plan::PlanFailure>(())
    /// ```
    fn default() -> Self {
        PlanSpec {
            alt_m: DEFAULT_ALT_M,
            safety_m: DEFAULT_SAFETY_M,
            cell_m: DEFAULT_CELL_M,
            move_model: MoveModel::Octile,
            min_alt_m: 0.0,
            max_alt_m: 120.0,
        }
    }
}

/// Highest altitude any option takes, metres.
pub const MAX_ALT_M: f64 = 10_000.0;
/// Longest time budget, milliseconds (10 minutes).
pub const MAX_TIME_LIMIT_MS: u64 = 600_000;

/// A position as given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Position {
    Ne(f64, f64),
    Lla(f64, f64),
}

/// How the vehicle moves between cells.
pub(crate) use skyplan_search::MoveModel;

/// A start or goal, resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct End {
    /// Where (`None`: the map's default).
    pub at: Option<Position>,
    /// Altitude of 3D planners, metres (the flight altitude unless given).
    pub alt_m: f64,
}

impl End {
    /// `which` (`start` or `goal`) from the request's fields, each checked.
    fn of(
        which: &str,
        (ne, lla, alt_m): (Option<[f64; 2]>, Option<[f64; 2]>, Option<f64>),
        flight_alt_m: f64,
    ) -> Result<End, PlanFailure> {
        let alt_m = alt_m.unwrap_or(flight_alt_m);
        Ok(End {
            at: position(ne, lla, which)?,
            alt_m: in_range(&format!("{which}_alt_m"), alt_m, 0.0, MAX_ALT_M, " m")?,
        })
    }
}

/// The trajectory asked for, resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TrajectorySpec {
    pub limits: TrajectoryLimits,
    pub sample_hz: f64,
}

/// The trajectory of `r`, if asked for, its limits checked; limits given without it are
/// refused (nothing is silently ignored).
fn trajectory(r: &PlanRequest) -> Result<Option<TrajectorySpec>, PlanFailure> {
    let given: Vec<&str> = [
        ("max_speed_m_s", r.max_speed_m_s),
        ("max_accel_m_s2", r.max_accel_m_s2),
        ("max_jerk_m_s3", r.max_jerk_m_s3),
        ("max_climb_m_s", r.max_climb_m_s),
        ("max_descent_m_s", r.max_descent_m_s),
        ("max_yaw_rate_deg_s", r.max_yaw_rate_deg_s),
        ("sample_hz", r.sample_hz),
    ]
    .iter()
    .filter(|f| f.1.is_some())
    .map(|f| f.0)
    // Over terrain the speed and the vertical rates set the steepest climb and descent.
    .filter(|name| {
        r.alt_agl_m.is_none()
            || !matches!(*name, "max_speed_m_s" | "max_climb_m_s" | "max_descent_m_s")
    })
    .collect();
    if r.trajectory != Some(true) {
        if given.is_empty() {
            if r.alt_agl_m.is_some() {
                r.trajectory_limits()
                    .check()
                    .map_err(|e| bad(e.to_string()))?;
            }
            return Ok(None);
        }
        let one = given.len() == 1;
        return Err(bad(format!(
            "{} {} used only with a trajectory: ask for one (trajectory true)",
            given.join(", "),
            if one { "is" } else { "are" }
        )));
    }
    let limits = r.trajectory_limits();
    limits.check().map_err(|e| bad(e.to_string()))?;
    let sample_hz = positive("sample_hz", r.sample_hz.unwrap_or(10.0), 1000.0)?;
    Ok(Some(TrajectorySpec { limits, sample_hz }))
}

/// The request with defaults applied and every value checked.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Resolved {
    pub planner: PlannerId,
    pub alt_m: f64,
    pub safety_m: f64,
    pub cell_m: f64,
    pub start: End,
    pub goal: End,
    pub start_heading_rad: f64,
    pub model: MoveModel,
    pub prune: Prune,
    pub shortcut: bool,
    pub time_limit: Duration,
    pub time_limit_ms: u64,
    /// `ch`: how long its preprocessing may take (only when a time limit is given).
    pub preprocess_limit: Option<Duration>,
    pub seed: u64,
    pub min_alt_m: f64,
    pub max_alt_m: f64,
    pub climb_weight: f64,
    pub voxel_m: f64,
    pub layer_m: f64,
    pub field: FieldMode,
    pub costmap: CostmapOptions,
    pub geometry: bool,
    pub trajectory: Option<TrajectorySpec>,
    /// The request's no-fly zones, parsed (longitude/latitude).
    pub no_fly: Option<skyplan_map::nofly::NoFlyZones>,
    /// The departure (Unix seconds, UTC), when given.
    pub departure_unix_s: Option<i64>,
    /// `alt_agl_m` when given (the flight altitude `alt_m` is then this height).
    pub alt_agl_m: Option<f64>,
    /// Steepest climb and descent over terrain, metres per metre flown horizontally.
    pub terrain_slopes: [f64; 2],
}

/// Collinearity pruning, resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Prune {
    None,
    Collinear,
    Epsilon(f64),
}

fn bad(message: String) -> PlanFailure {
    PlanFailure::new(FailureKind::BadRequest, message)
}

/// A value in `[lo, hi]`, else an error naming the field and the range.
pub(crate) fn in_range(
    name: &str,
    v: f64,
    lo: f64,
    hi: f64,
    unit: &str,
) -> Result<f64, PlanFailure> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(bad(format!(
            "{name} {v}: expected a number from {lo} to {hi}{unit}"
        )))
    }
}

fn positive(name: &str, v: f64, hi: f64) -> Result<f64, PlanFailure> {
    if v.is_finite() && v > 0.0 && v <= hi {
        Ok(v)
    } else {
        Err(bad(format!(
            "{name} {v}: expected a number above 0 and at most {hi}"
        )))
    }
}

fn position(
    ne: Option<[f64; 2]>,
    lla: Option<[f64; 2]>,
    which: &str,
) -> Result<Option<Position>, PlanFailure> {
    match (ne, lla) {
        (Some(_), Some(_)) => Err(bad(format!(
            "give either {which}_ne or {which}_lla, not both"
        ))),
        (Some([n, e]), None) if n.is_finite() && e.is_finite() => Ok(Some(Position::Ne(n, e))),
        (None, Some([lat, lon])) if lat.is_finite() && lon.is_finite() => {
            Ok(Some(Position::Lla(lat, lon)))
        }
        (None, None) => Ok(None),
        _ => Err(bad(format!("{which}: expected finite numbers"))),
    }
}

/// The options of `group` that `r` gives.
fn given(r: &PlanRequest, group: OptionGroup) -> Vec<&'static str> {
    let fields: &[(&'static str, bool)] = match group {
        OptionGroup::GridPath => &[
            ("prune", r.prune.is_some()),
            ("epsilon", r.epsilon.is_some()),
            ("shortcut", r.shortcut.is_some()),
            ("connectivity", r.connectivity.is_some()),
            ("corner_cutting", r.corner_cutting.is_some()),
        ],
        OptionGroup::ThreeD => &[
            ("start_alt_m", r.start_alt_m.is_some()),
            ("goal_alt_m", r.goal_alt_m.is_some()),
            ("min_alt_m", r.min_alt_m.is_some()),
            ("max_alt_m", r.max_alt_m.is_some()),
        ],
        OptionGroup::TimeLimit => &[("time_limit_ms", r.time_limit_ms.is_some())],
        OptionGroup::Lattice => &[
            ("climb_weight", r.climb_weight.is_some()),
            ("voxel_m", r.voxel_m.is_some()),
            ("layer_m", r.layer_m.is_some()),
        ],
        OptionGroup::Inflation => &[
            ("inscribed_radius_m", r.inscribed_radius_m.is_some()),
            ("inflation_radius_m", r.inflation_radius_m.is_some()),
            ("cost_scaling", r.cost_scaling.is_some()),
            ("cost_weight", r.cost_weight.is_some()),
        ],
        OptionGroup::Field => &[("field", r.field.is_some())],
    };
    fields.iter().filter(|f| f.1).map(|f| f.0).collect()
}

/// Options given that the planner does not use: refused, naming the planners that use them
/// (from the registry), so that nothing is silently ignored.
fn check_applicable(r: &PlanRequest, planner: PlannerId) -> Result<(), PlanFailure> {
    for &group in OptionGroup::ALL {
        let names = given(r, group);
        if names.is_empty() || planner.uses(group) {
            continue;
        }
        let users = PlannerId::names_where(|p| p.uses(group));
        let one = names.len() == 1;
        return Err(bad(format!(
            "{} {} not used by planner {planner}: {} need{} a planner that uses {} ({users})",
            names.join(", "),
            if one { "is" } else { "are" },
            if one { "it" } else { "they" },
            if one { "s" } else { "" },
            if one { "it" } else { "them" },
        )));
    }
    Ok(())
}

/// The move model of `connectivity` and `corner_cutting`.
fn move_model(r: &PlanRequest) -> Result<MoveModel, PlanFailure> {
    match (
        r.connectivity.unwrap_or(8),
        r.corner_cutting.unwrap_or(false),
    ) {
        (8, false) => Ok(MoveModel::Octile),
        (8, true) => Ok(MoveModel::OctileCornerCutting),
        (4, false) => Ok(MoveModel::FourConnected),
        (4, true) => Err(bad(
            "corner_cutting needs diagonal moves: use it with connectivity 8".into(),
        )),
        (other, _) => Err(bad(format!("connectivity {other}: expected 4 or 8"))),
    }
}

/// The pruning of `prune` and `epsilon`.
fn prune(r: &PlanRequest) -> Result<Prune, PlanFailure> {
    match (r.epsilon, r.prune) {
        (Some(eps), _) if !(eps.is_finite() && eps >= 0.0) => {
            Err(bad(format!("epsilon {eps}: expected a tolerance ≥ 0")))
        }
        (Some(_), Some(PruneMode::None)) => {
            Err(bad("epsilon asks for pruning, prune none forbids it".into()))
        }
        (Some(eps), _) => Ok(Prune::Epsilon(eps)),
        (None, Some(PruneMode::None)) => Ok(Prune::None),
        (None, _) => Ok(Prune::Collinear),
    }
}

/// The flight volume's floor and ceiling (the ceiling at least 10 m above both ends unless given).
fn volume(r: &PlanRequest, start: &End, goal: &End) -> Result<(f64, f64), PlanFailure> {
    let min_alt_m = in_range(
        "min_alt_m",
        r.min_alt_m.unwrap_or(0.0),
        0.0,
        MAX_ALT_M,
        " m",
    )?;
    let max_alt_m = match r.max_alt_m {
        Some(v) => in_range("max_alt_m", v, 0.0, MAX_ALT_M, " m")?,
        None => 120f64
            .max(start.alt_m + 10.0)
            .max(goal.alt_m + 10.0)
            .min(MAX_ALT_M),
    };
    if min_alt_m >= max_alt_m {
        let (which, given) = match (r.min_alt_m, r.max_alt_m) {
            (_, Some(_)) => ("max_alt_m", format!("{max_alt_m}")),
            _ => ("min_alt_m", format!("{min_alt_m}")),
        };
        return Err(bad(format!(
            "{which} {given}: the floor of the flight volume ({min_alt_m} m) must be below its ceiling ({max_alt_m} m)"
        )));
    }
    Ok((min_alt_m, max_alt_m))
}

/// The request's departure in Unix seconds: an RFC 3339 time, given with no-fly zones.
fn departure(r: &PlanRequest) -> Result<Option<i64>, PlanFailure> {
    let Some(text) = &r.departure else {
        return Ok(None);
    };
    if r.no_fly.is_none() {
        return Err(bad(
            "departure is used only with no-fly zones (no_fly): it says which timed zones apply"
                .into(),
        ));
    }
    skyplan_map::nofly::parse_rfc3339(text)
        .map(Some)
        .ok_or_else(|| {
            bad(format!(
                "departure \"{}\": expected an RFC 3339 time such as \"2026-12-03T17:00:00Z\"",
                text.chars().take(40).collect::<String>()
            ))
        })
}

impl Resolved {
    /// The values every front end reads back from a plan.
    pub(crate) fn spec(&self) -> PlanSpec {
        PlanSpec {
            alt_m: self.alt_m,
            safety_m: self.safety_m,
            cell_m: self.cell_m,
            move_model: self.model,
            min_alt_m: self.min_alt_m,
            max_alt_m: self.max_alt_m,
        }
    }

    pub(crate) fn new(r: &PlanRequest) -> Result<Self, PlanFailure> {
        let planner = r.planner.unwrap_or_default();
        check_applicable(r, planner)?;
        let alt_agl_m = r
            .alt_agl_m
            .map(|h| in_range("alt_agl_m", h, 0.0, MAX_ALT_M, " m"))
            .transpose()?;
        if let (Some(h), Some(a)) = (alt_agl_m, r.alt_m)
            && h != a
        {
            return Err(bad(format!(
                "alt_agl_m {h} and alt_m {a}: over terrain the flight altitude is the height above the ground; give one of them"
            )));
        }
        let alt_m = in_range(
            "alt_m",
            alt_agl_m.or(r.alt_m).unwrap_or(DEFAULT_ALT_M),
            0.0,
            MAX_ALT_M,
            " m",
        )?;
        let limits = r.trajectory_limits();
        let safety_m = in_range(
            "safety_m",
            r.safety_m.unwrap_or(DEFAULT_SAFETY_M),
            0.0,
            1000.0,
            " m",
        )?;
        let cell_m = positive("cell_m", r.cell_m.unwrap_or(DEFAULT_CELL_M), 1000.0)?;
        let model = move_model(r)?;
        let prune = prune(r)?;
        let start = End::of("start", (r.start_ne, r.start_lla, r.start_alt_m), alt_m)?;
        let goal = End::of("goal", (r.goal_ne, r.goal_lla, r.goal_alt_m), alt_m)?;
        let (min_alt_m, max_alt_m) = volume(r, &start, &goal)?;
        let time_limit_ms = r.time_limit_ms.unwrap_or(1000);
        if !(1..=MAX_TIME_LIMIT_MS).contains(&time_limit_ms) {
            return Err(bad(format!(
                "time_limit_ms {time_limit_ms}: expected 1 to {MAX_TIME_LIMIT_MS} (10 minutes)"
            )));
        }
        let climb_weight = in_range("climb_weight", r.climb_weight.unwrap_or(1.0), 0.0, 1e6, "")?;
        let voxel_m = positive("voxel_m", r.voxel_m.unwrap_or(5.0), 1000.0)?;
        let layer_m = positive("layer_m", r.layer_m.unwrap_or(5.0), 1000.0)?;
        let start_heading_deg = r.start_heading_deg.unwrap_or(0.0);
        if !start_heading_deg.is_finite() {
            return Err(bad("start_heading_deg: expected a finite number".into()));
        }
        Ok(Self {
            planner,
            alt_m,
            safety_m,
            cell_m,
            start,
            goal,
            start_heading_rad: start_heading_deg.to_radians(),
            model,
            prune,
            shortcut: r.shortcut.unwrap_or(true),
            time_limit: Duration::from_millis(time_limit_ms),
            time_limit_ms,
            preprocess_limit: r.time_limit_ms.map(Duration::from_millis),
            seed: r.seed_or_default(),
            min_alt_m,
            max_alt_m,
            climb_weight,
            voxel_m,
            layer_m,
            field: r.field.unwrap_or(FieldMode::Length),
            costmap: CostmapOptions {
                inscribed_radius_m: r.inscribed_radius_m,
                inflation_radius_m: r.inflation_radius_m,
                cost_scaling: r.cost_scaling,
                cost_weight: r.cost_weight,
            }
            .checked()?,
            geometry: r.geometry.unwrap_or(false),
            trajectory: trajectory(r)?,
            no_fly: r
                .no_fly
                .as_deref()
                .map(skyplan_map::nofly::parse_no_fly)
                .transpose()
                .map_err(|e| bad(format!("no_fly: {e}")))?,
            departure_unix_s: departure(r)?,
            alt_agl_m,
            terrain_slopes: [
                limits.max_climb_m_s / limits.max_speed_m_s,
                limits.max_descent_m_s / limits.max_speed_m_s,
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_values_name_the_field_and_range() {
        for (req, phrase) in [
            (
                PlanRequest {
                    alt_m: Some(-5.0),
                    ..Default::default()
                },
                "alt_m -5",
            ),
            (
                PlanRequest {
                    alt_m: Some(1e9),
                    ..Default::default()
                },
                "alt_m 1000000000",
            ),
            (
                PlanRequest {
                    cell_m: Some(0.0),
                    ..Default::default()
                },
                "cell_m 0",
            ),
            (
                PlanRequest {
                    time_limit_ms: Some(u64::MAX),
                    planner: Some(PlannerId::Prm),
                    ..Default::default()
                },
                "time_limit_ms",
            ),
            (
                PlanRequest {
                    max_alt_m: Some(0.0),
                    planner: Some(PlannerId::Prm),
                    ..Default::default()
                },
                "max_alt_m 0",
            ),
            (
                PlanRequest {
                    connectivity: Some(4),
                    corner_cutting: Some(true),
                    ..Default::default()
                },
                "corner_cutting",
            ),
            (
                PlanRequest {
                    start_ne: Some([0.0, 0.0]),
                    start_lla: Some([1.0, 1.0]),
                    ..Default::default()
                },
                "either start_ne or start_lla",
            ),
            (
                PlanRequest {
                    trajectory: Some(true),
                    max_accel_m_s2: Some(80.0),
                    ..Default::default()
                },
                "max_accel_m_s2 = 80: expected a number above 0 and at most 50",
            ),
            (
                PlanRequest {
                    trajectory: Some(true),
                    max_speed_m_s: Some(f64::NAN),
                    ..Default::default()
                },
                "max_speed_m_s = NaN",
            ),
            (
                PlanRequest {
                    trajectory: Some(true),
                    sample_hz: Some(0.0),
                    ..Default::default()
                },
                "sample_hz 0",
            ),
            (
                PlanRequest {
                    max_speed_m_s: Some(5.0),
                    ..Default::default()
                },
                "max_speed_m_s is used only with a trajectory",
            ),
        ] {
            let e = Resolved::new(&req).unwrap_err();
            assert_eq!(e.kind, FailureKind::BadRequest);
            assert!(e.message.contains(phrase), "{} lacks {phrase}", e.message);
        }
    }

    #[test]
    fn options_the_planner_does_not_use_are_refused() {
        let e = Resolved::new(&PlanRequest {
            goal_alt_m: Some(30.0),
            ..Default::default()
        })
        .unwrap_err();
        assert!(
            e.message.contains("goal_alt_m is not used by planner jps"),
            "{}",
            e.message
        );
        assert!(
            e.message
                .contains("(prm, lazy-prm, rrt-connect, rrt-star, voxel)"),
            "{}",
            e.message
        );
        let e = Resolved::new(&PlanRequest {
            planner: Some(PlannerId::Astar),
            climb_weight: Some(2.0),
            ..Default::default()
        })
        .unwrap_err();
        assert!(
            e.message.ends_with("a planner that uses it (voxel)"),
            "{}",
            e.message
        );
        assert!(
            Resolved::new(&PlanRequest {
                planner: Some(PlannerId::Voxel),
                climb_weight: Some(2.0),
                goal_alt_m: Some(30.0),
                ..Default::default()
            })
            .is_ok()
        );
    }

    #[test]
    fn command_line_wins_over_config_field_by_field() {
        let cli = PlanRequest {
            alt_m: Some(10.0),
            ..Default::default()
        };
        let cfg = PlanRequest {
            alt_m: Some(3.0),
            safety_m: Some(2.0),
            ..Default::default()
        };
        let merged = cli.or(cfg);
        assert_eq!((merged.alt_m, merged.safety_m), (Some(10.0), Some(2.0)));
        // An end given in one form replaces the fallback's end in the other form.
        let cli = PlanRequest {
            goal_ne: Some([100.0, 100.0]),
            ..Default::default()
        };
        let cfg = PlanRequest {
            goal_lla: Some([37.79, -122.39]),
            start_lla: Some([37.7925, -122.3975]),
            ..Default::default()
        };
        let merged = cli.or(cfg);
        assert_eq!(
            (merged.goal_ne, merged.goal_lla),
            (Some([100.0, 100.0]), None)
        );
        assert_eq!(merged.start_lla, Some([37.7925, -122.3975]));
    }
}
