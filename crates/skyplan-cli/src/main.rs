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
mod report;
mod scen_cmd;
mod serve_cmd;
mod show;
mod sim_cmd;
mod world_load;

use clap::Parser;
use exit::Failure;
use std::process::ExitCode;

fn main() -> ExitCode {
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
