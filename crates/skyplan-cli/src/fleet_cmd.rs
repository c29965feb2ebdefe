//! `skyplan fleet` and `skyplan bench --fleet N`: many missions planned and reserved against a
//! shared airspace store (skyplan-fleet); this reads the files, opens the store, prints and
//! writes.

use crate::args::{BenchArgs, FleetArgs};
use crate::exit::{Result, bad_input, runtime};
use crate::files::{read_text, write_atomic};
use serde_json::json;
use skyplan_airspace::{PriorityRule, Timestamp};
use skyplan_airspace_store::{IntentStore, PostgresStore, StoreError, open_url};
use skyplan_fleet::{
    Clock, FlightRecord, Format, Mission, Mode, RandomMissions, RunOptions, Status, Summary,
    binding_conflicts, fly_fleet, parse_missions, random_missions,
};
use skyplan_plan::{PlanRequest, Session, World};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Now, rounded up to the next whole minute.
fn next_minute() -> Timestamp {
    let ms = Timestamp::now().unix_ms();
    Timestamp::from_unix_ms((ms.div_euclid(60_000) + 1) * 60_000)
}

/// The world of `--map` (or the bundled city); it needs a geodetic home.
fn world_of(map: Option<&Path>) -> Result<World> {
    let limits = crate::args::limits(None);
    let world = crate::world_load::load_world(map, &Default::default(), 1, &limits)?;
    if world.frame().is_none() {
        return Err(bad_input(format!(
            "--map {}: the map has no geodetic home, so its routes have no latitude and longitude for an operational intent",
            map.map_or_else(|| world.name().to_string(), |p| p.display().to_string())
        )));
    }
    Ok(world)
}

/// A fresh SQLite file in the temporary directory (not yet created).
fn temp_sqlite(tag: &str) -> PathBuf {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    std::env::temp_dir().join(format!(
        "skyplan-{tag}-{}-{nanos}.sqlite",
        std::process::id()
    ))
}

/// Removes a SQLite file and its WAL companions.
fn remove_sqlite(path: &Path) {
    for suffix in ["", "-wal", "-shm"] {
        let mut p = path.as_os_str().to_owned();
        p.push(suffix);
        let _ = std::fs::remove_file(PathBuf::from(p));
    }
}

/// Opens the store; an address it does not know is bad input, a store that fails a runtime error.
fn open_store(url: &str) -> Result<Box<dyn IntentStore>> {
    open_url(url).map_err(|e| match e {
        StoreError::Address(_) => bad_input(format!("--airspace {url}: {e}")),
        e => runtime(format!("--airspace {url}: {e}")),
    })
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
fn progress(len: usize, what: &str) -> indicatif::ProgressBar {
    let bar = crate::show::progress(
        "{msg:>24} [{bar:40}] {pos}/{len} flights",
        Some(len as u64),
        indicatif::ProgressDrawTarget::stderr(),
    );
    bar.set_message(what.to_string());
    bar
}

/// Flies `missions` against `store` with a progress bar.
fn fly(
    world: World,
    store: &dyn IntentStore,
    base: &PlanRequest,
    missions: &[Mission],
    mode: Mode,
    deadline_ms: Option<u64>,
    label: &str,
) -> Result<Vec<FlightRecord>> {
    let mut session = Session::new(world);
    let options = RunOptions {
        mode,
        search_deadline: deadline_ms.map(std::time::Duration::from_millis),
        ..RunOptions::default()
    };
    // One untimed plan first: the grid and the planner's tables are built once per session,
    // not in the first flight's latency.
    if let Some(first) = missions.first() {
        let _ = session.plan(&first.request(base));
    }
    let bar = progress(missions.len(), label);
    let records = fly_fleet(&mut session, store, base, missions, &options, |_, _| {
        bar.inc(1)
    })
    .map_err(runtime)?;
    bar.finish_and_clear();
    Ok(records)
}

/// Pairs of stored intents that intersect although the later was bound by the earlier.
fn conflicts_in(store: &dyn IntentStore) -> Result<usize> {
    let stored = store.list().map_err(runtime)?;
    Ok(binding_conflicts(&stored, PriorityRule::EqualOrHigher).len())
}

/// `skyplan fleet`.
pub fn run(args: FleetArgs) -> Result<()> {
    // Outputs are checked before any flight is planned.
    if let Some(path) = &args.plot {
        crate::files::output_target("--plot", path)?;
    }
    if let Some(path) = &args.json {
        crate::files::output_target("--json", path)?;
    }
    let world = world_of(args.map.as_deref())?;
    let start = match &args.start {
        Some(text) => text
            .parse::<Timestamp>()
            .map_err(|e| bad_input(format!("--start {text}: {e}")))?,
        None => next_minute(),
    };
    let base = PlanRequest {
        planner: args.planner,
        ..args.slice.request()
    };
    let spec = base.spec()?;
    if let Some(plot) = &args.plot
        && !plot
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("svg"))
    {
        return Err(bad_input(format!(
            "--plot {}: expected a .png or .svg file name",
            plot.display()
        )));
    }
    let clock = Clock {
        start,
        now: Timestamp::now(),
    };
    let missions = match (&args.file, args.random) {
        (Some(path), _) => {
            let name = path.display().to_string();
            let format = Format::of_name(&name).ok_or_else(|| {
                bad_input(format!(
                    "{name}: unknown mission file type; expected .json or .toml"
                ))
            })?;
            let text = read_text(path)?;
            parse_missions(&name, &text, format, clock).map_err(bad_input)?
        }
        (None, Some(n)) => {
            let mut session = Session::new(world.clone());
            let grid = session.grid(spec.alt_m, spec.safety_m, spec.cell_m)?;
            let r = RandomMissions {
                count: n as usize,
                seed: args.seed,
                min_distance_m: args.min_distance_m,
                spread_s: args.spread_s,
                window_s: args.window_s,
                start,
            };
            random_missions(&grid, spec.move_model, &r)
        }
        (None, None) => return Err(bad_input("give a mission FILE or --random N")),
    };
    let (url, fresh) = match &args.airspace {
        Some(url) => (url.clone(), None),
        None => {
            let path = temp_sqlite("fleet");
            (format!("sqlite:{}", path.display()), Some(path))
        }
    };
    let store = open_store(&url)?;
    if fresh.is_some() {
        eprintln!("airspace: {url} (a fresh SQLite file; kept)");
    }
    let mode = match (args.reject_on_conflict, args.space_time) {
        (true, true) => {
            return Err(bad_input(
                "--reject-on-conflict and --space-time: choose one way to handle a conflict",
            ));
        }
        (true, false) => Mode::RejectOnConflict,
        (false, true) => Mode::SpaceTime,
        (false, false) => Mode::Shift,
    };
    let records = fly(
        world.clone(),
        store.as_ref(),
        &base,
        &missions,
        mode,
        args.deadline_ms,
        mode.name(),
    )?;
    let summary = Summary::of(&records);
    let conflicts = conflicts_in(store.as_ref())?;
    if let Some(plot) = &args.plot {
        let bytes = crate::picture::fleet_picture(&world, &base, &records, plot)?;
        write_atomic(plot, &bytes)?;
    }
    match &args.json {
        Some(path) => {
            let report = json!({
                "map": world.name(),
                "airspace": url,
                "mode": mode,
                "start": start,
                "flights": records,
                "summary": summary,
                "conflicts": conflicts,
            });
            let text = serde_json::to_string_pretty(&report).map_err(runtime)?;
            write_atomic(path, text.as_bytes())?;
            eprintln!(
                "wrote    {} ({} of {} flights accepted, {conflicts} conflicts)",
                path.display(),
                summary.accepted,
                summary.missions
            );
        }
        None => print!("{}", table(&records, &summary, conflicts, &url, mode)),
    }
    if let Some(plot) = &args.plot {
        eprintln!("wrote    {}", plot.display());
    }
    if conflicts > 0 {
        return Err(runtime(format!(
            "{conflicts} pairs of accepted intents intersect"
        )));
    }
    Ok(())
}

/// The stdout report: one row per flight, then the totals.
fn table(records: &[FlightRecord], s: &Summary, conflicts: usize, url: &str, mode: Mode) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<12} {:<9} {:>8} {:>8} {:>8} {:>9} {:>9} {:>8}  {:<20}  blocking intents",
        "mission",
        "status",
        "delay s",
        "hover s",
        "detour m",
        "arrive +s",
        "latency",
        "checked",
        "departure"
    );
    for r in records {
        let delay = r.delay_s.map_or("-".into(), |d| format!("{d:.0}"));
        let hover = r.hover_s.map_or("-".into(), |d| format!("{d:.1}"));
        let detour = r.detour_m.map_or("-".into(), |d| format!("{d:.0}"));
        let arrive = r.arrival_delay_s.map_or("-".into(), |d| format!("{d:.1}"));
        let departure = r.departure.map_or("-".into(), |d| d.to_string());
        let blocking = match (r.status, &r.message) {
            (Status::NoRoute | Status::TimedOut, Some(m)) => m.clone(),
            _ => r
                .blocking
                .iter()
                .map(|b| b.id.as_str())
                .collect::<Vec<_>>()
                .join(" "),
        };
        let _ = writeln!(
            out,
            "{:<12} {:<9} {:>8} {:>8} {:>8} {:>9} {:>6.1} ms {:>8}  {:<20}  {blocking}",
            r.mission,
            r.status.name(),
            delay,
            hover,
            detour,
            arrive,
            r.latency_ms,
            r.checked,
            departure,
        );
    }
    let _ = write!(out, "{}", totals(s, conflicts));
    let _ = writeln!(out, "mode:      {}; airspace {url}", mode.name());
    out
}

fn totals(s: &Summary, conflicts: usize) -> String {
    format!(
        "flights:   {} missions, {} accepted ({:.1} %), {} refused, {} without a route, {} timed out\n\
         delay:     mean {:.1} s, p95 {:.0} s (accepted flights' departures)\n\
         arrival:   mean {:.1} s, p95 {:.0} s later than alone; {} hovering, {} detoured{}\n\
         latency:   plan and reserve p50 {:.1} ms, p99 {:.1} ms\n\
         checked:   {:.1} stored intents per request (max {})\n\
         conflicts: {conflicts} (every pair of stored intents, exact 4D test)\n",
        s.missions,
        s.accepted,
        100.0 * s.share_planned,
        s.refused,
        s.no_route,
        s.timed_out,
        s.delay_mean_s,
        s.delay_p95_s,
        s.arrival_delay_mean_s,
        s.arrival_delay_p95_s,
        s.hovering,
        s.detoured,
        unproven(s),
        s.latency_p50_ms,
        s.latency_p99_ms,
        s.checked_mean,
        s.checked_max,
    )
}

/// The flights whose earliest arrival the search did not prove (stopped by its deadline), if
/// any: "; N not proven earliest (could arrive at most G s sooner, mean)".
fn unproven(s: &Summary) -> String {
    if s.unproven == 0 {
        String::new()
    } else {
        format!(
            "; {} not proven earliest (could arrive at most {:.1} s sooner, mean)",
            s.unproven, s.arrival_gap_mean_s
        )
    }
}

/// One run of `bench --fleet`.
struct BenchRun {
    store: &'static str,
    mode: Mode,
    /// The space-time search's deadline per flight, if any.
    deadline_ms: Option<u64>,
    summary: Summary,
    conflicts: usize,
}

impl BenchRun {
    /// The mode as the table names it, with the search's deadline if any.
    fn label(&self) -> String {
        match self.deadline_ms {
            Some(ms) => format!("{}, {ms} ms", self.mode.name()),
            None => self.mode.name().to_string(),
        }
    }
}

/// `skyplan bench --fleet N`.
pub fn bench(args: &BenchArgs, flights: usize) -> Result<()> {
    let world = world_of(args.map.as_deref())?;
    let base = args.slice.request();
    let spec = base.spec()?;
    let start = next_minute();
    let missions = {
        let mut session = Session::new(world.clone());
        let grid = session.grid(spec.alt_m, spec.safety_m, spec.cell_m)?;
        let r = RandomMissions {
            count: flights,
            seed: args.seed,
            min_distance_m: args.min_distance_m.unwrap_or(300.0),
            spread_s: 3600.0,
            window_s: 900.0,
            start,
        };
        random_missions(&grid, spec.move_model, &r)
    };
    let postgres = args
        .airspace
        .clone()
        .or_else(|| std::env::var("SKYPLAN_TEST_POSTGRES").ok())
        .filter(|u| !u.is_empty());
    if let Some(url) = &postgres
        && !(url.starts_with("postgres://") || url.starts_with("postgresql://"))
    {
        return Err(bad_input(format!(
            "--airspace {url}: expected postgres://USER@HOST:PORT/DATABASE (SQLite always runs)"
        )));
    }
    // One fleet on one fresh store: its summary and the intersecting pairs it holds.
    let run_on = |url: &str, store: &'static str, mode: Mode| {
        let deadline_ms = args.deadline_ms.filter(|_| mode == Mode::SpaceTime);
        let opened = open_store(url)?;
        let label = format!("{store}, {}", mode.name());
        let records = fly(
            world.clone(),
            opened.as_ref(),
            &base,
            &missions,
            mode,
            deadline_ms,
            &label,
        )?;
        let conflicts = conflicts_in(opened.as_ref())?;
        Ok::<_, crate::exit::Failure>(BenchRun {
            store,
            mode,
            deadline_ms,
            summary: Summary::of(&records),
            conflicts,
        })
    };
    let mut runs = Vec::new();
    for mode in Mode::ALL {
        let path = temp_sqlite("bench-fleet");
        let url = format!("sqlite:{}", path.display());
        let result = run_on(&url, "sqlite", mode);
        remove_sqlite(&path);
        runs.push(result?);
        if let Some(pg) = &postgres {
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            let name = format!("skyplan_bench_fleet_{}_{nanos}", std::process::id());
            let url = PostgresStore::create_database(pg, &name)
                .map_err(|e| runtime(format!("--airspace: {e}")))?;
            runs.push(run_on(&url, "postgres", mode)?);
        }
    }
    if args.json {
        let rows: Vec<_> = runs
            .iter()
            .map(|r| json!({"store": r.store, "mode": r.mode, "deadline_ms": r.deadline_ms, "summary": r.summary, "conflicts": r.conflicts}))
            .collect();
        println!(
            "{}",
            json!({"map": world.name(), "flights": flights, "seed": args.seed, "runs": rows})
        );
    } else {
        print!("{}", bench_table(world.name(), flights, args.seed, &runs));
    }
    let conflicts: usize = runs.iter().map(|r| r.conflicts).sum();
    if conflicts > 0 {
        return Err(runtime(format!(
            "{conflicts} pairs of accepted intents intersect"
        )));
    }
    Ok(())
}

fn bench_table(map: &str, flights: usize, seed: u64, runs: &[BenchRun]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "fleet of {flights} random missions (seed {seed}) on {map}: departures over 1 h, windows of 15 min, priority 0, planned and reserved in order\n"
    );
    let _ = writeln!(
        out,
        "{:<9} {:<26} {:>8} {:>9} {:>8} {:>10} {:>9} {:>11} {:>11} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9}",
        "store",
        "mode",
        "planned",
        "timed out",
        "unproven",
        "delay avg",
        "delay p95",
        "arrive +avg",
        "arrive +p95",
        "hovering",
        "detoured",
        "p50 ms",
        "p99 ms",
        "checked",
        "conflicts"
    );
    for r in runs {
        let s = &r.summary;
        let _ = writeln!(
            out,
            "{:<9} {:<26} {:>7.1}% {:>9} {:>8} {:>8.1} s {:>7.0} s {:>9.1} s {:>9.0} s {:>8} {:>8} {:>8.1} {:>8.1} {:>8.1} {:>9}",
            r.store,
            r.label(),
            100.0 * s.share_planned,
            s.timed_out,
            s.unproven,
            s.delay_mean_s,
            s.delay_p95_s,
            s.arrival_delay_mean_s,
            s.arrival_delay_p95_s,
            s.hovering,
            s.detoured,
            s.latency_p50_ms,
            s.latency_p99_ms,
            s.checked_mean,
            r.conflicts
        );
    }
    let _ = writeln!(
        out,
        "\nplan-and-reserve latency as the store fills (p50 / p99 ms per tenth of the run; stored intents at its start):"
    );
    for r in runs {
        let cells: Vec<String> = r
            .summary
            .deciles
            .iter()
            .map(|d| format!("{}: {:.1}/{:.1}", d.stored_at_start, d.p50_ms, d.p99_ms))
            .collect();
        let _ = writeln!(out, "{:<9} {:<26} {}", r.store, r.label(), cells.join("  "));
    }
    out
}
