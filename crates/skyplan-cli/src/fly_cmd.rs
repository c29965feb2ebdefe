//! `skyplan fly`: connect (or start the simulator), wait for the vehicle, plan from where it is,
//! fly the FCND state machine, write the flight log, exit 0 only after landing and disarming with
//! every waypoint reached.

use crate::args::FlyArgs;
use crate::exit::runtime;
use crate::exit::{Failure, Kind, Result, bad_input};
use crate::files::{Target, write_atomic, write_target};
use crate::picture::PictureKind;
use crate::replan_cmd::flight_picture;
use skyplan_flight::collision::BoxWorld;
use skyplan_flight::executor::{ExecutorConfig, FlightState, Note, Outcome, Telemetry};
use skyplan_flyer::flight::{self, Observer, reached_index};
use skyplan_flyer::runner::{self, Ended, FlyOptions, Mode, RunObserver, Unfinished};
use skyplan_flyer::words::{log_csv, progress_message, sim_note_line};
use skyplan_frames::LocalFrame;
use skyplan_link::ground::{GroundConfig, Update, Waiting};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::vehicle::{SimReport, SimServerConfig};
use skyplan_link::{Address, Role};
use skyplan_map::colliders::{GeodeticHome, ObstacleBox};
use skyplan_plan::FailureKind;
use skyplan_plan::Plan;
use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// The Ctrl-C handler's view: `in_flight` while the executor flies (a Ctrl-C then sets
/// `interrupt`, which the ground station turns into `--on-interrupt`: land, rtl or hold; a second one exits at
/// once); outside the flight a Ctrl-C exits at once, nothing having been commanded to fly.
#[derive(Clone)]
struct CtrlC {
    interrupt: Arc<AtomicBool>,
    in_flight: Arc<AtomicBool>,
}

impl CtrlC {
    fn install() -> Self {
        let c = CtrlC {
            interrupt: Arc::new(AtomicBool::new(false)),
            in_flight: Arc::new(AtomicBool::new(false)),
        };
        let h = c.clone();
        // Without a handler (another one installed first), Ctrl-C kills the process as usual.
        let _ = ctrlc::set_handler(move || {
            if !h.in_flight.load(Ordering::SeqCst) {
                eprintln!(
                    "error: interrupted (Ctrl-C) outside the flight: nothing was commanded to fly"
                );
                std::process::exit(130);
            }
            if h.interrupt.swap(true, Ordering::SeqCst) {
                eprintln!(
                    "error: second Ctrl-C: exiting without waiting for the vehicle, which was told to stop: check it"
                );
                std::process::exit(130);
            }
        });
        c
    }
}

/// Stops the simulator, prints its last notes, returns its report.
fn finish_sim(sim: InProcessSim) -> Option<SimReport> {
    let (report, notes) = sim.finish();
    for n in notes.iter().filter_map(sim_note_line) {
        println!("sim        {n}");
    }
    report
}

pub fn run(args: FlyArgs) -> Result<()> {
    let t0 = Instant::now();
    let ctrl_c = CtrlC::install();
    let options = fly_options(&args);
    let crate::world_load::Resolved {
        world,
        limits,
        request,
        config,
    } = crate::world_load::resolve(&args.route)?;
    if world.terrain().is_some() && (args.hidden.is_some() || args.hidden_random > 0) {
        return Err(bad_input(
            "--hidden and --hidden-random over terrain: not yet. Going around what the map lacks is the replanner's work, and it keeps one altitude; over terrain fly flies its planned route, which follows the ground",
        ));
    }
    // Said before connecting: the planning that would find it waits for the vehicle first.
    if request.goal_ne.is_none()
        && request.goal_lla.is_none()
        && world.default_endpoints_ne().1.is_none()
    {
        return Err(bad_input(format!(
            "missing goal: give --goal-ne N,E (metres north,east of the map's origin; {}) or --goal-lla LAT,LON",
            world.bounds_ne(1.0)
        )));
    }
    if request.departure.is_some() {
        return Err(bad_input(
            "--departure: fly takes off now and keeps out of every no-fly zone whatever its time window (a replanned flight's arrival is not known in advance); --departure is for plan and the API",
        ));
    }
    if args.fence && request.no_fly.is_none() {
        return Err(bad_input(
            "--fence uploads the no-fly zones as the vehicle's fence: give them with --no-fly FILE (or no_fly in --config)",
        ));
    }
    let format = args.format.as_deref().or(config.text.format.as_deref());
    let out = (args.out.clone().or(config.path(&config.text.out)))
        .map(|path| crate::plan_cmd::output_file(&path, format).map(|(t, f)| (path, t, f)))
        .transpose()?;
    let (Some(obstacles), Some(frame)) = (runner::map_obstacles(&world)?, world.frame().cloned())
    else {
        return Err(bad_input(format!(
            "fly: {} is not a map of obstacles; flying needs the map's buildings and geodetic home (an FCND colliders map --map FILE.csv, footprints --map FILE.geojson or .osm, or the bundled map)",
            world.name()
        )));
    };
    let home = frame.home();
    let plot = (args.plot.as_ref())
        .map(|path| {
            // A flight is drawn on the map whatever its planner (no heat map): a scene's kind.
            let kind = crate::picture::kind_for(path, skyplan_plan::PlannerId::Jps)?;
            Ok::<_, Failure>((crate::files::output_target("--plot", path)?, kind))
        })
        .transpose()?;
    if let Some(path) = &args.log {
        crate::files::output_target("--log", path)?;
    }
    if args.sim {
        check_ends(&world, &limits, &request)?;
    }
    let home = GeodeticHome {
        lat_deg: home.lat_deg,
        lon_deg: home.lon_deg,
    };
    let hidden = hidden_obstacles(&args, &world, &request, &home)?;
    println!(
        "map        {}: {} obstacles, home lat {:.6}, lon {:.6}",
        world.name(),
        obstacles.len(),
        home.lat_deg,
        home.lon_deg
    );

    let (address, sim) = vehicle(&args, (obstacles, &world), &frame, &request, &hidden)?;
    let zones = crate::picture::zones_of(&world, &request);
    let drawing = plot.map(|plot| (world.clone(), plot, zones.clone()));
    let bar = progress_bar(0);
    bar.set_prefix("WAITING");
    let mut terminal = Terminal {
        live: crate::live::Live::start(&world, args.view.as_deref(), args.record.as_deref())?,
        bar,
        wait_s: args.wait_s,
        out,
        in_flight: Arc::clone(&ctrl_c.in_flight),
        request: request.clone(),
    };
    let interrupt = Arc::clone(&ctrl_c.interrupt);
    // With --upload, the trajectory paces the uploaded mission (leg speeds, acceptance radii)
    // instead of being streamed as setpoints.
    let uploads = args.upload || args.upload_only;
    let reference =
        (request.trajectory == Some(true) && !uploads).then(skyplan_flyer::trajectory::from_plan);
    let ground = world.terrain_shared().map(|t| (t, request.alt_agl_m));
    let planned = (world, limits, request);
    let result = runner::fly_mission_with(
        &address,
        &frame,
        planned,
        &options,
        reference.as_ref(),
        sim.as_ref(),
        interrupt,
        &mut terminal,
    );
    if result.is_ok() {
        terminal.live.finish()?;
    }
    let report = sim.and_then(finish_sim);
    let flight = result?;
    conclude(
        &args,
        &flight,
        drawing,
        (&hidden, &zones, ground),
        report.as_ref(),
        t0,
    )
}

/// With the built-in simulator the start is known, so a 2D route that cannot begin or end where
/// asked (a goal in a building or its margin, an end off the map) is refused before a vehicle is
/// started, by planning the same ends on the same grid with JPS (milliseconds, whatever
/// preprocessing the chosen planner needs). 3D planners check their ends after connecting.
fn check_ends(
    world: &skyplan_plan::World,
    limits: &skyplan_plan::Limits,
    request: &skyplan_plan::PlanRequest,
) -> Result<()> {
    if request.planner.unwrap_or_default().info().dims != 2 {
        return Ok(());
    }
    // The grid's options only: the planner's own (a field, a cost map, a time limit) and the
    // replanner's climbing limit are not JPS's.
    let probe = skyplan_plan::PlanRequest {
        planner: Some(skyplan_plan::PlannerId::Jps),
        field: None,
        inscribed_radius_m: None,
        inflation_radius_m: None,
        cost_scaling: None,
        cost_weight: None,
        time_limit_ms: None,
        max_alt_m: None,
        ..request.clone()
    };
    let mut session = skyplan_plan::Session::new(world.clone()).with_limits(*limits);
    match session.plan(&probe) {
        Err(f) if matches!(f.kind, FailureKind::InvalidStart | FailureKind::InvalidGoal) => {
            Err(f.into())
        }
        _ => Ok(()),
    }
}

/// The map's terrain and the height above it the route keeps, for the flight's account.
type Ground = Option<(Arc<skyplan_map::terrain::Terrain>, Option<f64>)>;

/// After the flight: the replanner's account, the picture, the flight log and the exit.
fn conclude(
    args: &FlyArgs,
    flight: &runner::Flight,
    drawing: Option<(
        skyplan_plan::World,
        (Target, PictureKind),
        Vec<skyplan_map::nofly::Zone>,
    )>,
    (hidden, zones, ground): (&[ObstacleBox], &[skyplan_map::nofly::Zone], Ground),
    report: Option<&SimReport>,
    t0: Instant,
) -> Result<()> {
    if let Some(w) = &flight.watcher
        && let Ok(r) = w.0.lock()
    {
        let name = args.replanner.name();
        println!(
            "{}",
            runner::summary_line(name, r.stats(), r.learned_count())
        );
    }
    if let (Some((world, (target, kind), zones)), Some(path)) = (&drawing, &args.plot) {
        write_target(target, &flight_picture(world, kind, flight, hidden, zones)?)?;
        println!("wrote      {}", path.display());
    }
    let outcome = match &flight.ended {
        Ended::Uploaded => {
            println!("time       {:.2} s wall in all", t0.elapsed().as_secs_f64());
            return Ok(());
        }
        Ended::Flight(outcome) => outcome.clone(),
    };
    if let Some((terrain, agl_m)) = &ground
        && let Some(low) = skyplan_flyer::flight::lowest_over_ground(&flight.log, terrain)
    {
        let planned = agl_m.map_or(String::new(), |h| {
            format!(" (the route keeps {h} m above it)")
        });
        println!(
            "terrain    lowest {:.1} m above the ground while flying the route{planned}, at {:.1} s (N {:.1} m, E {:.1} m)",
            low.above_ground_m, low.time_s, low.ne_m[0], low.ne_m[1]
        );
    }
    if let Some(path) = &args.log {
        write_atomic(
            path,
            log_csv(&flight.log, &flight.replan_events()).as_bytes(),
        )?;
        println!(
            "wrote      flight log {} ({} rows)",
            path.display(),
            flight.log.len()
        );
    }
    let margin_m = runner::plan_margin_m(&flight.plan);
    let zone = skyplan_flyer::zones::closest_zone(&flight.log, zones, margin_m.unwrap_or(0.0));
    finish_flight(
        report,
        outcome,
        margin_m,
        (flight.tracking.as_ref(), zone.as_ref()),
        t0,
    )
}

/// The obstacles of the simulated world that the map does not have: `--hidden FILE` and
/// `--hidden-random N` buildings on or near the route.
fn hidden_obstacles(
    args: &FlyArgs,
    world: &skyplan_plan::World,
    request: &skyplan_plan::PlanRequest,
    home: &GeodeticHome,
) -> Result<Vec<ObstacleBox>> {
    let mut hidden = (args.hidden.as_ref())
        .map(|path| crate::sim_cmd::load_hidden(path, home))
        .transpose()?
        .unwrap_or_default();
    if args.hidden_random > 0 {
        let seed = request.seed_or_default();
        let placed = runner::hidden_random(world, request, args.hidden_random, seed)?;
        println!(
            "hidden     {} buildings on or near the route (seed {seed}), in the simulated world only",
            placed.len()
        );
        hidden.extend(placed);
    }
    Ok(hidden)
}

/// The vehicle: the built-in simulator on a free loopback port (`--sim`), or `--connect`.
fn vehicle(
    args: &FlyArgs,
    (obstacles, world): (BoxWorld, &skyplan_plan::World),
    frame: &LocalFrame,
    request: &skyplan_plan::PlanRequest,
    hidden: &[ObstacleBox],
) -> Result<(Address, Option<InProcessSim>)> {
    if !args.sim {
        let address = Address::parse(&args.connect, Role::Client).map_err(bad_input)?;
        return Ok((address, None));
    }
    let mut vehicle = skyplan_flight::sim::SimConfig::default();
    if request.trajectory == Some(true) {
        // The trajectory's limits are the vehicle's: simulate one that can fly them, with
        // headroom for its controllers (as a real autopilot's tilt limit gives).
        let l = request.trajectory_limits();
        vehicle.max_accel_m_s2 = vehicle.max_accel_m_s2.max(1.5 * l.max_accel_m_s2);
        vehicle.max_ground_speed_m_s = vehicle.max_ground_speed_m_s.max(l.max_speed_m_s);
        vehicle.max_climb_m_s = vehicle.max_climb_m_s.max(l.max_climb_m_s);
        vehicle.max_descent_m_s = vehicle.max_descent_m_s.max(l.max_descent_m_s);
        vehicle.max_yaw_rate_rad_s = vehicle.max_yaw_rate_rad_s.max(l.max_yaw_rate_rad_s());
    }
    let config = SimServerConfig {
        sim: vehicle,
        speedup: args.speedup,
        drop_link_after_s: args.sim_drop_link_after_s,
        link_gap_s: args.sim_link_gap_s,
        ekf_delay_s: args.sim_ekf_delay_s,
        sensor_range_m: args.sensor_range_m,
        proximity: args.proximity.into(),
        hidden: hidden.to_vec(),
        terrain: world.terrain_shared(),
        ..SimServerConfig::at(frame.home())
    };
    let (sim, home) = runner::start_sim(obstacles, frame, request, config)?;
    println!(
        "sim        simulated multicopter on tcp:127.0.0.1:{}, {}× real time, at lat {:.7}, lon {:.7}",
        sim.port(),
        args.speedup,
        home.lat_deg,
        home.lon_deg
    );
    Ok((sim.address(), Some(sim)))
}

/// The flight options of the arguments (an uploaded mission is flown by the autopilot: no
/// route swaps).
fn fly_options(a: &FlyArgs) -> FlyOptions {
    let ground = GroundConfig {
        speedup: a.speedup,
        link_timeout_s: a.link_timeout_s,
        timeout_s: a.timeout_s,
        on_interrupt: a.on_interrupt,
        ..GroundConfig::default()
    };
    let executor = ExecutorConfig {
        deadband_m: a.deadband_m,
        failsafe: a.failsafe,
        link_regain_wait_s: runner::LINK_REGAIN_FACTOR * a.link_timeout_s,
        ..ExecutorConfig::default()
    };
    let mode = match (a.upload, a.upload_only) {
        (_, true) => Mode::Upload { fly: false },
        (true, false) => Mode::Upload { fly: true },
        (false, false) => Mode::Guided(a.replanner.kind()),
    };
    let user_start = a.route.request.start_ne.is_some() || a.route.request.start_lla.is_some();
    FlyOptions {
        ground,
        executor,
        wait_s: a.wait_s,
        mode,
        user_start,
        fence: a.fence,
    }
}

/// The simulator's track report and the flight's exit: 0 only when landed and disarmed with
/// every waypoint reached and, on the simulator, no collision and never within half the route's
/// safety margin `margin_m` of an obstacle; a flight by a trajectory, never further than that
/// from its setpoints.
fn finish_flight(
    report: Option<&SimReport>,
    outcome: Option<Outcome>,
    margin_m: Option<f64>,
    (tracking, zone): (
        Option<&skyplan_flight::executor::TrackingReport>,
        Option<&skyplan_flyer::zones::ZonePass>,
    ),
    t0: Instant,
) -> Result<()> {
    if let Some(r) = report {
        println!("{}", flight::track_line(r, margin_m));
    }
    if let Some(z) = zone {
        println!("{}", skyplan_flyer::zones::zone_line(z, margin_m));
    }
    println!("time       {:.2} s wall in all", t0.elapsed().as_secs_f64());
    runner::verdict(outcome, report, margin_m, tracking, zone).map_err(|e| match e {
        Unfinished::NoRoute(_) => Failure::new(Kind::NoPath, e),
        e => runtime(e),
    })
}

/// Prints a line, above the progress bar when there is one.
fn say(line: &str) {
    match PROGRESS.get() {
        Some(bar) if !bar.is_hidden() => bar.println(line),
        _ => println!("{line}"),
    }
}

/// The flight's progress bar, drawn only when stdout is a terminal.
static PROGRESS: std::sync::OnceLock<indicatif::ProgressBar> = std::sync::OnceLock::new();

fn progress_bar(waypoints: usize) -> indicatif::ProgressBar {
    let bar = PROGRESS
        .get_or_init(|| {
            let target = match std::io::stdout().is_terminal() {
                true => indicatif::ProgressDrawTarget::stdout(),
                false => indicatif::ProgressDrawTarget::hidden(),
            };
            let template = "{prefix:>9} [{bar:30}] waypoint {pos}/{len}  {msg}";
            crate::show::progress(template, Some(waypoints as u64), target)
        })
        .clone();
    bar.set_length(waypoints as u64);
    bar
}

/// The terminal's observer: lines above the progress bar, the live view, the waypoint file.
struct Terminal {
    live: crate::live::Live,
    bar: indicatif::ProgressBar,
    wait_s: f64,
    out: Option<crate::plan_cmd::WaypointFile>,
    in_flight: Arc<AtomicBool>,
    /// The request (its no-fly zones go into a `.plan` file's geoFence).
    request: skyplan_plan::PlanRequest,
}

impl Observer for Terminal {
    fn say(&mut self, line: &str) {
        say(line);
    }

    fn update(&mut self, u: &Update) {
        match u {
            Update::Notes(t, notes) => {
                for note in notes {
                    if let Note::Replanned { event, targets } = note {
                        self.bar.set_length(targets.len() as u64);
                        self.live.events.replanned(*t, targets, event);
                    }
                }
                if let Some(i) = notes.iter().rev().find_map(reached_index) {
                    self.bar.set_position((i + 1) as u64);
                }
            }
            Update::Reading(r) => self.live.events.reading(r.clone()),
            Update::Progress(p) => {
                self.live.events.progress(p);
                self.bar.set_prefix(p.state.name());
                self.bar.set_position(p.reached as u64);
                self.bar.set_message(progress_message(p));
            }
            _ => {}
        }
    }
}

impl RunObserver for Terminal {
    type Error = Failure;

    fn waiting(&mut self, waiting: Waiting, vehicle_s: f64) {
        self.bar.set_message(format!(
            "waiting for the vehicle's {waiting}  t {vehicle_s:.1} s of {:.0} s",
            self.wait_s
        ));
        self.bar.tick();
    }

    fn planned(&mut self, plan: &Plan) -> Result<()> {
        self.bar.set_message("");
        self.live.events.route(plan, "plan");
        if let (Some(file @ (path, _, format)), Some(mission)) = (&self.out, &plan.mission) {
            let summary = serde_json::json!({ "map_home": plan.home, "planner": plan.planner });
            let (fence, _) = if *format == skyplan_export::Format::QgcPlan {
                crate::plan_cmd::geo_fence(&self.request, plan)?
            } else {
                Default::default()
            };
            // fly refuses terrain: the mission's altitudes are above home.
            crate::plan_cmd::write_waypoints(file, mission, &summary, (&fence, None))?;
            println!("wrote      {} ({})", path.display(), format.name());
        }
        Ok(())
    }

    fn flying(&mut self, waypoints: Option<usize>) {
        match waypoints {
            Some(n) => {
                self.bar = progress_bar(n);
                self.in_flight.store(true, Ordering::SeqCst);
            }
            None => {
                self.in_flight.store(false, Ordering::SeqCst);
                self.bar.finish_and_clear();
            }
        }
    }

    fn landed(&mut self, time_s: f64, state: FlightState, telemetry: Option<&Telemetry>) {
        self.live.events.last(time_s, state, telemetry);
    }
}
