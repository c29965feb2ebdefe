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
    ExecutorConfig, FailsafeAction, FlightExecutor, FlightState, MissionExecutor, Note, Outcome,
    Target,
};
use skyplan_flight::upload::{GlobalWaypoint, UploadConfig, mission_items};
use skyplan_frames::{Lla, LocalFrame, Ned};
use skyplan_link::ground::{
    Autopilot, GroundConfig, GroundStation, LogRow, Progress, Update, grid_convergence_rad,
};
use skyplan_link::vehicle::{SimNote, SimReport, SimServer, SimServerConfig};
use skyplan_link::{Address, Role};
use skyplan_plan::{PlanRequest, Session, World};
use std::io::IsTerminal;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
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

/// The in-process simulator: its thread, stop flag and notes.
struct InProcessSim {
    stop: Arc<AtomicBool>,
    thread: std::thread::JoinHandle<SimReport>,
    notes: mpsc::Receiver<SimNote>,
}

impl InProcessSim {
    fn print_notes(&self) {
        while let Ok(n) = self.notes.try_recv() {
            if let Some(line) = sim_note_line(&n) {
                say(&format!("sim        {line}"));
            }
        }
    }

    fn finish(self) -> Option<SimReport> {
        self.stop.store(true, Ordering::Relaxed);
        let InProcessSim { thread, notes, .. } = self;
        let report = thread.join().ok();
        while let Ok(n) = notes.try_recv() {
            if let Some(line) = sim_note_line(&n) {
                println!("sim        {line}");
            }
        }
        report
    }
}

/// How the CLI shows a simulator note (`None`: not worth a line).
pub(crate) fn sim_note_line(n: &SimNote) -> Option<String> {
    Some(match n {
        SimNote::Connected(p) => format!("ground station connected from {p}"),
        SimNote::Disconnected(why) => format!("ground station left ({why})"),
        SimNote::Mode(m) => format!("mode {m}"),
        SimNote::Armed(true) => "armed".into(),
        SimNote::Armed(false) => "disarmed".into(),
        SimNote::Refused(why) => format!("refused: {why}"),
        SimNote::Takeoff(alt) => format!("taking off to {alt:.1} m"),
        SimNote::Landed => "touched down".into(),
        SimNote::MissionUploaded(n) => format!("mission of {n} items received"),
        SimNote::MissionItemReached(s) => format!("mission item {s} reached"),
        SimNote::Collision(c) => format!(
            "COLLISION at {:.1} s: N {:.2} E {:.2} alt {:.2} m inside obstacle #{}",
            c.time_s, c.point_ned_m[0], c.point_ned_m[1], -c.point_ned_m[2], c.box_index
        ),
        SimNote::Failsafe(why) => format!("failsafe: {why}"),
        SimNote::LinkDropped => "injected fault: the vehicle stops talking".into(),
        SimNote::LinkRestored => "injected fault over: the vehicle talks again".into(),
    })
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
    let map_name = world.name().to_string();
    println!(
        "map        {map_name}: {} obstacles, home lat {:.6}, lon {:.6}",
        map.boxes.len(),
        map.home.lat_deg,
        map.home.lon_deg
    );

    // The vehicle: the built-in simulator on a free loopback port, or the given address.
    let (address, sim) = if args.sim {
        let (address, sim) = start_sim(&args, &request, &frame, &map)?;
        (address, Some(sim))
    } else {
        (
            Address::parse(&args.connect, Role::Client).map_err(bad_input)?,
            None,
        )
    };
    let live = crate::live::Live::start(&world, args.view.as_deref(), args.record.as_deref())?;
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
        Ok((log, ended, live)) => (Ok((log, ended)), Some(live)),
        Err(e) => (Err(e), None),
    };
    if let Some(live) = live {
        live.finish()?;
    }
    let report = sim.and_then(InProcessSim::finish);
    let (log, ended) = result?;
    let outcome = match ended {
        Ended::Uploaded => {
            println!("time       {:.2} s wall in all", t0.elapsed().as_secs_f64());
            return Ok(());
        }
        Ended::Flight(outcome) => outcome,
    };
    if let Some(path) = &log_path {
        write_atomic(path, &log_csv(&log)?)?;
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
    map: &skyplan_map::colliders::CollidersMap,
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
        hidden: match &args.hidden {
            Some(path) => crate::sim_cmd::load_hidden(path, &map.home)?,
            None => Vec::new(),
        },
        sensor_range_m: crate::sim_cmd::sensor_range_m(args.sensor_range_m)?,
        ..SimServerConfig::at(home)
    };
    let server =
        SimServer::bind(&Address::TcpIn("127.0.0.1:0".into()), config).or_exit(Kind::Runtime)?;
    let port = server
        .local_addr()
        .map(|a| a.port())
        .ok_or_else(|| runtime("the simulator has no local address"))?;
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, notes) = mpsc::channel();
    let world = BoxWorld::new(&map.boxes);
    let thread_stop = Arc::clone(&stop);
    let thread = std::thread::spawn(move || {
        server.run(Some(&world), &thread_stop, |n| {
            let _ = tx.send(n);
        })
    });
    println!(
        "sim        simulated multicopter on tcp:127.0.0.1:{port}, {}× real time, at lat {:.7}, lon {:.7}",
        args.speedup, home.lat_deg, home.lon_deg
    );
    Ok((
        Address::TcpOut(format!("127.0.0.1:{port}")),
        InProcessSim {
            stop,
            thread,
            notes,
        },
    ))
}

/// The simulator's track report and the flight's exit: 0 only when landed and disarmed with
/// every waypoint reached and, on the simulator, no collision.
fn finish_flight(report: Option<&SimReport>, outcome: Option<Outcome>, t0: Instant) -> Result<()> {
    let report = report.cloned();
    if let Some(r) = &report {
        let clearance = r
            .track
            .min_clearance_m()
            .map_or("no obstacle within 20 m".to_string(), |c| {
                format!("closest obstacle {c:.2} m")
            });
        match r.track.collision() {
            Some(c) => println!(
                "track      COLLISION: {} samples inside obstacles, first at {:.1} s (obstacle #{})",
                r.track.colliding_samples(),
                c.time_s,
                c.box_index
            ),
            None => println!(
                "track      flown {:.1} m, max altitude {:.2} m, no collision with the map's obstacles ({clearance})",
                r.distance_m, r.max_alt_m
            ),
        }
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
) -> Result<(Vec<LogRow>, Ended, crate::live::Live)> {
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
        s.print_notes();
    }
    println!(
        "vehicle    system {} ({}) at lat {:.7}, lon {:.7}, {:.2} m above home; {}",
        info.system_id,
        match info.autopilot {
            Autopilot::ArduPilot => "ArduPilot",
            Autopilot::Px4 => "PX4",
            Autopilot::Other => "another autopilot",
        },
        info.position.lat_deg,
        info.position.lon_deg,
        info.position.alt_m,
        match info.ekf_origin {
            Some(o) => format!("EKF origin lat {:.7}, lon {:.7}", o.lat_deg, o.lon_deg),
            None => "no EKF origin reported".to_string(),
        }
    );

    // PLANNING: the heartbeat thread keeps the link alive meanwhile.
    println!("state      PLANNING");
    let mut request = p.request;
    if !p.user_start {
        request.start_lla = Some([info.position.lat_deg, info.position.lon_deg]);
        request.start_ne = None;
    }
    let t_plan = Instant::now();
    let plan = Session::new(p.world).with_limits(p.limits).plan(&request)?;
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
        return fly_with(&mut gcs, &mut ex, frame, (sim, ctrl_c, &mut live))
            .map(|(log, o)| (log, Ended::Flight(o), live));
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
    .map(|(log, ended)| (log, ended, live))
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
    // --upload: the plan as a mission; ArduPilot's item 0 is its home (PX4 has none).
    // The plan's headings are from the map's grid north; the vehicle's are from true north.
    let waypoints: Vec<GlobalWaypoint> = mission
        .waypoints
        .iter()
        .map(|w| {
            let at = Lla {
                lat_deg: w.lat_deg,
                lon_deg: w.lon_deg,
                alt_m: 0.0,
            };
            let convergence_rad = grid_convergence_rad(frame, at).unwrap_or(0.0);
            GlobalWaypoint {
                heading_rad: w.heading_rad + convergence_rad,
                ..GlobalWaypoint::from(w)
            }
        })
        .collect();
    let home = match info.autopilot {
        Autopilot::Px4 => None,
        _ => Some((info.position.lat_deg, info.position.lon_deg)),
    };
    // ArduCopter ignores NAV_WAYPOINT's yaw: a CONDITION_YAW after each waypoint sets it.
    let condition_yaw = info.autopilot == Autopilot::ArduPilot;
    let items = mission_items(&waypoints, home, condition_yaw).map_err(bad_input)?;
    println!(
        "mission    {} items: {}take-off to {} m, {} waypoints with headings{}, land (MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)",
        items.items.len(),
        if home.is_some() { "home, " } else { "" },
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
    fly_with(gcs, &mut ex, frame, (sim, ctrl_c, live)).map(|(log, o)| (log, Ended::Flight(o)))
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

/// The progress bar's message: vehicle time and distance left.
pub(crate) fn progress_message(p: &Progress) -> String {
    format!(
        "{:.1} m left  t {:.1} s",
        p.distance_left_m.max(0.0),
        p.time_s
    )
}

/// Flies with either executor, printing as it goes, and sums the flight up.
fn fly_with<E: FlightExecutor>(
    gcs: &mut GroundStation,
    ex: &mut E,
    frame: &LocalFrame,
    (sim, ctrl_c, live): (Option<&InProcessSim>, &CtrlC, &mut crate::live::Live),
) -> Result<(Vec<LogRow>, Option<Outcome>)> {
    let n = ex.targets().len();
    let bar = progress_bar(n);
    ctrl_c.in_flight.store(true, Ordering::SeqCst);
    let mut n_route = n;
    let flown = gcs.fly(ex, frame, |u| {
        if let Some(s) = sim {
            s.print_notes();
        }
        match u {
            Update::Notes(t, notes) => {
                for note in notes {
                    if let Note::Replanned { event, targets } = &note {
                        n_route = targets.len();
                        bar.set_length(n_route as u64);
                        live.replanned(t, targets, event);
                    }
                    if let Some(line) = note_line(t, n_route, &note) {
                        say(&line);
                    }
                    if let Note::Reached(r) = note {
                        bar.set_position((r.index + 1) as u64);
                    }
                }
            }
            Update::StatusText(text) => say(&format!("vehicle    says: {text}")),
            Update::LinkClosed(why) => say(&format!("link       closed: {why}")),
            Update::TimedOut(limit) => say(&format!("timeout    {limit} s wall exceeded: landing")),
            Update::Interrupted(action) => say(&format!(
                "interrupt  Ctrl-C: {}",
                match action {
                    FailsafeAction::Land => "landing",
                    FailsafeAction::ReturnToLaunch => "returning to launch",
                    FailsafeAction::Hold =>
                        "holding position (LOITER), then leaving it to the pilot",
                }
            )),
            Update::Mode(m) => say(&format!("mode       {m}")),
            Update::Reading(r) => live.reading(r),
            Update::Warning(w) => say(&format!("sensor     {w}")),
            Update::Progress(p) => {
                live.progress(&p);
                bar.set_prefix(p.state.name());
                bar.set_position(p.reached as u64);
                bar.set_message(progress_message(&p));
            }
        }
    });
    ctrl_c.in_flight.store(false, Ordering::SeqCst);
    bar.finish_and_clear();
    let summary = flown.or_exit(Kind::Runtime)?;
    live.last(summary.time_s, ex.state(), ex.last_telemetry());
    let reached = ex.reached();
    let worst_h = reached
        .iter()
        .map(|r| r.horizontal_error_m)
        .fold(0.0, f64::max);
    let worst_yaw = reached
        .iter()
        .map(|r| r.heading_error_rad.to_degrees())
        .fold(0.0, f64::max);
    let last = ex.last_telemetry();
    println!(
        "flight     {:.1} s simulated/vehicle time, {:.2} s wall; {} of {n} waypoints reached (worst {:.2} m, {:.1}°); {} position targets sent, {} vehicle heartbeats",
        summary.time_s,
        summary.wall_time_s,
        reached.len(),
        worst_h,
        worst_yaw,
        summary.position_targets_sent,
        summary.heartbeats_received
    );
    if let Some(t) = last {
        println!(
            "vehicle    at N {:.2} m, E {:.2} m, {:.2} m above home, {}, state {}",
            t.north_m,
            t.east_m,
            tidy(t.alt_m()),
            if t.armed { "ARMED" } else { "disarmed" },
            ex.state()
        );
    }
    let outcome = ex.outcome().cloned();
    match &outcome {
        Some(Outcome::Completed) => {
            println!("result     landed and disarmed after reaching all {n} waypoints")
        }
        Some(Outcome::Failed(f)) => println!("result     FAILED: {f}"),
        None => println!("result     FAILED: gave up waiting for the landing"),
    }
    Ok((summary.log, outcome))
}

/// How the CLI shows an executor note (`None`: not worth a line).
pub(crate) fn note_line(t: f64, n: usize, note: &Note) -> Option<String> {
    Some(match note {
        Note::State { from, to } => format!("state      {t:7.1} s  {from} → {to}"),
        Note::Reached(r) => format!(
            "waypoint   {:7.1} s  {} of {n} reached: {:.2} m off, heading off {:.1}°",
            r.time_s,
            r.index + 1,
            r.horizontal_error_m,
            r.heading_error_rad.to_degrees()
        ),
        Note::Refused { command, reason } => format!("refused    {t:7.1} s  {command}: {reason}"),
        Note::LinkLost {
            state,
            silent_s,
            wait_s,
            action,
        } => format!(
            "link       {t:7.1} s  lost in {state}: no heartbeat for {silent_s:.1} s; sending nothing, waiting up to {wait_s:.1} s for it to return (--failsafe {action})"
        ),
        Note::LinkRegained { silent_s, action } => format!(
            "link       {t:7.1} s  back after {silent_s:.1} s: commanding {}",
            match action {
                FailsafeAction::Land => "LAND (--failsafe land)",
                FailsafeAction::ReturnToLaunch => "RTL (--failsafe rtl)",
                FailsafeAction::Hold => "LOITER (--failsafe hold)",
            }
        ),
        Note::Replanned { event, targets } => format!(
            "replan     {t:7.1} s  at N {:.1} m, E {:.1} m: {} ({}, {:.2} ms, {} expansions, {} learned cells): new route of {} waypoints, {:.1} m",
            event.position_ned[0],
            event.position_ned[1],
            event.reason,
            event.planner,
            event.latency_ms,
            event.expansions,
            event.learned_cells,
            targets.len(),
            event.route_length_m
        ),
        Note::Holding { reason, hold_s } => {
            format!("hold       {t:7.1} s  no route: {reason}; holding {hold_s:.1} s, then landing")
        }
        Note::Finished => return None,
    })
}

/// Shows values that round to zero as 0.000, not -0.000.
fn tidy(x: f64) -> f64 {
    if x.abs() < 0.0005 { 0.0 } else { x }
}

fn log_csv(log: &[LogRow]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let write =
        |w: &mut csv::Writer<Vec<u8>>, rec: Vec<String>| w.write_record(rec).or_exit(Kind::Runtime);
    write(
        &mut w,
        [
            "time_s",
            "state",
            "north_m",
            "east_m",
            "alt_m",
            "heading_deg",
            "ground_speed_m_s",
            "target_index",
            "target_north_m",
            "target_east_m",
            "target_alt_m",
            "target_heading_deg",
            "lat_deg",
            "lon_deg",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect(),
    )?;
    for r in log {
        let mut rec = vec![
            format!("{:.3}", r.time_s),
            FlightState::name(r.state).to_string(),
            format!("{:.3}", r.north_m),
            format!("{:.3}", r.east_m),
            format!("{:.3}", tidy(r.alt_m)),
            format!("{:.2}", r.yaw_rad.to_degrees()),
            format!("{:.3}", r.speed_m_s),
        ];
        match r.target {
            Some((i, t)) => rec.extend([
                (i + 1).to_string(),
                format!("{:.3}", t.north_m),
                format!("{:.3}", t.east_m),
                format!("{:.3}", t.alt_m),
                format!("{:.2}", t.heading_rad.to_degrees()),
            ]),
            None => rec.extend(std::iter::repeat_n(String::new(), 5)),
        }
        rec.extend([format!("{:.7}", r.lat_deg), format!("{:.7}", r.lon_deg)]);
        write(&mut w, rec)?;
    }
    w.into_inner()
        .map_err(|e| anyhow::anyhow!("flight log: {e}"))
        .or_exit(Kind::Runtime)
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_flight::executor::FlightState;

    #[test]
    fn fault_notes_and_progress_read_plainly() {
        let lost = Note::LinkLost {
            state: FlightState::Waypoint,
            silent_s: 1.04,
            wait_s: 6.0,
            action: FailsafeAction::ReturnToLaunch,
        };
        assert_eq!(
            note_line(31.4, 3, &lost).unwrap(),
            "link          31.4 s  lost in WAYPOINT: no heartbeat for 1.0 s; sending nothing, waiting up to 6.0 s for it to return (--failsafe rtl)"
        );
        let back = Note::LinkRegained {
            silent_s: 2.0,
            action: FailsafeAction::Hold,
        };
        assert!(
            note_line(40.0, 3, &back)
                .unwrap()
                .ends_with("back after 2.0 s: commanding LOITER (--failsafe hold)")
        );
        assert_eq!(note_line(1.0, 3, &Note::Finished), None);
        let p = Progress {
            time_s: 12.34,
            state: FlightState::Waypoint,
            reached: 2,
            waypoints: 5,
            distance_left_m: 123.45,
            telemetry: None,
            readings: 0,
            replans: 0,
        };
        assert_eq!(progress_message(&p), "123.5 m left  t 12.3 s");
        assert_eq!(
            FailsafeAction::from(FailsafeArg::Rtl),
            FailsafeAction::ReturnToLaunch
        );
        assert_eq!(
            FailsafeAction::from(InterruptArg::Hold),
            FailsafeAction::Hold
        );
    }
}
