//! `skyplan`: the command-line front end. A thin layer over the library crates: it reads files,
//! calls the planning API (skyplan-plan), writes outputs atomically and maps errors to exit codes.

mod args;
mod bench3d_cmd;
mod bench_cmd;
mod bench_traj_cmd;
mod config;
mod exit;
mod files;
mod fleet_cmd;
mod fly_cmd;
mod grid_args;
mod live;
mod map_cmd;
mod navigate_cmd;
mod picture;
mod plan_cmd;
mod replan_cmd;
mod report;
mod scen_cmd;
mod serve_cmd;
mod show;
mod sim_cmd;
mod world_load;

use clap::{CommandFactory, Parser};
use exit::Failure;
use std::process::ExitCode;

/// Exit status when standard output was closed by its reader (`skyplan … | head -1`): 128 +
/// SIGPIPE, as `cat` or `grep` end in the same pipeline.
pub const CLOSED_STDOUT_EXIT: i32 = 141;

/// Ends the process quietly: the reader of standard output has gone, nobody is listening.
pub fn exit_closed_stdout() -> ! {
    std::process::exit(CLOSED_STDOUT_EXIT)
}

/// `print!` panics when standard output is a closed pipe (Rust ignores SIGPIPE and reports
/// EPIPE as an error). That one panic ends the process quietly instead; every other panic keeps
/// the default report.
fn quiet_on_closed_stdout() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        // EPIPE is 32 on Linux and the BSDs; std's message ends with the OS error's text.
        let epipe = std::io::Error::from_raw_os_error(32).to_string();
        if message.starts_with("failed printing to std") && message.ends_with(&epipe) {
            exit_closed_stdout();
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    quiet_on_closed_stdout();
    let cli = match args::Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => {
            let argv: Vec<String> = std::env::args().collect();
            let Some(hint) = comma_hint(&error, &argv) else {
                error.exit()
            };
            let _ = error.print();
            eprintln!("\nhint: {hint}");
            std::process::exit(error.exit_code());
        }
    };
    let flying = matches!(cli.command, args::Command::Fly(_));
    let result = match cli.command {
        args::Command::Plan(a) => plan_cmd::run(*a),
        args::Command::Scen(a) => scen_cmd::run(a),
        args::Command::Bench(a) => bench_cmd::run_bench(a),
        args::Command::Navigate(a) => navigate_cmd::run_navigate(*a),
        args::Command::Fly(a) => fly_cmd::run(*a),
        args::Command::Sim(a) => sim_cmd::run(a),
        args::Command::Map(args::MapCommand::Tile(a)) => map_cmd::tile(a),
        args::Command::Map(args::MapCommand::Maze(a)) => map_cmd::maze(a),
        args::Command::Map(args::MapCommand::Rooms(a)) => map_cmd::rooms(a),
        args::Command::Serve(a) => serve_cmd::run(a),
        args::Command::Fleet(a) => fleet_cmd::run(*a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure { kind, error, .. }) => {
            eprintln!("error: {error:#}");
            if flying && refused(&error) {
                eprintln!(
                    "hint: no vehicle listens there; start the simulator first \
                     (skyplan sim --listen tcp:127.0.0.1:5760), or fly the built-in one with skyplan fly --sim"
                );
            }
            ExitCode::from(kind.code())
        }
    }
}

/// clap's "unexpected argument '390'" after `--goal-ne 420`: a position typed with a space where
/// its comma belongs. The hint names the option and the value as it should be written.
fn comma_hint(error: &clap::Error, argv: &[String]) -> Option<String> {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if error.kind() != ErrorKind::UnknownArgument {
        return None;
    }
    let Some(ContextValue::String(extra)) = error.get(ContextKind::InvalidArg) else {
        return None;
    };
    let command = args::Cli::command();
    // Every option whose value is a pair (`N,E`, `LAT,LON`), in any subcommand.
    let takes_a_pair = |long: &str| {
        let mut commands = vec![&command];
        let mut found = false;
        while let Some(c) = commands.pop() {
            commands.extend(c.get_subcommands());
            found |= c.get_arguments().any(|a| {
                a.get_long() == Some(long)
                    && a.get_value_names()
                        .is_some_and(|names| names.iter().any(|n| n.contains(',')))
            });
        }
        found
    };
    argv.windows(3).find_map(|w| {
        let (option, first, second) = (&w[0], &w[1], &w[2]);
        let long = option.strip_prefix("--")?;
        // A negative second number (`-122.39`) is reported by its first flag-like part (`-1`).
        let second_is_extra = second == extra || second.starts_with(extra.as_str());
        let numbers = first.parse::<f64>().is_ok() && second.parse::<f64>().is_ok();
        (second_is_extra && numbers && takes_a_pair(long)).then(|| {
            format!(
                "a position is two numbers with a comma and no space: {option} {first},{second}"
            )
        })
    })
}

/// Whether a connection was refused somewhere in the error's causes (nobody listens on the port).
fn refused(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::ConnectionRefused)
    })
}
