//! # skyplan's planning API
//!
//! One door to every planner. Load a [`World`] once (an FCND colliders map, an occupancy image,
//! a MovingAI grid or a random workspace), open a [`Session`] on it, and send [`PlanRequest`]s:
//! plain, serialisable options whose keys are the CLI's long options with underscores. Every
//! planner — grid search, any-angle, navigation functions, roadmaps, sampling and voxel search in
//! 3D — answers with the same [`Plan`] (waypoints `[north, east, alt, heading]`, cost, statistics,
//! and the geometry pictures need) or the same [`PlanFailure`] (kinds as in OMPL). Every route is
//! re-checked against the map inside the session before it is returned: no caller can skip it.
//!
//! The crate does no I/O: worlds are built from text and bytes, plans are values.
//!
//! ## Grid planners (exact)
//! ```
//! use skyplan_plan::{PlanRequest, PlannerId, Session, World};
//! let mut session = Session::new(World::fcnd_city());
//! let plan = session.plan(&PlanRequest {
//!     planner: Some(PlannerId::JpsPlus),
//!     goal_ne: Some([420.0, 390.0]),
//!     ..Default::default()
//! })?;
//! assert_eq!(plan.waypoints.first().map(|w| (w[0], w[1])), Some((0.0, 0.0)));
//! assert!(plan.mission.is_some()); // the map has a geodetic home: waypoints carry lat/lon
//! # Ok::<(), skyplan_plan::PlanFailure>(())
//! ```
//!
//! ## Navigation functions on a grid map
//! ```
//! use skyplan_plan::{PlanRequest, PlannerId, Session, World};
//! let grid = skyplan_cspace::Grid2::from_ascii("......\n.####.\n......")?;
//! let mut session = Session::new(World::from_grid("tiny", grid));
//! let plan = session.plan(&PlanRequest {
//!     planner: Some(PlannerId::Wavefront),
//!     start_ne: Some([1.5, 0.5]),
//!     goal_ne: Some([1.5, 5.5]),
//!     ..Default::default()
//! })?;
//! assert!(plan.cost_m > 5.0); // around the wall
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## 3D planners among the boxes
//! ```
//! use skyplan_plan::{FailureKind, PlanRequest, PlannerId, Session, World};
//! let mut session = Session::new(World::fcnd_city());
//! let request = PlanRequest {
//!     planner: Some(PlannerId::RrtConnect),
//!     goal_ne: Some([60.0, 40.0]),
//!     goal_alt_m: Some(20.0),
//!     ..Default::default()
//! };
//! let plan = session.plan(&request)?;
//! assert_eq!(plan.waypoints.last().map(|w| w[2]), Some(20.0));
//! // The grid's corner is inside every planner's bounds.
//! let corner = PlanRequest { goal_ne: Some([-316.0, -389.0]), ..request };
//! assert_ne!(session.plan(&corner).err().map(|f| f.kind), Some(FailureKind::InvalidGoal));
//! # Ok::<(), skyplan_plan::PlanFailure>(())
//! ```
//!
//! ## Roadmaps
//! ```
//! use skyplan_plan::{PlanRequest, PlannerId, Session, World};
//! let mut session = Session::new(World::fcnd_city());
//! let plan = session.plan(&PlanRequest { planner: Some(PlannerId::Voronoi), ..Default::default() })?;
//! assert!(plan.details["nodes"].as_u64().unwrap_or(0) > 1000);
//! # Ok::<(), skyplan_plan::PlanFailure>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod algorithm;
mod any_angle;
pub mod auto;
mod cell_search;
pub mod cli;
mod config;
mod failure;
mod grid;
mod map_file;
mod navfn;
mod plan;
mod planner_id;
mod request;
mod ride;
mod session;
mod summary;
mod three_d;
mod voronoi;
mod world;
mod zone_times;

pub use cell_search::CellSearch;
pub use config::{ConfigError, ConfigText, parse_config_toml};
pub use failure::{FailureKind, PlanFailure};
pub use grid::waypoint_points;
pub use map_file::{MapFileError, MapFileOptions};
pub use navfn::CostmapOptions;
pub use plan::{
    Geometry, GridInfo, GridPathStats, Home, Place, Plan, PlanSpec, Segment3, TRAJECTORY_COLUMNS,
    Timings, TrajectoryReport, WaypointCounts,
};
pub use planner_id::{MapKinds, Optimality, OptionGroup, PlannerId, PlannerInfo, UnknownPlanner};
pub use request::{FieldMode, MAX_ALT_M, MAX_TIME_LIMIT_MS, PlanRequest, PruneMode, RoadmapIo};
pub use ride::{Ride, RideChange, RideLeg, RidePlace, RideRequest};
pub use session::{Session, model_name, recheck_grid_route};
pub use skyplan_imagemap::MapYaml;
pub use skyplan_trajectory as trajectory;
pub use skyplan_trajectory::Limits as TrajectoryLimits;
pub use world::{
    BoundsNe, FCND_CITY_CSV, FCND_CITY_NAME, FCND_DEFAULT_GOAL_NE, Limits, MapFormat, MapKind,
    World, human_bytes,
};
pub use zone_times::{ARRIVAL_FACTOR, ARRIVAL_SLACK_S, latest_arrival_s};
