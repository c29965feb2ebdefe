//! `skyplan`: the command-line front end. A thin layer over the library crates: it reads files,
//! calls the planning API (skyplan-plan), writes outputs atomically and maps errors to exit codes.

mod args;
mod bench3d_cmd;
mod bench_cmd;
mod config;
mod exit;
mod files;
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

use clap::Parser;
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
    let cli = args::Cli::parse();
    let result = match cli.command {
        args::Command::Plan(a) => plan_cmd::run(*a),
        args::Command::Scen(a) => scen_cmd::run(a),
        args::Command::Bench(a) => bench_cmd::run_bench(a),
        args::Command::Navigate(a) => navigate_cmd::run_navigate(*a),
        args::Command::Fly(a) => fly_cmd::run(*a),
        args::Command::Sim(a) => sim_cmd::run(a),
        args::Command::Map(args::MapCommand::Tile(a)) => map_cmd::tile(a),
        args::Command::Serve(a) => serve_cmd::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure { kind, error, .. }) => {
            eprintln!("error: {error:#}");
            ExitCode::from(kind.code())
        }
    }
}
