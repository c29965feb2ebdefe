//! `skyplan bench --3d`: skyplan's PRM, RRT-Connect and Informed RRT\* on the same 3D queries
//! (random free points far apart, plus the FCND route), and with `--peers` OMPL's PRM,
//! RRTConnect and RRT\* through its Python wheels (`bench/peers3d.py`). Every path of either side
//! is re-checked exactly (continuous segment–box tests).

use crate::args::BenchArgs;
use crate::exit::{Result, bad_input};
use serde_json::json;
use skyplan_bench::python_peers::ompl_peers;
use skyplan_bench::three_d::{format_table, random_queries, skyplan_runs, table};
use skyplan_plan::{Session, World};
use skyplan_world3::{BoxWorld3, WorldSpec};

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
    let safety_m = args.slice.spec().safety_m;
    let (name, text) = crate::bench_cmd::map_text(args.map.as_deref())?;
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{name}: {e}")))?;
    let spec = WorldSpec {
        safety_m,
        min_alt_m: 0.0,
        max_alt_m: 120.0,
        margin_bounds_m: 0.0,
    };
    let world = BoxWorld3::new(&map.boxes, &spec).map_err(|e| bad_input(format!("{e}")))?;
    let qs = random_queries(&world, args.random.unwrap_or(10), args.seed);
    let mut session = Session::new(World::from_colliders(&name, map.clone())?);
    let mut runs = skyplan_runs(&mut session, &qs, safety_m, args.seed, BUDGET_S);
    let mut notes = Vec::new();
    if args.peers {
        match ompl_peers(&world, &qs, BUDGET_S) {
            Ok((peer_runs, peer_notes)) => {
                runs.extend(peer_runs);
                notes.extend(peer_notes);
            }
            Err(e) => notes.push(e),
        }
    }
    let rows = table(&runs, &qs);
    if args.json {
        println!(
            "{}",
            json!({ "map": name, "safety_m": safety_m, "queries": qs.len(), "budget_s": BUDGET_S, "rows": rows, "notes": notes })
        );
        return Ok(());
    }
    println!(
        "map      {name}: {} boxes grown by {} m in all three axes",
        map.boxes.len(),
        safety_m
    );
    println!(
        "queries  {} (FCND route + {} random free pairs, seed {}), budget {BUDGET_S} s each (RRT* uses all of it)",
        qs.len(),
        qs.len().saturating_sub(1),
        args.seed
    );
    println!();
    print!("{}", format_table(&rows));
    for n in &notes {
        println!("note     {n}");
    }
    Ok(())
}
