//! `skyplan`: the command-line front end. A thin layer over the library crates: it reads files,
//! calls the pipeline, writes outputs atomically and maps errors to exit codes.

mod args;
mod bench3d_cmd;
mod bench_cmd;
mod colliders_query;
mod config;
mod exit;
mod files;
mod fly_cmd;
mod grid_args;
mod grid_cmd;
mod plan3d_cmd;
mod plan_cmd;
mod scen_cmd;
mod sim_cmd;
mod voronoi_cmd;

use clap::Parser;
use exit::Failure;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = args::Cli::parse();
    let result = match cli.command {
        args::Command::Plan(a) => plan_cmd::run(*a),
        args::Command::Scen(a) => scen_cmd::run(a),
        args::Command::Bench(a) => bench_cmd::run_bench(a),
        args::Command::Navigate(a) => grid_cmd::run_navigate(*a),
        args::Command::Fly(a) => fly_cmd::run(*a),
        args::Command::Sim(a) => sim_cmd::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure { kind, error }) => {
            eprintln!("error: {error:#}");
            ExitCode::from(kind.code())
        }
    }
}
