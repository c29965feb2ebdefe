//! A whole flight for any front end (`skyplan fly`, `skyplan bench --replan`): start the
//! simulator in-process, wait for the vehicle, plan from where it is (a replanner watching),
//! upload or fly, and sum it up. Lines go to a [`RunObserver`]; nothing here prints or writes
//! files.

use crate::flight::{self, Observer, Quiet};
use crate::home::{PlannedHome, RtlClearance, rtl_clearance};
use crate::words::sim_note_line;
use skyplan_flight::auto::{AutoExecutor, MissionLayout};
use skyplan_flight::collision::BoxWorld;
use skyplan_flight::executor::{
    ExecutorConfig, FailsafeAction, FlightExecutor, FlightState, MissionExecutor, Note, Outcome,
    ReferenceExecutor, Target, Telemetry, TrackingReport,
};
use skyplan_flight::fence::{RouteForFence, fence_from_zones, fence_items};
use skyplan_flight::reference::Reference;
use skyplan_flight::sim::DEFAULT_RTL_ALT_M;
use skyplan_flight::upload::{ItemCommand, LegPace, MissionPlan, UploadConfig};
use skyplan_frames::{Lla, LocalFrame, Ned};
use skyplan_link::ground::{
    Autopilot, GroundConfig, GroundError, GroundStation, LogRow, Update, VehicleInfo, Waiting,
};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::vehicle::SimServerConfig;
use skyplan_link::{Address, LinkError};
use skyplan_map::colliders::ObstacleBox;
use skyplan_map::nofly::parse_no_fly;
use skyplan_plan::{Limits, Plan, PlanFailure, PlanRequest, Session, World};
use skyplan_replan::bench::{FlightResult, Scenario, ScenarioSpec, SharedReplanner};
use skyplan_replan::hidden::{HiddenSpec, place_hidden};
use skyplan_replan::{ReplanOptions, ReplanStats, Replanner, ReplannerKind};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A lost link is waited for this many times the link timeout when a failsafe is set.
pub const LINK_REGAIN_FACTOR: f64 = 6.0;

/// Why a run stopped before its flight ended.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The options, the map or a position do not make a flight.
    #[error("{0}")]
    BadInput(String),
    /// Planning failed.
    #[error(transparent)]
    Plan(#[from] PlanFailure),
    /// The ground station failed (link, vehicle, upload).
    #[error(transparent)]
    Ground(#[from] GroundError),
    /// The simulator could not start.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// Anything else at run time.
    #[error("{0}")]
    Runtime(String),
}

fn bad(e: impl std::fmt::Display) -> RunError {
    RunError::BadInput(e.to_string())
}

/// Where a run's story goes: the flight's lines and updates ([`Observer`]), and the moments a
/// front end draws or writes something at.
pub trait RunObserver: Observer {
    /// The error a front end's [`RunObserver::planned`] may stop the run with.
    type Error: From<RunError>;
    /// Still waiting for the vehicle's `waiting`, `vehicle_s` vehicle seconds so far.
    fn waiting(&mut self, _waiting: Waiting, _vehicle_s: f64) {}
    /// The first plan, told before anything flies (write it, show it); an error stops the run.
    fn planned(&mut self, _plan: &Plan) -> Result<(), Self::Error> {
        Ok(())
    }
    /// The flight starts with this many waypoints (`Some`), or has ended, well or not (`None`).
    fn flying(&mut self, _waypoints: Option<usize>) {}
    /// The vehicle at the end of a flight: vehicle time, last state and telemetry.
    fn landed(&mut self, _time_s: f64, _state: FlightState, _telemetry: Option<&Telemetry>) {}
}

/// The map's obstacles as the simulator and the flight checks see them (no margin): a colliders
/// map's boxes or a footprint map's buildings, standing on the terrain if the world has one
/// ([`World::standing_obstacles`]); `None` for a grid map. Errors: a DEM that does not reach
/// under an obstacle.
pub fn map_obstacles(world: &World) -> Result<Option<BoxWorld>, PlanFailure> {
    if world.colliders().is_none() && world.footprints().is_none() {
        return Ok(None);
    }
    let (boxes, footprints) = world.standing_obstacles()?;
    Ok(Some(BoxWorld::with_footprints(&footprints, &boxes)))
}

/// Starts the simulator in-process on a free loopback port at the request's start (its
/// lat/lon, its north/east, else the map's home), the map's `obstacles` and `config.hidden`
/// its world; `config`'s home and map home are set here. Returns it and where it starts.
pub fn start_sim(
    obstacles: BoxWorld,
    frame: &LocalFrame,
    request: &PlanRequest,
    config: SimServerConfig,
) -> Result<(InProcessSim, Lla), RunError> {
    let home = match (request.start_lla, request.start_ne) {
        (Some([lat_deg, lon_deg]), _) => Lla {
            lat_deg,
            lon_deg,
            alt_m: 0.0,
        },
        (None, Some([north_m, east_m])) => frame
            .lla_from_ned(Ned {
                north_m,
                east_m,
                down_m: 0.0,
            })
            .map_err(|e| bad(format!("start: {e}")))?,
        (None, None) => frame.home(),
    };
    // Over terrain the vehicle stands on the ground where it starts.
    let home = match &config.terrain {
        Some(t) => {
            let at = frame
                .ned_from_lla(home)
                .map_err(|e| bad(format!("start: {e}")))?;
            let ground_m = (t.ground_m(at.north_m, at.east_m))
                .map_err(|e| bad(format!("start: the terrain under it: {e}")))?;
            Lla {
                alt_m: t.amsl_m(ground_m),
                ..home
            }
        }
        None => home,
    };
    let config = SimServerConfig {
        home,
        map_home: Some(frame.home()),
        ..config
    };
    Ok((InProcessSim::start(config, obstacles)?, home))
}

/// How a mission is flown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Position targets in GUIDED, this replanner watching (2D grid planners only).
    Guided(Option<ReplannerKind>),
    /// Uploaded as a mission, then flown in AUTO (`fly`), or not (an upload only).
    Upload {
        /// Fly it after the upload.
        fly: bool,
    },
}

/// How a run flies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlyOptions {
    /// The ground station: speedup, link timeout, flight budget, what an interrupt commands.
    pub ground: GroundConfig,
    /// The executor: deadband, failsafe and how long a lost link is waited for.
    pub executor: ExecutorConfig,
    /// How long to wait for the vehicle, vehicle seconds.
    pub wait_s: f64,
    /// GUIDED with a replanner, or an upload.
    pub mode: Mode,
    /// The request gives the start; otherwise the plan starts where the vehicle is.
    pub user_start: bool,
    /// Before take-off, upload the request's no-fly zones as the vehicle's fence and read it
    /// back (`upload_fence`); a refusal or a difference stops the run before arming.
    pub fence: bool,
}

/// A plan turned into the reference to fly (a time-parametrised trajectory through its
/// waypoints, say); an error stops the run before the flight.
pub type MakeReference = Arc<dyn Fn(&Plan) -> Result<Arc<dyn Reference>, String> + Send + Sync>;

/// What a GUIDED run flies by instead of waypoint-by-waypoint position targets
/// ([`fly_mission_with`]): setpoints with feed-forward streamed from a [`Reference`]'s clock
/// ([`ReferenceExecutor`]). With a replanner (a plan with a trajectory), each replanned route
/// becomes a trajectory from the one being flown, flown on without stopping
/// ([`crate::trajectory::rereference`]).
#[derive(Clone)]
pub enum ReferenceSource {
    /// This reference, whatever the plan (its frame: the map's local NED about its home).
    Given(Arc<dyn Reference>),
    /// The reference made from the plan, once it is planned (from where the vehicle is).
    FromPlan(MakeReference),
}

impl std::fmt::Debug for ReferenceSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReferenceSource::Given(r) => write!(f, "Given({} s)", r.duration_s()),
            ReferenceSource::FromPlan(_) => f.write_str("FromPlan(..)"),
        }
    }
}

impl ReferenceSource {
    /// The reference for `plan`.
    pub fn reference(&self, plan: &Plan) -> Result<Arc<dyn Reference>, RunError> {
        match self {
            ReferenceSource::Given(r) => Ok(Arc::clone(r)),
            ReferenceSource::FromPlan(make) => {
                make(plan).map_err(|e| RunError::BadInput(format!("the reference: {e}")))
            }
        }
    }
}

/// How a run ended: a flight (its outcome, `None` if an aborted flight did not land in time),
/// or an upload without a flight.
#[derive(Debug, Clone, PartialEq)]
pub enum Ended {
    /// Flown.
    Flight(Option<Outcome>),
    /// Uploaded only.
    Uploaded,
}

/// A run's result: what its summary, flight log and picture need.
pub struct Flight {
    /// The flight log (empty for an upload only).
    pub log: Vec<LogRow>,
    /// How it ended.
    pub ended: Ended,
    /// The first plan.
    pub plan: Plan,
    /// The replanner that watched the flight, if any.
    pub watcher: Option<SharedReplanner>,
    /// Every replanned route as (north, east) points.
    pub replanned: Vec<Vec<(f64, f64)>>,
    /// How a flight by a reference (`fly --trajectory`) followed it.
    pub tracking: Option<TrackingReport>,
}

impl Flight {
    /// The replans the flight's watcher made, in order (none without one): the flight log's
    /// replan rows.
    pub fn replan_events(&self) -> Vec<skyplan_flight::sensing::ReplanEvent> {
        self.watcher
            .as_ref()
            .and_then(|w| w.0.lock().ok().map(|r| r.events().to_vec()))
            .unwrap_or_default()
    }

    /// The cells the watcher learned, as (north, east) points (none without a watcher).
    pub fn learned_ne(&self) -> Vec<(f64, f64)> {
        self.watcher
            .as_ref()
            .and_then(|w| w.0.lock().ok().map(|r| r.learned_points_ne()))
            .unwrap_or_default()
            .into_iter()
            .flat_map(|(_, points)| points.into_iter().map(|[n, e]| (n, e)))
            .collect()
    }

    /// The flown track, as (north, east) points of the log.
    pub fn track_ne(&self) -> Vec<(f64, f64)> {
        self.log.iter().map(|r| (r.north_m, r.east_m)).collect()
    }
}

/// Connects to the vehicle at `address`, waits for it, plans `request` on `world` from where it
/// is (unless the request gives the start), then flies the plan in GUIDED (or uploads it and
/// flies it in AUTO), telling `observer` all along. `interrupt`, once set, lands or holds.
#[allow(clippy::too_many_arguments)]
pub fn fly_mission<O: RunObserver>(
    address: &Address,
    frame: &LocalFrame,
    inputs: (World, Limits, PlanRequest),
    o: &FlyOptions,
    sim: Option<&InProcessSim>,
    interrupt: Arc<AtomicBool>,
    observer: &mut O,
) -> Result<Flight, O::Error> {
    fly_mission_with(address, frame, inputs, o, None, sim, interrupt, observer)
}

/// As [`fly_mission`]; with `reference` (GUIDED only), the flight follows the reference made
/// for the plan (take-off over its start, its setpoints streamed with feed-forward from its
/// clock, a hold at its end, the landing), and its summary tells the tracking.
#[allow(clippy::too_many_arguments)]
pub fn fly_mission_with<O: RunObserver>(
    address: &Address,
    frame: &LocalFrame,
    (world, limits, mut request): (World, Limits, PlanRequest),
    o: &FlyOptions,
    reference: Option<&ReferenceSource>,
    sim: Option<&InProcessSim>,
    interrupt: Arc<AtomicBool>,
    observer: &mut O,
) -> Result<Flight, O::Error> {
    if reference.is_some() && matches!(o.mode, Mode::Upload { .. }) {
        return Err(bad("a reference is flown in GUIDED, not as an uploaded mission").into());
    }
    let returns = o.ground.on_interrupt == FailsafeAction::Return
        || o.executor.failsafe == Some(FailsafeAction::Return);
    if returns && (reference.is_some() || matches!(o.mode, Mode::Upload { .. })) {
        return Err(bad(
            "the action 'return' flies a route planned home in GUIDED, waypoint by waypoint; an uploaded mission or a trajectory flight cannot change its route in flight: use 'rtl' (the autopilot's own way home) or 'land'",
        )
        .into());
    }
    let mut gcs = GroundStation::connect(address, o.ground).map_err(RunError::from)?;
    gcs.set_interrupt(interrupt);
    observer.say(&format!(
        "link       {address}: connected, sending heartbeats at 1 Hz"
    ));
    let info = wait_for_vehicle(&mut gcs, o, sim, observer)?;

    // PLANNING: the heartbeat thread keeps the link alive meanwhile.
    observer.say("state      PLANNING");
    if !o.user_start {
        request.start_lla = Some([info.position.lat_deg, info.position.lon_deg]);
        request.start_ne = None;
    }
    // A trajectory flown by setpoints, or pacing an uploaded mission (seen against ArduCopter
    // SITL: paced at 9.8 m/s past its WPNAV limits, it ran 19 % over its duration).
    let trajectory = reference.is_some() || request.trajectory == Some(true);
    if trajectory && info.autopilot != Autopilot::Px4 {
        cap_to_vehicle(&mut gcs, &mut request, observer);
    }
    let t_plan = Instant::now();
    let home_world = returns.then(|| world.clone());
    let map_boxes = map_obstacles(&world).map_err(RunError::from)?;
    let terrain = world.terrain_shared();
    let home_up_m = match &terrain {
        Some(t) => vehicle_home_up_m(t, frame, &info, observer)?,
        None => 0.0,
    };
    gcs.set_home_up_m(home_up_m);
    let session = Session::new(world).with_limits(limits);
    let replanner = match o.mode {
        // The replanner keeps one altitude: over terrain the route's profile is flown as planned.
        Mode::Guided(Some(_)) if terrain.is_some() => {
            observer.say("replan     off over terrain: the replanner keeps one altitude, so the planned route's terrain profile is flown as planned");
            None
        }
        Mode::Guided(replanner) => replanner,
        Mode::Upload { .. } => None,
    };
    let (plan, watcher) =
        plan_with_replanner(session, request.clone(), replanner, brake(trajectory))
            .map_err(RunError::from)?;
    if let Some(w) = &watcher {
        gcs.set_watcher(Box::new(w.clone()));
    }
    let mission = plan
        .mission
        .as_ref()
        .ok_or_else(|| RunError::Runtime("the plan has no geodetic waypoints".into()))?;
    let alts = mission.waypoints.iter().map(|w| w.alt_m);
    observer.say(&format!(
        "plan       {}: {} → {}: {} waypoints, {:.1} m, altitudes {:.1}..{:.1} m, planned in {:.1} ms",
        plan.planner,
        plan.start,
        plan.goal,
        mission.waypoints.len(),
        mission.length_3d_m(),
        alts.clone().fold(f64::INFINITY, f64::min),
        alts.fold(f64::NEG_INFINITY, f64::max),
        t_plan.elapsed().as_secs_f64() * 1000.0
    ));
    if let Some(line) = plan.no_fly_line() {
        observer.say(&line);
    }
    observer.planned(&plan)?;
    if o.fence {
        upload_fence(&mut gcs, &request, mission, plan.spec.safety_m, observer)?;
    }
    let mut config = o.executor;
    if let Some(boxes) = &map_boxes {
        let margin_m = plan.spec.safety_m;
        // RTL altitudes are above the vehicle's home (over terrain, not the map's).
        let mut clearance = mission_rtl_clearance(boxes, mission, margin_m).map(|c| RtlClearance {
            alt_m: c.alt_m - home_up_m,
            ..c
        });
        observer.say(&rtl_line(clearance, boxes));
        if let Some(t) = &terrain {
            let ground_m = crate::home::rtl_ground_clearance(t, &route_ne(mission), margin_m)
                .map_err(|e| bad(format!("the terrain under a straight way home: {e}")))?
                - home_up_m;
            observer.say(&format!(
                "rtl        the ground under a straight way home rises to {:.1} m above the vehicle's home: only an RTL altitude of at least {ground_m:.2} m clears it with the margin",
                ground_m - margin_m
            ));
            if clearance.is_none_or(|c| c.alt_m < ground_m) {
                clearance = Some(RtlClearance {
                    alt_m: ground_m,
                    obstacle: usize::MAX,
                });
            }
        }
        // The ceiling: the request's climbing limit, else the 120 m most rules set for drones.
        let ceiling_m = request.max_alt_m.unwrap_or(RTL_CEILING_M);
        config.rtl_alt_m = set_rtl_alt(&mut gcs, info.autopilot, clearance, ceiling_m, observer);
    }
    if let Some(world) = home_world {
        gcs.set_home_router(Box::new(PlannedHome::new(world, limits, &request, &plan)));
    }
    let targets: Vec<Target> = mission.waypoints.iter().map(Target::from).collect();
    if let Some(source) = reference {
        let r = source.reference(&plan)?;
        let (start, end) = (
            r.setpoint(0.0).point_ned,
            r.setpoint(r.duration_s()).point_ned,
        );
        observer.say(&format!(
            "reference  {:.1} s from N {:.1} m, E {:.1} m, {:.1} m up to N {:.1} m, E {:.1} m, {:.1} m up, flown by setpoints with velocity and acceleration",
            r.duration_s(),
            start[0],
            start[1],
            -start[2],
            end[0],
            end[1],
            -end[2]
        ));
        // A replanned route becomes a trajectory from the one being flown, within its limits.
        let limits = plan.trajectory.as_ref().map(|t| t.trajectory.limits);
        let mut ex = match (&watcher, limits) {
            (Some(w), Some(limits)) => {
                let make = crate::trajectory::rereference(w, limits).map_err(RunError::from)?;
                observer.say("replan     a replanned route becomes a trajectory from the vehicle's motion, flown on without stopping");
                ReferenceExecutor::replanning(r, config, make)
            }
            _ => ReferenceExecutor::new(r, config),
        }
        .map_err(bad)?;
        let (log, outcome, replanned) = fly_with(&mut gcs, &mut ex, frame, sim, observer)?;
        return Ok(Flight {
            log,
            ended: Ended::Flight(outcome),
            plan,
            watcher,
            replanned,
            tracking: ex.tracking(),
        });
    }
    let Mode::Upload { fly } = o.mode else {
        let mut ex = MissionExecutor::new(&targets, config).map_err(bad)?;
        let (log, outcome, replanned) = fly_with(&mut gcs, &mut ex, frame, sim, observer)?;
        return Ok(Flight {
            log,
            ended: Ended::Flight(outcome),
            plan,
            watcher,
            replanned,
            tracking: None,
        });
    };
    // `--upload`: the plan as a mission (ArduPilot's item 0 is its home; PX4 has none), uploaded,
    // then flown in AUTO.
    let alt_m = plan.spec.alt_m;
    let pace = (plan.trajectory.as_ref()).map(|t| {
        let pace = crate::mission::trajectory_pace(&t.trajectory, mission, plan.spec.safety_m);
        observer.say(&pace_line(&t.trajectory, &pace));
        pace
    });
    let items = upload(
        &mut gcs,
        (frame, &info),
        (mission, pace.as_deref()),
        (alt_m, home_up_m),
        observer,
    )?;
    let (log, ended) = if !fly {
        observer.say("result     mission uploaded (--upload-only: not flown)");
        (Vec::new(), Ended::Uploaded)
    } else {
        let layout = MissionLayout::from(&items);
        let mut ex = AutoExecutor::new(&targets, layout, config).map_err(bad)?;
        let (log, outcome, _) = fly_with(&mut gcs, &mut ex, frame, sim, observer)?;
        (log, Ended::Flight(outcome))
    };
    Ok(Flight {
        log,
        ended,
        plan,
        watcher: None,
        replanned: Vec::new(),
        tracking: None,
    })
}

/// What a trajectory becomes in an uploaded mission, and what it loses, in one line.
fn pace_line(trajectory: &skyplan_plan::trajectory::Trajectory, pace: &[LegPace]) -> String {
    let range = |f: fn(&LegPace) -> f64| {
        let lo = pace.iter().map(f).fold(f64::INFINITY, f64::min);
        let hi = pace.iter().map(f).fold(0.0, f64::max);
        format!("{lo:.1}–{hi:.1}")
    };
    format!(
        "pace       the trajectory ({}, {:.1} s) as leg speeds {} m/s (DO_CHANGE_SPEED) and acceptance radii {} m; lost in AUTO: the curve between waypoints (the autopilot flies the checked straight legs, its own way round corners), the trajectory's clock and its acceleration and jerk profile (the autopilot's own limits), the yaw profile (one heading per leg); PX4 honours the radii, ArduCopter turns by its own WPNAV_RADIUS",
        trajectory.method.name(),
        trajectory.duration_s(),
        range(|l| l.speed_m_s),
        range(|l| l.acceptance_radius_m),
    )
}

/// Uploads `mission` (flown at `alt_m`, paced when `pace` is given) to the vehicle, telling its
/// items and the upload.
fn upload<O: RunObserver>(
    gcs: &mut GroundStation,
    (frame, info): (&LocalFrame, &VehicleInfo),
    (mission, pace): (&skyplan_mission::Mission, Option<&[LegPace]>),
    (alt_m, home_up_m): (f64, f64),
    observer: &mut O,
) -> Result<MissionPlan, RunError> {
    let mut items = crate::mission::items_for(mission, frame, info, pace).map_err(bad)?;
    // The items' altitudes are above the vehicle's home (over terrain, not the map's); an
    // ArduPilot mission's item 0 is that home.
    let home_item = usize::from(info.autopilot != Autopilot::Px4);
    for item in items.items.iter_mut().skip(home_item) {
        if matches!(item.command, ItemCommand::Waypoint | ItemCommand::Takeoff) {
            item.alt_m -= home_up_m as f32;
        }
    }
    let takeoff_m = (items.items.iter())
        .find(|i| i.command == ItemCommand::Takeoff)
        .map_or(alt_m, |i| f64::from(i.alt_m));
    let before = match (info.autopilot == Autopilot::ArduPilot, pace.is_some()) {
        (true, true) => {
            " (each after a CONDITION_YAW to its heading and a DO_CHANGE_SPEED to its leg's speed)"
        }
        (true, false) => " (each after a CONDITION_YAW to its heading)",
        (false, true) => " (each after a DO_CHANGE_SPEED to its leg's speed)",
        (false, false) => "",
    };
    observer.say(&format!(
        "mission    {} items: {}take-off to {} m, {} waypoints with headings{before}, land (MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)",
        items.items.len(),
        if info.autopilot == Autopilot::Px4 { "" } else { "home, " },
        (takeoff_m * 100.0).round() / 100.0,
        mission.waypoints.len(),
    ));
    let report = gcs
        .upload_mission(&items, UploadConfig::default())
        .map_err(RunError::from)?;
    observer.say(&format!(
        "upload     accepted: {} items in {:.3} s wall ({} requests answered, {} resends)",
        report.items, report.wall_time_s, report.requests, report.resends
    ));
    Ok(items)
}

/// Uploads the request's no-fly zones as the vehicle's fence (`mission_type` FENCE), reads it
/// back and checks it item by item, telling what is uploaded and what a fence cannot carry
/// ([`fence_from_zones`]). Zones go as the file gives them, not grown by the planning margin:
/// the autopilot applies its own `FENCE_MARGIN`. `FENCE_ENABLE` and `FENCE_TYPE` are not set.
/// Any failure is an error: the caller stops before arming.
fn upload_fence<O: RunObserver>(
    gcs: &mut GroundStation,
    request: &PlanRequest,
    mission: &skyplan_mission::Mission,
    margin_m: f64,
    observer: &mut O,
) -> Result<(), RunError> {
    let text = (request.no_fly.as_deref()).ok_or_else(|| {
        bad("--fence uploads the no-fly zones as the vehicle's fence: give them with --no-fly FILE")
    })?;
    let zones = parse_no_fly(text).map_err(|e| bad(format!("no_fly: {e}")))?;
    let alts = mission.waypoints.iter().map(|w| w.alt_m);
    let route = RouteForFence {
        points_lat_lon_deg: (mission.waypoints.iter())
            .map(|w| [w.lat_deg, w.lon_deg])
            .collect(),
        alt_range_m: [
            alts.clone().fold(f64::INFINITY, f64::min),
            alts.fold(f64::NEG_INFINITY, f64::max),
        ],
        margin_m,
    };
    let stop = |e: String| {
        RunError::Ground(GroundError::Fence(format!(
            "{e}; the flight stops before arming"
        )))
    };
    let fence = fence_from_zones(&zones, &route).map_err(|e| bad(format!("--fence: {}", e.0)))?;
    for n in &fence.notes {
        observer.say(&format!("fence      {n}"));
    }
    let items = fence_items(&fence.shapes).map_err(|e| bad(format!("--fence: {}", e.0)))?;
    observer.say(&format!(
        "fence      {} shapes as {} items (mission_type FENCE, MAV_FRAME_GLOBAL_INT), as the file gives them: the autopilot applies its own FENCE_MARGIN; FENCE_ENABLE and FENCE_TYPE are left as they are",
        fence.shapes.len(),
        items.len()
    ));
    let report = gcs
        .upload_fence(&items, UploadConfig::default())
        .map_err(|e| match e {
            GroundError::Fence(why) => stop(why),
            other => stop(other.to_string()),
        })?;
    observer.say(&format!(
        "fence      accepted and read back: {} items match the items sent, item by item ({:.3} s wall, {} resends)",
        report.items, report.wall_time_s, report.resends
    ));
    Ok(())
}

/// Waits for the vehicle (`o.wait_s` vehicle seconds), telling what is awaited, then who it is.
fn wait_for_vehicle<O: RunObserver>(
    gcs: &mut GroundStation,
    o: &FlyOptions,
    sim: Option<&InProcessSim>,
    observer: &mut O,
) -> Result<VehicleInfo, RunError> {
    let speedup = o.ground.speedup;
    let mut last = None;
    let wall = Duration::from_secs_f64(o.wait_s / speedup);
    let info = gcs.wait_for_vehicle(wall, |waiting, wall_s| {
        if last != Some(waiting) {
            last = Some(waiting);
            observer.say(&format!(
                "wait       {:7.1} s  for the vehicle's {waiting}",
                wall_s * speedup
            ));
        }
        observer.waiting(waiting, wall_s * speedup);
    })?;
    sim_notes(sim, observer);
    observer.say(&format!(
        "vehicle    {}",
        crate::mission::vehicle_line(&info)
    ));
    Ok(info)
}

/// The simulator's new notes, told as lines.
fn sim_notes<O: Observer + ?Sized>(sim: Option<&InProcessSim>, observer: &mut O) {
    for n in sim.map(InProcessSim::notes).unwrap_or_default() {
        if let Some(line) = sim_note_line(&n) {
            observer.say(&format!("sim        {line}"));
        }
    }
}

/// The front end's observer with the simulator's notes told and the replanned routes kept.
struct Story<'a, O: ?Sized> {
    inner: &'a mut O,
    sim: Option<&'a InProcessSim>,
    replanned: Vec<Vec<(f64, f64)>>,
}

impl<O: Observer + ?Sized> Observer for Story<'_, O> {
    fn say(&mut self, line: &str) {
        self.inner.say(line);
    }

    fn update(&mut self, u: &Update) {
        sim_notes(self.sim, self.inner);
        if let Update::Notes(_, notes) = u {
            for note in notes {
                if let Note::Replanned { targets, .. } = note {
                    let route = targets.iter().map(|p| (p.north_m, p.east_m)).collect();
                    self.replanned.push(route);
                }
            }
        }
        self.inner.update(u);
    }
}

/// The altitude above which `fly` warns about the RTL altitude it sets (without `max_alt_m`),
/// metres: the ceiling of the open category in the EU and of Part 107 in the US (~400 ft).
const RTL_CEILING_M: f64 = 120.0;

/// The highest obstacle the autopilot's own way home (RTL: a straight line to the launch point,
/// the route's start) would fly over from anywhere on the route.
fn mission_rtl_clearance(
    obstacles: &BoxWorld,
    mission: &skyplan_mission::Mission,
    margin_m: f64,
) -> Option<RtlClearance> {
    let route = route_ne(mission);
    rtl_clearance(obstacles, &route, *route.first()?, margin_m)
}

/// A mission's waypoints, north and east.
fn route_ne(mission: &skyplan_mission::Mission) -> Vec<[f64; 2]> {
    (mission.waypoints.iter())
        .map(|w| [w.north_m, w.east_m])
        .collect()
}

/// Over terrain: how high the vehicle's home (where it stands before take-off) is above the
/// map's home, from the DEM; said in a line.
fn vehicle_home_up_m<O: RunObserver>(
    terrain: &skyplan_map::terrain::Terrain,
    frame: &LocalFrame,
    info: &VehicleInfo,
    observer: &mut O,
) -> Result<f64, RunError> {
    let at = frame
        .ned_from_lla(Lla {
            alt_m: 0.0,
            ..info.position
        })
        .map_err(|e| bad(format!("the vehicle's position: {e}")))?;
    let up_m = (terrain.ground_m(at.north_m, at.east_m))
        .map_err(|e| bad(format!("the terrain under the vehicle: {e}")))?;
    observer.say(&format!(
        "terrain    the vehicle stands on ground {up_m:+.1} m above the map's home ground (DEM, N {:.1} m, E {:.1} m): its relative altitudes are above that ground, this run's above the map's home",
        at.north_m, at.east_m
    ));
    Ok(up_m)
}

/// Sets the autopilot's RTL altitude (ArduPilot `RTL_ALT` in centimetres with `RTL_CONE_SLOPE`
/// 0, so that it is not lowered near home; PX4 `RTL_RETURN_ALT` in metres) to clear what a
/// straight way home flies over, at least ArduCopter's default 15 m; warns above `ceiling_m`.
/// The altitude the vehicle confirmed, or `None` (said why).
fn set_rtl_alt<O: RunObserver>(
    gcs: &mut GroundStation,
    autopilot: Autopilot,
    clearance: Option<RtlClearance>,
    ceiling_m: f64,
    observer: &mut O,
) -> Option<f64> {
    let alt_m = clearance.map_or(DEFAULT_RTL_ALT_M, |c| c.alt_m.max(DEFAULT_RTL_ALT_M));
    // Rounded up to whole centimetres (ArduPilot's unit), float noise under 0.01 mm aside.
    let alt_cm = (alt_m * 100.0 - 1e-3).ceil();
    let (name, value) = match autopilot {
        Autopilot::Px4 => ("RTL_RETURN_ALT", alt_cm / 100.0),
        Autopilot::ArduPilot | Autopilot::Other => ("RTL_ALT", alt_cm),
    };
    let held = match gcs.set_param(name, value as f32) {
        Ok(held) => f64::from(held),
        Err(e) => {
            observer.say(&format!(
                "rtl        WARNING: {e}; the autopilot's own RTL may fly through what is under a straight way home"
            ));
            return None;
        }
    };
    let held_m = if name == "RTL_ALT" {
        held / 100.0
    } else {
        held
    };
    if name == "RTL_ALT" && gcs.set_param("RTL_CONE_SLOPE", 0.0).is_err() {
        observer.say(
            "rtl        RTL_CONE_SLOPE not confirmed: near home the RTL altitude may be lower",
        );
    }
    observer.say(&format!(
        "rtl        {name} set to {value:.0} (the autopilot's RTL returns at {held_m:.2} m above home)"
    ));
    if held_m > ceiling_m {
        observer.say(&format!(
            "rtl        WARNING: that is above the altitude ceiling of {ceiling_m:.0} m: the autopilot's own RTL would break it; --failsafe return flies a planned way home at the route's altitude"
        ));
    }
    Some(held_m)
}

/// What [`mission_rtl_clearance`] found, in a line.
fn rtl_line(clearance: Option<RtlClearance>, obstacles: &BoxWorld) -> String {
    match clearance {
        Some(c) => format!(
            "rtl        a straight way home (the autopilot's RTL) from this route passes over {}: only an RTL altitude of at least {:.2} m clears it with the margin; --on-interrupt return and --failsafe return fly a planned way home instead",
            match obstacles.footprints().get(c.obstacle) {
                Some(f) => format!("the building of feature {}", f.feature),
                None => format!("obstacle #{}", c.obstacle),
            },
            c.alt_m
        ),
        None => "rtl        no obstacle under a straight way home (the autopilot's RTL) from any point of this route".into(),
    }
}

type Routes = Vec<Vec<(f64, f64)>>;

/// Flies with either executor, telling as it goes.
fn fly_with<E: FlightExecutor, O: RunObserver>(
    gcs: &mut GroundStation,
    ex: &mut E,
    frame: &LocalFrame,
    sim: Option<&InProcessSim>,
    observer: &mut O,
) -> Result<(Vec<LogRow>, Option<Outcome>, Routes), RunError> {
    observer.flying(Some(ex.targets().len()));
    let mut story = Story {
        inner: &mut *observer,
        sim,
        replanned: Vec::new(),
    };
    let flown = flight::fly(gcs, ex, frame, &mut story);
    let replanned = story.replanned;
    observer.flying(None);
    let flown = flown?;
    observer.landed(flown.summary.time_s, ex.state(), ex.last_telemetry());
    Ok((flown.log, flown.outcome, replanned))
}

/// The braking a replan made at speed assumes, m/s²: ArduCopter SITL took 24.3–26.3 m to stop
/// from 9.3 m/s (1.65–1.8 m/s²); less is the safe side (the vehicle flies on to the point).
const BRAKE_ACCEL_M_S2: f64 = 1.6;

/// How a replanned route begins: where the vehicle comes to rest when it flies waypoints
/// (braking at [`BRAKE_ACCEL_M_S2`]), where it is when it flies a trajectory (which is made
/// from the vehicle's motion).
fn brake(trajectory: bool) -> Option<f64> {
    (!trajectory).then_some(BRAKE_ACCEL_M_S2)
}

/// Whether a request's planner can be replanned in flight (the 2D cell searches).
pub fn replannable(request: &PlanRequest) -> bool {
    request.planner.unwrap_or_default().is_cell_search()
}

/// The first plan and, for a 2D grid planner with a replanner, the replanner that watches it.
/// The request's `max_alt_m` is the replanner's climbing limit then (the grid planners do not
/// take it).
pub fn plan_with_replanner(
    mut session: Session,
    mut request: PlanRequest,
    replanner: Option<ReplannerKind>,
    brake_accel_m_s2: Option<f64>,
) -> Result<(Plan, Option<SharedReplanner>), PlanFailure> {
    let kind = match replanner {
        Some(kind) if replannable(&request) => kind,
        _ => return Ok((session.plan(&request)?, None)),
    };
    let options = ReplanOptions {
        replanner: kind,
        max_alt_m: request
            .max_alt_m
            .take()
            .unwrap_or(ReplanOptions::default().max_alt_m),
        brake_accel_m_s2,
        ..ReplanOptions::default()
    };
    let r = Replanner::new(session, &request, options)?;
    let plan = r.initial_plan().clone();
    Ok((plan, Some(SharedReplanner(Arc::new(Mutex::new(r))))))
}

/// `count` hidden buildings on or near the route planned for `request` (seeded).
pub fn hidden_random(
    world: &World,
    request: &PlanRequest,
    count: usize,
    seed: u64,
) -> Result<Vec<ObstacleBox>, RunError> {
    let not_obstacles = || {
        bad("--hidden-random needs a map of obstacles (colliders or footprints), not a fixed grid")
    };
    if world.colliders().is_none() && world.footprints().is_none() {
        return Err(not_obstacles());
    }
    let mut plain = request.clone();
    plain.max_alt_m = None;
    let plan = Session::new(world.clone()).plan(&plain)?;
    let grid = plan
        .grid
        .ok_or_else(|| bad("--hidden-random needs a 2D grid planner's route"))?;
    let spec = HiddenSpec {
        count,
        seed,
        route_ne: plan.waypoints.iter().map(|w| [w[0], w[1]]).collect(),
        start_ne: [plan.start.north_m, plan.start.east_m],
        goal_ne: [plan.goal.north_m, plan.goal.east_m],
        alt_m: grid.alt_m,
        safety_m: grid.safety_m,
        cell_m: grid.cell_m,
        model: plan.spec.move_model,
    };
    match (world.colliders(), world.footprints()) {
        (Some(map), _) => place_hidden(map, &spec).map_err(bad),
        (None, Some(f)) => {
            skyplan_replan::hidden::place_hidden_among_footprints(f, &spec).map_err(bad)
        }
        (None, None) => Err(not_obstacles()),
    }
}

/// Why a flown mission does not count as done ([`verdict`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Unfinished {
    /// The simulated vehicle flew into the ground (over terrain) outside a landing.
    #[error(
        "the simulated vehicle flew into the ground at {time_s:.1} s (N {north_m:.1} m, E {east_m:.1} m, {alt_m:.1} m above home)"
    )]
    StruckGround {
        /// When, simulated seconds.
        time_s: f64,
        /// Where, metres north of the map's home.
        north_m: f64,
        /// Where, metres east of the map's home.
        east_m: f64,
        /// Its altitude above the map's home, metres.
        alt_m: f64,
    },
    /// Every waypoint was reached, but the simulated vehicle hit an obstacle on the way.
    #[error(
        "the flight completed but the simulated vehicle hit obstacle #{box_index} at {time_s:.1} s"
    )]
    Collided {
        /// The obstacle's index in the simulated world.
        box_index: usize,
        /// When, simulated seconds.
        time_s: f64,
    },
    /// Every waypoint was reached without a collision, but the vehicle flew closer to an
    /// obstacle than half the safety margin: it entered the obstacles grown by half the margin.
    #[error(
        "the flight completed but the vehicle came within {clearance_m:.2} m of {obstacle} at {time_s:.1} s, closer than half ({half_m} m) the route's {margin_m} m safety margin: not done", half_m = margin_m / 2.0
    )]
    TooClose {
        /// The closest approach, metres.
        clearance_m: f64,
        /// The safety margin the route was planned with, metres.
        margin_m: f64,
        /// The obstacle: a map obstacle or a hidden building, by its number.
        obstacle: String,
        /// When, simulated seconds.
        time_s: f64,
    },
    /// Every waypoint was reached, but the vehicle flew closer to a no-fly zone than half the
    /// safety margin (or into it, or out of an inclusion boundary).
    #[error(
        "the flight completed but the vehicle came within {clearance_m:.2} m of no-fly zone {feature} at {time_s:.1} s, closer than half ({half_m} m) the route's {margin_m} m safety margin: not done", half_m = margin_m / 2.0
    )]
    NearZone {
        /// The zone's feature index in its file.
        feature: usize,
        /// The closest approach, metres (0: inside an exclusion zone, or outside an inclusion
        /// boundary).
        clearance_m: f64,
        /// The safety margin the route was planned with, metres.
        margin_m: f64,
        /// When, seconds of the flight log.
        time_s: f64,
    },
    /// No route in the true world: the "no path" of planning.
    #[error("flight failed: {0}")]
    NoRoute(skyplan_flight::executor::Failure),
    /// The flight failed otherwise (link, timeout, vehicle, interrupt).
    #[error("flight failed: {0}")]
    Failed(skyplan_flight::executor::Failure),
    /// The flight was aborted and the vehicle did not land in time.
    #[error("flight aborted and the vehicle did not land in time: check it")]
    NotLanded,
    /// The vehicle landed at the end of its reference, but strayed from its path by more than
    /// half the route's safety margin: the trajectory is proven free with the margin, the
    /// vehicle flying that far off it is not (early or late along it does not count here).
    #[error(
        "the flight completed but the vehicle strayed up to {max_error_m:.2} m from its trajectory's path, more than half ({half_m} m) the route's {margin_m} m safety margin: not done (fly slower: lower --max-speed-m-s and --max-accel-m-s2, or check the vehicle's tuning)", half_m = margin_m / 2.0
    )]
    OffTrack {
        /// The largest distance between the vehicle and its trajectory's path (the closest
        /// setpoint within a few seconds of its own: being early or late is not straying),
        /// metres.
        max_error_m: f64,
        /// The safety margin the route was planned with, metres.
        margin_m: f64,
    },
}

/// The share of ArduCopter's own GUIDED limits (`WPNAV_SPEED`, `WPNAV_ACCEL`) a trajectory
/// may use. ArduCopter shapes every GUIDED target through its position controller's limits: a
/// trajectory at its speed limit or above its acceleration limit is smoothed away from its
/// path in every turn (against ArduCopter SITL at 10 m/s and 4 m/s², its defaults being
/// 10 m/s and 2.5 m/s²: 58 m off the path; at 8 m/s and 2 m/s²: 0.77 m).
pub const VEHICLE_LIMIT_SHARE: f64 = 0.8;

/// A trajectory's speed and acceleration limits within [`VEHICLE_LIMIT_SHARE`] of the
/// vehicle's `WPNAV_SPEED` (cm/s) and `WPNAV_ACCEL` (cm/s²), where known, and the line that
/// says what was lowered (`None` when nothing was).
///
/// ```
/// use skyplan_flyer::runner::vehicle_caps;
/// let (speed, accel, line) = vehicle_caps(10.0, 4.0, Some(1000.0), Some(250.0));
/// assert_eq!((speed, accel), (8.0, 2.0));
/// assert!(line.unwrap().contains("WPNAV_SPEED 10 m/s"));
/// assert_eq!(vehicle_caps(6.0, 1.5, Some(1000.0), Some(250.0)), (6.0, 1.5, None));
/// ```
pub fn vehicle_caps(
    speed_m_s: f64,
    accel_m_s2: f64,
    wpnav_speed_cm_s: Option<f32>,
    wpnav_accel_cm_s2: Option<f32>,
) -> (f64, f64, Option<String>) {
    let cap = |v: Option<f32>| {
        v.map(f64::from)
            .filter(|v| v.is_finite() && *v > 0.0)
            .map(|v| v / 100.0)
    };
    let mut said = Vec::new();
    let mut speed = speed_m_s;
    let mut accel = accel_m_s2;
    if let Some(w) = cap(wpnav_speed_cm_s)
        && speed > VEHICLE_LIMIT_SHARE * w
    {
        speed = VEHICLE_LIMIT_SHARE * w;
        said.push(format!(
            "max speed {speed_m_s} → {speed:.2} m/s ({:.0} % of its WPNAV_SPEED {w} m/s)",
            VEHICLE_LIMIT_SHARE * 100.0
        ));
    }
    if let Some(w) = cap(wpnav_accel_cm_s2)
        && accel > VEHICLE_LIMIT_SHARE * w
    {
        accel = VEHICLE_LIMIT_SHARE * w;
        said.push(format!(
            "max acceleration {accel_m_s2} → {accel:.2} m/s² ({:.0} % of its WPNAV_ACCEL {w} m/s²)",
            VEHICLE_LIMIT_SHARE * 100.0
        ));
    }
    let line = (!said.is_empty()).then(|| {
        format!(
            "limits     the trajectory within the vehicle's own GUIDED limits (it smooths faster targets off their path): {}",
            said.join(", ")
        )
    });
    (speed, accel, line)
}

/// Reads ArduPilot's `WPNAV_SPEED` and `WPNAV_ACCEL` and lowers the request's trajectory limits
/// to [`vehicle_caps`], saying so; a vehicle that does not answer keeps them, with a line.
fn cap_to_vehicle<O: RunObserver>(
    gcs: &mut GroundStation,
    request: &mut PlanRequest,
    observer: &mut O,
) {
    let limits = request.trajectory_limits();
    let speed = gcs.get_param("WPNAV_SPEED", 2, 0.5).ok();
    let accel = gcs.get_param("WPNAV_ACCEL", 2, 0.5).ok();
    if speed.is_none() && accel.is_none() {
        observer.say("limits     the vehicle did not tell its WPNAV_SPEED and WPNAV_ACCEL: the trajectory keeps its limits (fly within about 80 % of the vehicle's own)");
        return;
    }
    let (s, a, line) = vehicle_caps(limits.max_speed_m_s, limits.max_accel_m_s2, speed, accel);
    if let Some(line) = line {
        request.max_speed_m_s = Some(s);
        request.max_accel_m_s2 = Some(a);
        observer.say(&line);
    }
}

/// The safety margin a plan was made with, metres (its resolved spec; every planner has one).
pub fn plan_margin_m(plan: &Plan) -> Option<f64> {
    Some(plan.spec.safety_m)
}

/// A flight's verdict from its outcome ([`Ended::Flight`]) and, on the simulator, its track
/// report judged against the route's safety margin `margin_m`: done only when it landed and
/// disarmed with every waypoint reached, no collision, and never closer to an obstacle (the map's
/// or a hidden one) than half the margin.
///
/// ```
/// use skyplan_flight::executor::Outcome;
/// use skyplan_flyer::runner::{Unfinished, verdict};
///
/// assert_eq!(verdict(Some(Outcome::Completed), None, Some(5.0), None, None), Ok(()));
/// assert_eq!(verdict(None, None, Some(5.0), None, None), Err(Unfinished::NotLanded));
/// ```
pub fn verdict(
    outcome: Option<Outcome>,
    report: Option<&skyplan_link::vehicle::SimReport>,
    margin_m: Option<f64>,
    tracking: Option<&TrackingReport>,
    zone: Option<&crate::zones::ZonePass>,
) -> Result<(), Unfinished> {
    use skyplan_flight::executor::Failure;
    if let Some(g) = report.and_then(|r| r.ground_strike) {
        let [north_m, east_m, down_m] = g.position_ned_m;
        return Err(Unfinished::StruckGround {
            time_s: g.time_s,
            north_m,
            east_m,
            alt_m: -down_m,
        });
    }
    match outcome {
        Some(Outcome::Completed) => {
            if let (Some(z), Some(margin_m)) = (zone, margin_m)
                && z.clearance_m < 0.5 * margin_m
            {
                return Err(Unfinished::NearZone {
                    feature: z.feature,
                    clearance_m: z.clearance_m,
                    margin_m,
                    time_s: z.time_s,
                });
            }
            if let (Some(t), Some(margin_m)) = (tracking, margin_m)
                && t.max_path_error_m > 0.5 * margin_m
            {
                return Err(Unfinished::OffTrack {
                    max_error_m: t.max_path_error_m,
                    margin_m,
                });
            }
            let track = report.map(|r| &r.track);
            if let Some(c) = track.and_then(|t| t.collision()) {
                return Err(Unfinished::Collided {
                    box_index: c.box_index,
                    time_s: c.time_s,
                });
            }
            match (report, track.and_then(|t| t.closest()), margin_m) {
                (Some(r), Some(c), Some(margin_m)) if c.clearance_m < 0.5 * margin_m => {
                    Err(Unfinished::TooClose {
                        clearance_m: c.clearance_m,
                        margin_m,
                        obstacle: flight::obstacle_name(r, c.box_index),
                        time_s: c.time_s,
                    })
                }
                _ => Ok(()),
            }
        }
        Some(Outcome::Failed(f @ Failure::NoRoute { .. })) => Err(Unfinished::NoRoute(f)),
        Some(Outcome::Failed(f)) => Err(Unfinished::Failed(f)),
        None => Err(Unfinished::NotLanded),
    }
}

/// The replanner's account: replans, latencies, expansions, learned cells.
pub fn summary_line(kind: &str, stats: &ReplanStats, learned: usize) -> String {
    format!("replans    {}", stats.account(kind, learned))
}

/// Flies one `bench --replan` scenario on the in-process simulator: the first route planned
/// with `replanner` watching, the hidden buildings in the simulated world.
pub fn fly_scenario(
    world: &World,
    scenario: &Scenario,
    replanner: Option<ReplannerKind>,
    speedup: f64,
) -> Result<FlightResult, RunError> {
    let (Some(map), Some(frame)) = (world.colliders(), world.frame()) else {
        return Err(bad("bench --replan needs a colliders map"));
    };
    let session = Session::new(world.clone());
    let (plan, watcher) =
        plan_with_replanner(session, scenario.request.clone(), replanner, brake(false))?;
    let start = frame
        .lla_from_ned(Ned {
            north_m: plan.start.north_m,
            east_m: plan.start.east_m,
            down_m: 0.0,
        })
        .map_err(|e| bad(format!("start: {e}")))?;
    let config = SimServerConfig {
        speedup,
        map_home: Some(frame.home()),
        hidden: scenario.hidden.clone(),
        ..SimServerConfig::at(start)
    };
    let sim = InProcessSim::start(config, BoxWorld::new(&map.boxes))?;
    let ground = GroundConfig {
        speedup,
        timeout_s: Some(1200.0 / speedup),
        ..GroundConfig::default()
    };
    let mut gcs = GroundStation::connect(&sim.address(), ground)?;
    gcs.wait_for_vehicle(Duration::from_secs_f64(60.0 / speedup), |_, _| {})?;
    if let Some(w) = &watcher {
        gcs.set_watcher(Box::new(w.clone()));
    }
    let targets: Vec<_> = plan.waypoints.iter().copied().map(Target::from).collect();
    let mut ex = MissionExecutor::new(&targets, ExecutorConfig::default()).map_err(bad)?;
    let flown = flight::fly(&mut gcs, &mut ex, frame, &mut Quiet);
    drop(gcs);
    let (report, _) = sim.finish();
    flown?;
    let report =
        report.ok_or_else(|| RunError::Runtime("the simulator stopped unexpectedly".into()))?;
    let at_goal = ex
        .last_telemetry()
        .is_some_and(|t| (t.north_m - plan.goal.north_m).hypot(t.east_m - plan.goal.east_m) < 3.0);
    let stats = watcher
        .and_then(|w| w.0.lock().ok().map(|r| r.stats().clone()))
        .unwrap_or_default();
    Ok(FlightResult {
        success: matches!(ex.outcome(), Some(Outcome::Completed)) && at_goal,
        collisions: report.track.colliding_samples(),
        stats,
        flown_m: report.distance_m,
        optimum_m: scenario.optimum_m,
    })
}

/// `skyplan bench --replan N`: N seeded flights per replanner (D\* Lite, JPS from scratch), one
/// row each, as a table; `progress` hears (replanner, flight, of) before each flight.
pub fn replan_bench(
    world: &World,
    spec: &ScenarioSpec,
    speedup: f64,
    mut progress: impl FnMut(&str, usize, usize),
) -> Result<String, RunError> {
    let scenarios = skyplan_replan::bench::scenarios(world, spec).map_err(bad)?;
    let mut rows = Vec::new();
    for kind in [ReplannerKind::DStarLite, ReplannerKind::Scratch] {
        let mut results = Vec::new();
        for (k, s) in scenarios.iter().enumerate() {
            progress(kind.name(), k + 1, scenarios.len());
            results.push(fly_scenario(world, s, Some(kind), speedup)?);
        }
        rows.push(skyplan_replan::bench::summarise(kind, &results));
    }
    Ok(skyplan_replan::bench::format_rows(&rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_flight::executor::Failure;

    #[test]
    fn verdict_tells_no_route_from_other_failures_and_names_them() {
        let no_route = Failure::NoRoute {
            reason: "the goal is walled in".into(),
        };
        let got = verdict(
            Some(Outcome::Failed(no_route.clone())),
            None,
            Some(5.0),
            None,
            None,
        );
        assert_eq!(got, Err(Unfinished::NoRoute(no_route)));
        let lost = Failure::LinkLost {
            state: FlightState::Waypoint,
            silent_s: 6.0,
        };
        let got = verdict(
            Some(Outcome::Failed(lost.clone())),
            None,
            Some(5.0),
            None,
            None,
        )
        .unwrap_err();
        assert_eq!(got.to_string(), format!("flight failed: {lost}"));
        assert_eq!(
            verdict(Some(Outcome::Completed), None, Some(5.0), None, None),
            Ok(())
        );
        assert!(
            verdict(None, None, Some(5.0), None, None)
                .unwrap_err()
                .to_string()
                .contains("did not land in time")
        );
    }

    /// A trajectory flight that landed fails once the vehicle strayed from its path by more
    /// than half the margin (51 m seen against ArduCopter SITL at 10 m/s), not before, however
    /// early or late it was along it.
    #[test]
    fn a_reference_flight_far_off_its_trajectory_is_not_done() {
        let tracking = |max_path_error_m| TrackingReport {
            duration_s: 113.2,
            started_s: Some(0.0),
            flown_s: Some(114.4),
            max_tracking_error_m: 55.61,
            max_path_error_m,
            samples: 500,
            setpoints_sent: 1200,
            switches: 0,
            slowest_switch_ms: 0.0,
            by_waypoints_from_s: None,
        };
        let done = Some(Outcome::Completed);
        assert_eq!(
            verdict(done.clone(), None, Some(5.0), Some(&tracking(2.4)), None),
            Ok(())
        );
        let got = verdict(done, None, Some(5.0), Some(&tracking(51.05)), None).unwrap_err();
        assert_eq!(
            got,
            Unfinished::OffTrack {
                max_error_m: 51.05,
                margin_m: 5.0
            }
        );
        let text = got.to_string();
        assert!(
            text.contains("51.05 m") && text.contains("2.5 m") && text.contains("--max-speed-m-s"),
            "{text}"
        );
    }

    /// A simulator's report of a track flown at 5 m altitude from N 0 to N 40 along E 0, past
    /// a 2 m × 2 m tower centred at E `tower_east_m`.
    fn report_past_tower(tower_east_m: f64) -> skyplan_link::vehicle::SimReport {
        use skyplan_flight::collision::{BoxWorld, TrackCheck};
        use skyplan_flight::sim::{SimConfig, SimVehicle};
        let tower = ObstacleBox {
            north_m: 20.0,
            east_m: tower_east_m,
            up_m: 15.0,
            half_north_m: 1.0,
            half_east_m: 1.0,
            half_up_m: 15.0,
        };
        let world = BoxWorld::new(&[tower]);
        let mut track = TrackCheck::default();
        for k in 0..=40 {
            track.add(&world, f64::from(k), [f64::from(k), 0.0, -5.0]);
        }
        skyplan_link::vehicle::SimReport {
            sim_time_s: 40.0,
            wall_time_s: 1.0,
            final_state: SimVehicle::new(SimConfig::default()).state(),
            track,
            max_alt_m: 5.0,
            distance_m: 40.0,
            map_boxes: 1,
            map_features: Vec::new(),
            hidden_boxes: 0,
            ground_strike: None,
        }
    }

    #[test]
    fn a_completed_flight_closer_than_half_the_margin_is_not_done() {
        // The tower's face is 2 m from the track: inside half of a 5 m margin, outside half of 3 m.
        let report = report_past_tower(3.0);
        let got = verdict(
            Some(Outcome::Completed),
            Some(&report),
            Some(5.0),
            None,
            None,
        );
        let Err(Unfinished::TooClose {
            clearance_m,
            margin_m,
            time_s,
            ..
        }) = &got
        else {
            panic!("{got:?}");
        };
        assert!(
            (clearance_m - 2.0).abs() < 1e-9 && *margin_m == 5.0,
            "{got:?}"
        );
        assert!((19.0..=21.0).contains(time_s), "{got:?}");
        let text = got.unwrap_err().to_string();
        assert!(
            text.contains("within 2.00 m of map obstacle #0")
                && text.contains("closer than half (2.5 m) the route's 5 m safety margin"),
            "{text}"
        );
        assert_eq!(
            verdict(
                Some(Outcome::Completed),
                Some(&report),
                Some(3.0),
                None,
                None
            ),
            Ok(())
        );
        // Without a margin to judge by, only collisions count.
        assert_eq!(
            verdict(Some(Outcome::Completed), Some(&report), None, None, None),
            Ok(())
        );
        // A collision is told as one, whatever the margin.
        let hit = report_past_tower(0.5);
        assert!(matches!(
            verdict(Some(Outcome::Completed), Some(&hit), Some(5.0), None, None),
            Err(Unfinished::Collided { box_index: 0, .. })
        ));
    }
}
