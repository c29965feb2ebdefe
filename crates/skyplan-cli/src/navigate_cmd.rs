//! `skyplan navigate`: follow the inflated cost map's gradient from a start through targets,
//! which may change mid-ride (the workshop's navigation functions). The map is loaded through the
//! planning API's `World`; the ride itself is `skyplan_navfn::navigate`.

use crate::exit::{Failure, Result, bad_input};
use crate::files::read_text;
use crate::grid_args::NavigateArgs;
use skyplan_cspace::Grid2;
use skyplan_plan::{PlanRequest, RideChange, RideRequest, Session};
use std::io::IsTerminal;
use std::path::Path;

fn read_targets_file(path: &Path) -> Result<Vec<[f64; 2]>> {
    skyplan_plan::cli::targets_text(&read_text(path)?)
        .map_err(|e| bad_input(format!("{}: {e}", path.display())))
}

pub fn run_navigate(args: NavigateArgs) -> Result<()> {
    match crate::exit::print_json_failure(args.json, navigate_inner(args))? {
        Some(stopped_short) => Err(stopped_short),
        None => Ok(()),
    }
}

/// A position from the option, else the map's default, else a prompt on a terminal.
fn endpoint(
    session: &mut Session,
    args: &NavigateArgs,
    which: &str,
    option: &str,
    given: Option<[f64; 2]>,
    default: Option<[f64; 2]>,
) -> Result<[f64; 2]> {
    Ok(match given.or(default) {
        Some(p) => p,
        None if std::io::stdin().is_terminal() => {
            let s = args.slice.spec()?;
            let grid: std::sync::Arc<Grid2> = session.grid(s.alt_m, s.safety_m, s.cell_m)?;
            crate::show::ask_position(&grid, which)?
        }
        None => {
            return Err(bad_input(format!(
                "missing {option} N,E (the {which}, metres north,east of the map's origin)"
            )));
        }
    })
}

/// The request: the ends from the options (or the map's defaults, or a prompt), the cost map.
fn ride_request(session: &mut Session, args: &NavigateArgs) -> Result<RideRequest> {
    let (start_default, goal_default) = session.world().default_endpoints_ne();
    let start_ne = endpoint(
        session,
        args,
        "source",
        "--start-ne",
        args.start_ne,
        start_default,
    )?;
    let targets_ne = match (&args.targets, &args.targets_file) {
        (Some(t), _) => t.0.clone(),
        (None, Some(path)) => read_targets_file(path)?,
        (None, None) => vec![endpoint(
            session,
            args,
            "target",
            "--targets",
            None,
            goal_default,
        )?],
    };
    let route = PlanRequest {
        alt_m: args.slice.alt_m,
        safety_m: args.slice.safety_m,
        cell_m: args.slice.cell_m,
        ..args.moves.apply(args.costmap.into_request())
    };
    Ok(RideRequest {
        start_ne,
        targets_ne,
        changes: args
            .change_target_at
            .iter()
            .map(|c| RideChange {
                at_step: c.at_step,
                target_ne: c.target,
            })
            .collect(),
        route,
    })
}

/// Runs the ride; `Ok(Some(failure))` when it stopped short (its summary is already printed).
fn navigate_inner(args: NavigateArgs) -> Result<Option<Failure>> {
    let plot = match &args.plot {
        Some(path)
            if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("png")) =>
        {
            Some(crate::files::output_target("--plot", path)?)
        }
        Some(path) => {
            return Err(bad_input(format!(
                "--plot {}: navigate draws a PNG heat map; use a .png file name",
                path.display()
            )));
        }
        None => None,
    };
    let limits = args.memory.limits();
    let world = crate::world_load::load_world(args.map.as_deref(), &args.grid, args.seed, &limits)?;
    let mut session = Session::new(world).with_limits(limits);
    let request = ride_request(&mut session, &args)?;
    let ride = session.ride(&request)?;
    if args.show {
        let (start, goal) = ride.ends;
        crate::show::print(&ride.grid, start, goal, &ride.trace, ride.model, false);
    }
    if let Some(target) = &plot {
        let bytes =
            skyplan_plot::plan_picture::ride_heatmap_png(&ride).map_err(crate::exit::runtime)?;
        crate::files::write_target(target, &bytes)?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string(&ride).map_err(crate::exit::runtime)?
        );
    } else {
        print!("{ride}");
    }
    Ok(ride.stopped_short().map(Failure::from))
}
