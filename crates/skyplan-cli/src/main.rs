//! `skyplan`: the command-line front end. A thin layer over the library crates: it reads files,
//! calls the pipeline, writes outputs atomically and maps errors to exit codes.

mod args;
mod bench_cmd;
mod config;
mod exit;
mod files;
mod plan_cmd;
mod scen_cmd;

use clap::Parser;
use exit::Failure;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = args::Cli::parse();
    let result = match cli.command {
        args::Command::Plan(a) => plan_cmd::run(*a),
        args::Command::Scen(a) => scen_cmd::run(a),
        args::Command::Bench(a) => bench_cmd::run_bench(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure { kind, error }) => {
            eprintln!("error: {error:#}");
            ExitCode::from(kind.code())
        }
    }
}
