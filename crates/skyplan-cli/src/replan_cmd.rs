//! Replanning in flight, the CLI's side: `fly --replanner`, `fly --hidden-random`, the flight
//! picture, and `bench --replan` (seeded flights into hidden buildings, one row per replanner).

use crate::exit::{Classify, Kind, Result, bad_input, runtime};
use skyplan_flight::collision::BoxWorld;
use skyplan_flight::executor::{ExecutorConfig, MissionExecutor, Outcome};
use skyplan_frames::Ned;
use skyplan_link::flight::{self, Quiet};
use skyplan_link::ground::{GroundConfig, GroundStation};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::vehicle::SimServerConfig;
use skyplan_map::colliders::ObstacleBox;
use skyplan_plan::{Family, Plan, PlanRequest, Session, World};
use skyplan_replan::bench::{FlightResult, ScenarioSpec, SharedReplanner};
use skyplan_replan::hidden::{HiddenSpec, place_hidden};
use skyplan_replan::{ReplanOptions, ReplanStats, Replanner, ReplannerKind};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// `--replanner`: which search replans when the sensor finds the route blocked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ReplannerArg {
    /// D* Lite: one search kept and repaired across replans.
    DstarLite,
    /// JPS from scratch on the known and learned grid at every replan.
    Scratch,
    /// Never replan: fly the first route whatever the sensor sees.
    Off,
}

impl ReplannerArg {
    fn kind(self) -> Option<ReplannerKind> {
        match self {
            ReplannerArg::DstarLite => Some(ReplannerKind::DStarLite),
            ReplannerArg::Scratch => Some(ReplannerKind::Scratch),
            ReplannerArg::Off => None,
        }
    }
}

/// Whether a request's planner can be replanned in flight (the 2D grid planners).
pub fn replannable(request: &PlanRequest) -> bool {
    matches!(
        request.planner.unwrap_or_default().info().family,
        Family::Grid(_)
    )
}

/// The first plan and, for a 2D grid planner with a replanner, the replanner that watches it.
/// `--max-alt-m` is the replanner's climbing limit then (the grid planners do not take it).
pub fn plan_with_replanner(
    session: Session,
    mut request: PlanRequest,
    replanner: ReplannerArg,
) -> Result<(Plan, Option<SharedReplanner>)> {
    let kind = match replanner.kind() {
        Some(kind) if replannable(&request) => kind,
        _ => {
            let mut session = session;
            return Ok((session.plan(&request)?, None));
        }
    };
    let options = ReplanOptions {
        replanner: kind,
        max_alt_m: request
            .max_alt_m
            .take()
            .unwrap_or(ReplanOptions::default().max_alt_m),
        ..ReplanOptions::default()
    };
    let r = Replanner::new(session, &request, options)?;
    let plan = r.initial_plan().clone();
    Ok((plan, Some(SharedReplanner(Arc::new(Mutex::new(r))))))
}

/// `--hidden-random N`: N buildings on or near the route planned for `request` (seeded).
pub fn hidden_random(
    world: &World,
    request: &PlanRequest,
    count: usize,
    seed: u64,
) -> Result<Vec<ObstacleBox>> {
    let map = world
        .colliders()
        .ok_or_else(|| bad_input("--hidden-random needs a colliders map"))?;
    let mut plain = request.clone();
    plain.max_alt_m = None;
    let plan = Session::new(world.clone()).plan(&plain)?;
    let grid = plan
        .grid
        .ok_or_else(|| bad_input("--hidden-random needs a 2D grid planner's route"))?;
    let spec = HiddenSpec {
        count,
        seed,
        route_ne: plan.waypoints.iter().map(|w| [w[0], w[1]]).collect(),
        start_ne: [plan.start.north_m, plan.start.east_m],
        goal_ne: [plan.goal.north_m, plan.goal.east_m],
        alt_m: grid.alt_m,
        safety_m: grid.safety_m,
        cell_m: grid.cell_m,
        model: skyplan_search::MoveModel::Octile,
    };
    place_hidden(map, &spec).map_err(bad_input)
}

/// The replanner's account: replans, latencies, expansions, learned cells.
pub fn summary_line(kind: &str, stats: &ReplanStats, learned: usize) -> String {
    format!("replans    {}", stats.account(kind, learned))
}

/// Flies one `bench --replan` scenario on the in-process simulator: the first route planned
/// with `kind`'s replanner watching, the hidden buildings in the simulated world.
pub fn fly_scenario(
    world: &World,
    scenario: &skyplan_replan::bench::Scenario,
    replanner: ReplannerArg,
    speedup: f64,
) -> Result<FlightResult> {
    let (Some(map), Some(frame)) = (world.colliders(), world.frame()) else {
        return Err(bad_input("bench --replan needs a colliders map"));
    };
    let (plan, watcher) = plan_with_replanner(
        Session::new(world.clone()),
        scenario.request.clone(),
        replanner,
    )?;
    let start = frame
        .lla_from_ned(Ned {
            north_m: plan.start.north_m,
            east_m: plan.start.east_m,
            down_m: 0.0,
        })
        .map_err(|e| bad_input(format!("start: {e}")))?;
    let config = SimServerConfig {
        speedup,
        map_home: Some(frame.home()),
        hidden: scenario.hidden.clone(),
        ..SimServerConfig::at(start)
    };
    let sim = InProcessSim::start(config, BoxWorld::new(&map.boxes)).or_exit(Kind::Runtime)?;
    let ground = GroundConfig {
        speedup,
        timeout_s: Some(1200.0 / speedup),
        ..GroundConfig::default()
    };
    let mut gcs = GroundStation::connect(&sim.address(), ground).or_exit(Kind::Runtime)?;
    gcs.wait_for_vehicle(Duration::from_secs_f64(60.0 / speedup), |_, _| {})
        .or_exit(Kind::Runtime)?;
    if let Some(w) = &watcher {
        gcs.set_watcher(Box::new(w.clone()));
    }
    let targets: Vec<_> = plan
        .waypoints
        .iter()
        .map(|w| skyplan_flight::executor::Target {
            north_m: w[0],
            east_m: w[1],
            alt_m: w[2],
            heading_rad: w[3],
        })
        .collect();
    let mut ex = MissionExecutor::new(&targets, ExecutorConfig::default()).map_err(bad_input)?;
    let flown = flight::fly(&mut gcs, &mut ex, frame, &mut Quiet).or_exit(Kind::Runtime);
    drop(gcs);
    let (report, _) = sim.finish();
    flown?;
    let report = report.ok_or_else(|| runtime("the simulator stopped unexpectedly"))?;
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

/// `skyplan bench --replan N`: N seeded flights per replanner, one row each.
pub fn bench(world: &World, spec: &ScenarioSpec, speedup: f64) -> Result<String> {
    let scenarios = skyplan_replan::bench::scenarios(world, spec).map_err(bad_input)?;
    let mut rows = Vec::new();
    for arg in [ReplannerArg::DstarLite, ReplannerArg::Scratch] {
        let mut results = Vec::new();
        for (k, s) in scenarios.iter().enumerate() {
            eprint!(
                "\rbench --replan: {} flight {}/{}   ",
                arg.kind().map_or("off", ReplannerKind::name),
                k + 1,
                scenarios.len()
            );
            results.push(fly_scenario(world, s, arg, speedup)?);
        }
        if let Some(kind) = arg.kind() {
            rows.push(skyplan_replan::bench::summarise(kind, &results));
        }
    }
    eprintln!();
    Ok(skyplan_replan::bench::format_rows(&rows))
}

/// `fly --plot`: the first plan's picture with what the flight added — hidden buildings, the
/// cells the vehicle learned, every replanned route and the flown track.
pub fn flight_picture(
    world: &World,
    kind: &crate::picture::PictureKind,
    seen: &crate::fly_cmd::Seen,
    hidden: &[ObstacleBox],
    log: &[skyplan_link::ground::LogRow],
) -> Result<Vec<u8>> {
    let learned: Vec<(f64, f64)> = seen
        .watcher
        .as_ref()
        .and_then(|w| w.0.lock().ok().map(|r| r.learned_points_ne()))
        .unwrap_or_default()
        .into_iter()
        .flat_map(|(_, points)| points.into_iter().map(|[n, e]| (n, e)))
        .collect();
    let track: Vec<(f64, f64)> = log.iter().map(|r| (r.north_m, r.east_m)).collect();
    let layers = skyplan_plot::FlightLayers {
        hidden,
        learned_ne: &learned,
        replanned_ne: &seen.replanned,
        track_ne: &track,
    };
    crate::picture::render(world, &seen.plan, kind, Some(&layers))
}
