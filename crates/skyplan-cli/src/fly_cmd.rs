//! `skyplan fly`: connect (or start the simulator), wait for the vehicle, plan from where it is,
//! fly the FCND state machine, write the flight log, exit 0 only after landing and disarming with
//! every waypoint reached.

use crate::args::FlyArgs;
use crate::exit::runtime;
use crate::exit::{Classify, Kind, Result, bad_input};
use crate::files::{Target as OutTarget, write_atomic, write_target};
use skyplan_export::Format;
use skyplan_flight::auto::{AutoExecutor, MissionLayout};
use skyplan_flight::collision::BoxWorld;
use skyplan_flight::executor::{
    ExecutorConfig, FailsafeAction, FlightExecutor, MissionExecutor, Note, Outcome, Target,
};
use skyplan_flight::upload::UploadConfig;
use skyplan_frames::{Lla, LocalFrame, Ned};
use skyplan_link::flight::{self, Observer, reached_index};
use skyplan_link::ground::{Autopilot, GroundConfig, GroundStation, LogRow, Update};
use skyplan_link::in_process::InProcessSim;
use skyplan_link::vehicle::{SimReport, SimServerConfig};
use skyplan_link::words::{log_csv, progress_message, sim_note_line};
use skyplan_link::{Address, Role};
use skyplan_map::colliders::ObstacleBox;
use skyplan_plan::{PlanRequest, Session, World};
use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// `--on-interrupt`: what Ctrl-C commands in flight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum InterruptArg {
    /// Land where the vehicle is, wait for the touchdown and the disarm.
    Land,
    /// Hold the position (LOITER) and exit once the vehicle confirms: a pilot takes over.
    Hold,
}

/// `--failsafe`: what to command when a lost link comes back.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FailsafeArg {
    /// Land where the vehicle is.
    Land,
    /// Return to launch (RTL) and land there.
    Rtl,
    /// Hold the position (LOITER) and leave the vehicle to the pilot.
    Hold,
}

impl From<InterruptArg> for FailsafeAction {
    fn from(a: InterruptArg) -> Self {
        match a {
            InterruptArg::Land => FailsafeAction::Land,
            InterruptArg::Hold => FailsafeAction::Hold,
        }
    }
}

impl From<FailsafeArg> for FailsafeAction {
    fn from(a: FailsafeArg) -> Self {
        match a {
            FailsafeArg::Land => FailsafeAction::Land,
            FailsafeArg::Rtl => FailsafeAction::ReturnToLaunch,
            FailsafeArg::Hold => FailsafeAction::Hold,
        }
    }
}

/// A lost link is waited for this many times `--link-timeout-s` when `--failsafe` is set.
pub const LINK_REGAIN_FACTOR: f64 = 6.0;

/// The Ctrl-C handler's view: `in_flight` while the executor flies (a Ctrl-C then sets
/// `interrupt`, which the ground station turns into a landing or a hold; a second one exits at
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

/// Prints the simulator's new notes.
fn print_sim_notes(sim: &InProcessSim) {
    for n in sim.notes() {
        if let Some(line) = sim_note_line(&n) {
            say(&format!("sim        {line}"));
        }
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
    check_flight_args(&args)?;
    let ctrl_c = CtrlC::install();
    let view = args_view(&args);
    let log_path = args.log.clone();
    let crate::world_load::Resolved {
        world,
        limits,
        request,
        config,
    } = crate::world_load::resolve(&args.route)?;
    let user_start = request.start_ne.is_some() || request.start_lla.is_some();
    let out = match args.out.clone().or(config.out.clone()) {
        Some(path) => {
            let (target, format) = crate::plan_cmd::output_file(
                &path,
                args.format.as_deref().or(config.format.as_deref()),
            )?;
            Some((path, target, format))
        }
        None => None,
    };
    let (Some(map), Some(frame)) = (world.colliders().cloned(), world.frame().cloned()) else {
        return Err(bad_input(format!(
            "fly: {} is not an FCND colliders map; flying needs the map's boxes and geodetic home (--map FILE.csv, or the bundled map)",
            world.name()
        )));
    };
    let plot = match &args.plot {
        Some(path) => {
            let kind = crate::picture::kind_for(path, skyplan_plan::Family::AnyAngle)?;
            Some((crate::files::output_target("--plot", path)?, kind))
        }
        None => None,
    };
    let mut hidden = match &args.hidden {
        Some(path) => crate::sim_cmd::load_hidden(path, &map.home)?,
        None => Vec::new(),
    };
    if args.hidden_random > 0 {
        let seed = args.route.grid.seed;
        let placed = crate::replan_cmd::hidden_random(&world, &request, args.hidden_random, seed)?;
        println!(
            "hidden     {} buildings on or near the route (seed {seed}), in the simulated world only",
            placed.len()
        );
        hidden.extend(placed);
    }
    let map_name = world.name().to_string();
    println!(
        "map        {map_name}: {} obstacles, home lat {:.6}, lon {:.6}",
        map.boxes.len(),
        map.home.lat_deg,
        map.home.lon_deg
    );

    // The vehicle: the built-in simulator on a free loopback port, or the given address.
    let (address, sim) = if args.sim {
        let (address, sim) = start_sim(&args, &request, &frame, (&map, hidden.clone()))?;
        (address, Some(sim))
    } else {
        (
            Address::parse(&args.connect, Role::Client).map_err(bad_input)?,
            None,
        )
    };
    let live = crate::live::Live::start(&world, args.view.as_deref(), args.record.as_deref())?;
    let picture_world = plot.as_ref().map(|_| world.clone());
    let plan_with = FlyPlan {
        live,
        world,
        limits,
        request,
        user_start,
        out,
    };
    let result = fly(&view, &address, &frame, plan_with, sim.as_ref(), &ctrl_c);
    let (result, live) = match result {
        Ok((log, ended, live, seen)) => (Ok((log, ended, seen)), Some(live)),
        Err(e) => (Err(e), None),
    };
    if let Some(live) = live {
        live.finish()?;
    }
    let report = sim.and_then(finish_sim);
    let (log, ended, seen) = result?;
    if let Some(w) = &seen.watcher
        && let Ok(r) = w.0.lock()
    {
        println!(
            "{}",
            crate::replan_cmd::summary_line(view.replanner_name(), r.stats(), r.learned_count())
        );
    }
    if let (Some((target, kind)), Some(world)) = (&plot, &picture_world) {
        let bytes = crate::replan_cmd::flight_picture(world, kind, &seen, &hidden, &log)?;
        write_target(target, &bytes)?;
        if let Some(path) = &args.plot {
            println!("wrote      {}", path.display());
        }
    }
    let outcome = match ended {
        Ended::Uploaded => {
            println!("time       {:.2} s wall in all", t0.elapsed().as_secs_f64());
            return Ok(());
        }
        Ended::Flight(outcome) => outcome,
    };
    if let Some(path) = &log_path {
        write_atomic(path, log_csv(&log, &replan_events(&seen)).as_bytes())?;
        println!(
            "wrote      flight log {} ({} rows)",
            path.display(),
            log.len()
        );
    }
    finish_flight(report.as_ref(), outcome, t0)
}

/// Flight options out of range are bad input.
fn check_flight_args(args: &FlyArgs) -> Result<()> {
    if !(args.speedup >= 0.1 && args.speedup <= 1000.0) {
        return Err(bad_input(format!(
            "--speedup: expected 0.1 to 1000, found {}",
            args.speedup
        )));
    }
    for (name, v) in [
        ("--link-timeout-s", args.link_timeout_s),
        ("--wait-s", args.wait_s),
        ("--deadband-m", args.deadband_m),
    ] {
        if v <= 0.0 {
            return Err(bad_input(format!(
                "{name}: expected a positive number, found {v}"
            )));
        }
    }
    if let Some(t) = args.timeout_s
        && t <= 0.0
    {
        return Err(bad_input(format!(
            "--timeout-s: expected a positive number, found {t}"
        )));
    }
    if args.sim_ekf_delay_s < 0.0 {
        return Err(bad_input(format!(
            "--sim-ekf-delay-s: expected 0 or more, found {}",
            args.sim_ekf_delay_s
        )));
    }
    Ok(())
}

/// Starts the built-in simulator in-process at the plan's start, on a free loopback port.
fn start_sim(
    args: &FlyArgs,
    request: &PlanRequest,
    frame: &LocalFrame,
    (map, hidden): (&skyplan_map::colliders::CollidersMap, Vec<ObstacleBox>),
) -> Result<(Address, InProcessSim)> {
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
            .map_err(|e| bad_input(format!("start: {e}")))?,
        (None, None) => frame.home(),
    };
    let config = SimServerConfig {
        speedup: args.speedup,
        drop_link_after_s: args.sim_drop_link_after_s,
        link_gap_s: args.sim_link_gap_s,
        ekf_delay_s: args.sim_ekf_delay_s,
        map_home: Some(frame.home()),
        hidden,
        sensor_range_m: crate::sim_cmd::sensor_range_m(args.sensor_range_m)?,
        ..SimServerConfig::at(home)
    };
    let sim = InProcessSim::start(config, BoxWorld::new(&map.boxes)).or_exit(Kind::Runtime)?;
    println!(
        "sim        simulated multicopter on tcp:127.0.0.1:{}, {}× real time, at lat {:.7}, lon {:.7}",
        sim.port(),
        args.speedup,
        home.lat_deg,
        home.lon_deg
    );
    Ok((sim.address(), sim))
}

/// The simulator's track report and the flight's exit: 0 only when landed and disarmed with
/// every waypoint reached and, on the simulator, no collision.
fn finish_flight(report: Option<&SimReport>, outcome: Option<Outcome>, t0: Instant) -> Result<()> {
    if let Some(r) = report {
        println!("{}", flight::track_line(r));
    }
    println!("time       {:.2} s wall in all", t0.elapsed().as_secs_f64());
    match outcome {
        Some(Outcome::Completed) => {
            if let Some(r) = &report
                && let Some(c) = r.track.collision()
            {
                return Err(runtime(format!(
                    "the flight completed but the simulated vehicle hit obstacle #{} at {:.1} s",
                    c.box_index, c.time_s
                )));
            }
            Ok(())
        }
        // No route in the true world: the "no path" exit, as for planning.
        Some(Outcome::Failed(f @ skyplan_flight::executor::Failure::NoRoute { .. })) => {
            Err(crate::exit::Failure {
                kind: Kind::NoPath,
                error: anyhow::anyhow!("flight failed: {f}"),
                plan_kind: None,
            })
        }
        Some(Outcome::Failed(f)) => Err(runtime(format!("flight failed: {f}"))),
        None => Err(runtime(
            "flight aborted and the vehicle did not land in time: check it",
        )),
    }
}

/// The flight options that `fly` needs after `args.plan` is consumed.
struct FlyView {
    speedup: f64,
    link_timeout_s: f64,
    wait_s: f64,
    timeout_s: Option<f64>,
    deadband_m: f64,
    upload: bool,
    upload_only: bool,
    on_interrupt: FailsafeAction,
    failsafe: Option<FailsafeAction>,
    replanner: crate::replan_cmd::ReplannerArg,
}

impl FlyView {
    fn replanner_name(&self) -> &'static str {
        match self.replanner {
            crate::replan_cmd::ReplannerArg::DstarLite => "dstar-lite",
            crate::replan_cmd::ReplannerArg::Scratch => "scratch",
            crate::replan_cmd::ReplannerArg::Off => "off",
        }
    }
}

/// How `fly` ended: a flight (with its outcome, `None` if an aborted flight did not land in
/// time), or an upload without a flight (`--upload-only`).
enum Ended {
    Flight(Option<Outcome>),
    Uploaded,
}

fn args_view(a: &FlyArgs) -> FlyView {
    FlyView {
        speedup: a.speedup,
        link_timeout_s: a.link_timeout_s,
        wait_s: a.wait_s,
        timeout_s: a.timeout_s,
        deadband_m: a.deadband_m,
        upload: a.upload || a.upload_only,
        upload_only: a.upload_only,
        on_interrupt: a.on_interrupt.into(),
        failsafe: a.failsafe.map(FailsafeAction::from),
        // An uploaded mission is flown by the autopilot: no route swaps.
        replanner: if a.upload || a.upload_only {
            crate::replan_cmd::ReplannerArg::Off
        } else {
            a.replanner
        },
    }
}

/// What `fly` plans: the world, the request, whether the start was given, the waypoint file.
struct FlyPlan {
    live: crate::live::Live,
    world: World,
    limits: skyplan_plan::Limits,
    request: PlanRequest,
    user_start: bool,
    out: Option<(std::path::PathBuf, OutTarget, Format)>,
}

fn fly(
    a: &FlyView,
    address: &Address,
    frame: &LocalFrame,
    p: FlyPlan,
    sim: Option<&InProcessSim>,
    ctrl_c: &CtrlC,
) -> Result<(Vec<LogRow>, Ended, crate::live::Live, Seen)> {
    let mut live = p.live;
    let ground = GroundConfig {
        speedup: a.speedup,
        link_timeout_s: a.link_timeout_s,
        timeout_s: a.timeout_s,
        on_interrupt: a.on_interrupt,
        ..GroundConfig::default()
    };
    let mut gcs = GroundStation::connect(address, ground).or_exit(Kind::Runtime)?;
    gcs.set_interrupt(Arc::clone(&ctrl_c.interrupt));
    println!("link       {address}: connected, sending heartbeats at 1 Hz");
    let info = wait_for_vehicle(&mut gcs, a)?;
    if let Some(s) = sim {
        print_sim_notes(s);
    }
    println!("vehicle    {}", skyplan_link::mission::vehicle_line(&info));

    // PLANNING: the heartbeat thread keeps the link alive meanwhile.
    println!("state      PLANNING");
    let mut request = p.request;
    if !p.user_start {
        request.start_lla = Some([info.position.lat_deg, info.position.lon_deg]);
        request.start_ne = None;
    }
    let t_plan = Instant::now();
    let session = Session::new(p.world).with_limits(p.limits);
    let (plan, watcher) =
        crate::replan_cmd::plan_with_replanner(session, request.clone(), a.replanner)?;
    if let Some(w) = &watcher {
        gcs.set_watcher(Box::new(w.clone()));
    }
    live.route(&plan, "plan");
    let mission = plan
        .mission
        .as_ref()
        .ok_or_else(|| runtime("the plan has no geodetic waypoints"))?;
    println!(
        "plan       {}: {} → {}: {} waypoints, {:.1} m, altitudes {:.1}..{:.1} m, planned in {:.1} ms",
        plan.planner,
        plan.start,
        plan.goal,
        mission.waypoints.len(),
        mission.length_3d_m(),
        mission
            .waypoints
            .iter()
            .map(|w| w.alt_m)
            .fold(f64::INFINITY, f64::min),
        mission
            .waypoints
            .iter()
            .map(|w| w.alt_m)
            .fold(f64::NEG_INFINITY, f64::max),
        t_plan.elapsed().as_secs_f64() * 1000.0
    );
    if let Some((path, target, format)) = &p.out {
        let summary = serde_json::json!({ "map_home": plan.home, "planner": plan.planner });
        let bytes = skyplan_export::encode(*format, mission, &summary).or_exit(Kind::Runtime)?;
        write_target(target, &bytes)?;
        println!("wrote      {} ({})", path.display(), format.name());
    }
    let targets: Vec<Target> = mission.waypoints.iter().map(Target::from).collect();
    let config = ExecutorConfig {
        deadband_m: a.deadband_m,
        failsafe: a.failsafe,
        link_regain_wait_s: LINK_REGAIN_FACTOR * a.link_timeout_s,
        ..ExecutorConfig::default()
    };
    if !a.upload {
        let mut ex = MissionExecutor::new(&targets, config).map_err(bad_input)?;
        let (log, outcome, replanned) =
            fly_with(&mut gcs, &mut ex, frame, (sim, ctrl_c, &mut live))?;
        let seen = Seen {
            plan,
            watcher,
            replanned,
        };
        return Ok((log, Ended::Flight(outcome), live, seen));
    }
    fly_uploaded(
        &mut gcs,
        a,
        frame,
        mission,
        &info,
        request.alt_m.unwrap_or(5.0),
        (&targets, config),
        (sim, ctrl_c, &mut live),
    )
    .map(|(log, ended)| {
        let seen = Seen {
            plan: plan.clone(),
            watcher: None,
            replanned: Vec::new(),
        };
        (log, ended, live, seen)
    })
}

/// Routes as (north, east) points.
type Routes = Vec<Vec<(f64, f64)>>;

/// What a flight leaves for its summary and its picture.
pub(crate) struct Seen {
    /// The first plan.
    pub plan: skyplan_plan::Plan,
    /// The replanner that watched the flight, if any.
    pub watcher: Option<skyplan_replan::bench::SharedReplanner>,
    /// Every replanned route, (north, east).
    pub replanned: Vec<Vec<(f64, f64)>>,
}

/// `--upload`: the plan as a mission (ArduPilot's item 0 is its home; PX4 has none), uploaded,
/// then flown in AUTO.
#[allow(clippy::too_many_arguments)]
fn fly_uploaded(
    gcs: &mut GroundStation,
    a: &FlyView,
    frame: &LocalFrame,
    mission: &skyplan_mission::Mission,
    info: &skyplan_link::ground::VehicleInfo,
    alt_m: f64,
    (targets, config): (&[Target], ExecutorConfig),
    (sim, ctrl_c, live): (Option<&InProcessSim>, &CtrlC, &mut crate::live::Live),
) -> Result<(Vec<LogRow>, Ended)> {
    let items = skyplan_link::mission::items_for(mission, frame, info).map_err(bad_input)?;
    let condition_yaw = items.waypoint_stride == 2;
    println!(
        "mission    {} items: {}take-off to {} m, {} waypoints with headings{}, land (MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)",
        items.items.len(),
        if info.autopilot == Autopilot::Px4 {
            ""
        } else {
            "home, "
        },
        alt_m,
        targets.len(),
        if condition_yaw {
            " (each after a CONDITION_YAW to its heading)"
        } else {
            ""
        }
    );
    let report = gcs
        .upload_mission(&items, UploadConfig::default())
        .or_exit(Kind::Runtime)?;
    println!(
        "upload     accepted: {} items in {:.3} s wall ({} requests answered, {} resends)",
        report.items, report.wall_time_s, report.requests, report.resends
    );
    if a.upload_only {
        println!("result     mission uploaded (--upload-only: not flown)");
        return Ok((Vec::new(), Ended::Uploaded));
    }
    let mut ex =
        AutoExecutor::new(targets, MissionLayout::from(&items), config).map_err(bad_input)?;
    fly_with(gcs, &mut ex, frame, (sim, ctrl_c, live)).map(|(log, o, _)| (log, Ended::Flight(o)))
}

/// Waits for the vehicle (heartbeat, EKF origin, position) up to `--wait-s` vehicle seconds,
/// showing what it waits for on the progress line (and, without a terminal, once per change).
fn wait_for_vehicle(
    gcs: &mut GroundStation,
    a: &FlyView,
) -> Result<skyplan_link::ground::VehicleInfo> {
    let bar = progress_bar(0);
    bar.set_prefix("WAITING");
    let mut last = None;
    let wall = Duration::from_secs_f64(a.wait_s / a.speedup);
    let info = gcs.wait_for_vehicle(wall, |waiting, wall_s| {
        if last != Some(waiting) {
            last = Some(waiting);
            say(&format!(
                "wait       {:7.1} s  for the vehicle's {waiting}",
                wall_s * a.speedup
            ));
        }
        bar.set_message(format!(
            "waiting for the vehicle's {waiting}  t {:.1} s of {:.0} s",
            wall_s * a.speedup,
            a.wait_s
        ));
        bar.tick();
    });
    bar.set_message("");
    info.or_exit(Kind::Runtime)
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
            let bar = indicatif::ProgressBar::with_draw_target(
                Some(waypoints as u64),
                if std::io::stdout().is_terminal() {
                    indicatif::ProgressDrawTarget::stdout()
                } else {
                    indicatif::ProgressDrawTarget::hidden()
                },
            );
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{prefix:>9} [{bar:30}] waypoint {pos}/{len}  {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            bar
        })
        .clone();
    bar.set_length(waypoints as u64);
    bar
}

/// The terminal's observer: lines above the progress bar, the live view, the simulator's notes.
struct Terminal<'a> {
    sim: Option<&'a InProcessSim>,
    live: &'a mut crate::live::Live,
    bar: indicatif::ProgressBar,
    /// The replanned routes, (north, east) points, for the picture.
    replanned: Vec<Vec<(f64, f64)>>,
}

impl Observer for Terminal<'_> {
    fn say(&mut self, line: &str) {
        say(line);
    }

    fn update(&mut self, u: &Update) {
        if let Some(s) = self.sim {
            print_sim_notes(s);
        }
        match u {
            Update::Notes(t, notes) => {
                for note in notes {
                    if let Note::Replanned { event, targets } = note {
                        self.bar.set_length(targets.len() as u64);
                        self.live.replanned(*t, targets, event);
                        self.replanned
                            .push(targets.iter().map(|p| (p.north_m, p.east_m)).collect());
                    }
                }
                if let Some(i) = notes.iter().rev().find_map(reached_index) {
                    self.bar.set_position((i + 1) as u64);
                }
            }
            Update::Reading(r) => self.live.reading(r.clone()),
            Update::Progress(p) => {
                self.live.progress(p);
                self.bar.set_prefix(p.state.name());
                self.bar.set_position(p.reached as u64);
                self.bar.set_message(progress_message(p));
            }
            _ => {}
        }
    }
}

/// Flies with either executor, printing as it goes, and sums the flight up.
fn fly_with<E: FlightExecutor>(
    gcs: &mut GroundStation,
    ex: &mut E,
    frame: &LocalFrame,
    (sim, ctrl_c, live): (Option<&InProcessSim>, &CtrlC, &mut crate::live::Live),
) -> Result<(Vec<LogRow>, Option<Outcome>, Routes)> {
    let bar = progress_bar(ex.targets().len());
    ctrl_c.in_flight.store(true, Ordering::SeqCst);
    let mut terminal = Terminal {
        sim,
        live,
        bar: bar.clone(),
        replanned: Vec::new(),
    };
    let flown = flight::fly(gcs, ex, frame, &mut terminal);
    let replanned = std::mem::take(&mut terminal.replanned);
    ctrl_c.in_flight.store(false, Ordering::SeqCst);
    bar.finish_and_clear();
    let flown = flown.or_exit(Kind::Runtime)?;
    live.last(flown.summary.time_s, ex.state(), ex.last_telemetry());
    Ok((flown.log, flown.outcome, replanned))
}

/// The replans the flight's watcher made (none without one), for the flight log.
fn replan_events(seen: &Seen) -> Vec<skyplan_flight::sensing::ReplanEvent> {
    seen.watcher
        .as_ref()
        .and_then(|w| w.0.lock().ok().map(|r| r.events().to_vec()))
        .unwrap_or_default()
}
