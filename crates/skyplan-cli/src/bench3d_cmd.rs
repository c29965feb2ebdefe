//! `skyplan bench --3d`: every 3D planner of skyplan's registry on the same 3D queries
//! (random free points far apart, plus the FCND route), and with `--peers` OMPL's PRM,
//! RRTConnect and RRT\* through its Python wheels (`bench/peers3d.py`). Every path of either side
//! is re-checked exactly (continuous segment–box tests). The runs and the report are
//! `skyplan_bench::bench3d`'s; this reads the map and prints.

use crate::args::BenchArgs;
use crate::exit::{Result, bad_input};
use skyplan_bench::bench3d::Bench3d;

/// Budget of every run, seconds (RRT\* uses all of it; the others stop at the first path).
const BUDGET_S: f64 = 1.0;

/// Runs the 3D bench.
pub fn run(args: BenchArgs) -> Result<()> {
    if let Some(p) = args
        .map
        .as_ref()
        .filter(|p| p.extension().is_none_or(|e| e != "csv"))
    {
        return Err(bad_input(format!(
            "--3d needs an FCND colliders map (.csv), found {}",
            p.display()
        )));
    }
    let (name, text) = crate::files::map_text(args.map.as_deref(), crate::bench_cmd::BUNDLED_NAME)?;
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{name}: {e}")))?;
    let bench = Bench3d {
        safety_m: args.slice.spec()?.safety_m,
        random: args.random.unwrap_or(10),
        seed: args.seed,
        budget_s: BUDGET_S,
        peers: args.peers,
    };
    let report = skyplan_bench::bench3d::run(&name, map, bench).map_err(bad_input)?;
    if args.json {
        println!("{}", report.json());
    } else {
        print!("{report}");
    }
    Ok(())
}
