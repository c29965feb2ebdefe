//! `skyplan bench --3d`: skyplan's PRM, RRT-Connect and Informed RRT\* on the same 3D queries
//! (random free points far apart, plus the FCND route), and with `--peers` OMPL's PRM,
//! RRTConnect and RRT\* through its Python wheels (`bench/peers3d.py`). Every path of either side
//! is re-checked exactly (continuous segment–box tests).

use crate::args::BenchArgs;
use crate::exit::{Result, bad_input};
use crate::files::read_text;
use serde_json::json;
use skyplan_bench::three_d::{Rec3, format_table, parse_peer_lines, random_queries, table};
use skyplan_plan::{FCND_CITY_CSV as BUNDLED_COLLIDERS, PlanRequest, PlannerId, Session, World};
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu, WorldSpec};
use std::process::Command;

/// The OMPL peers script, compiled in.
const PEERS3D_PY: &str = include_str!("../../../bench/peers3d.py");

/// Budget of every run, seconds (RRT\* uses all of it; the others stop at the first path).
const BUDGET_S: f64 = 1.0;

/// Runs the 3D bench.
pub fn run(args: BenchArgs) -> Result<()> {
    let (name, text) = match &args.map {
        Some(p) if p.extension().is_some_and(|e| e == "csv") => {
            (p.display().to_string(), read_text(p)?)
        }
        Some(p) => {
            return Err(bad_input(format!(
                "--3d needs an FCND colliders map (.csv), found {}",
                p.display()
            )));
        }
        None => (
            "FCND city map (bundled)".to_string(),
            BUNDLED_COLLIDERS.to_string(),
        ),
    };
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{name}: {e}")))?;
    let spec = WorldSpec {
        safety_m: args.safety_m,
        min_alt_m: 0.0,
        max_alt_m: 120.0,
        margin_bounds_m: 0.0,
    };
    let world = BoxWorld3::new(&map.boxes, &spec).map_err(|e| bad_input(format!("{e}")))?;
    let qs = random_queries(&world, args.random.unwrap_or(10), args.seed);
    // skyplan's planners through the planning API (which re-checks every path exactly: a route
    // that failed it would be an internal failure, never a solved row).
    let mut session = Session::new(World::from_colliders(&name, map.clone())?);
    let mut runs: Vec<(String, Vec<Rec3>)> = Vec::new();
    for planner in [PlannerId::RrtConnect, PlannerId::Prm, PlannerId::RrtStar] {
        let mut recs = Vec::new();
        for (k, &(start, goal)) in qs.iter().enumerate() {
            let request = PlanRequest {
                planner: Some(planner),
                start_ne: Some([start[0], start[1]]),
                goal_ne: Some([goal[0], goal[1]]),
                start_alt_m: Some(start[2]),
                goal_alt_m: Some(goal[2]),
                safety_m: Some(args.safety_m),
                seed: Some(args.seed + k as u64),
                time_limit_ms: Some((BUDGET_S * 1e3) as u64),
                ..Default::default()
            };
            let plan = session.plan(&request).ok();
            let first_us = plan
                .as_ref()
                .and_then(|p| p.details.get("first_solution_us"))
                .and_then(|v| v.as_f64());
            recs.push(Rec3 {
                time_us: first_us.unwrap_or(BUDGET_S * 1e6),
                length_m: plan.as_ref().map(|p| p.mission_length_m),
                recheck_ok: plan.is_some(),
            });
        }
        runs.push((format!("skyplan {planner}"), recs));
    }
    let mut notes = Vec::new();
    if args.peers {
        match ompl_peers(&world, &qs) {
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
            json!({ "map": name, "safety_m": args.safety_m, "queries": qs.len(), "budget_s": BUDGET_S, "rows": rows, "notes": notes })
        );
        return Ok(());
    }
    println!(
        "map      {name}: {} boxes grown by {} m in all three axes",
        map.boxes.len(),
        args.safety_m
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

type PeerRuns = (Vec<(String, Vec<Rec3>)>, Vec<String>);

fn ompl_peers(world: &BoxWorld3, qs: &[(Neu, Neu)]) -> std::result::Result<PeerRuns, String> {
    let dir = std::env::temp_dir().join(format!("skyplan-peers3d-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("OMPL peers skipped: {e}"))?;
    let b = world.bounds();
    let boxes: Vec<[f64; 6]> = world
        .inflated_boxes()
        .iter()
        .map(|x| [x.min[0], x.min[1], x.min[2], x.max[0], x.max[1], x.max[2]])
        .collect();
    let problem = json!({
        "boxes": boxes,
        "bounds": [b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]],
        "queries": qs.iter().map(|(s, g)| [s[0], s[1], s[2], g[0], g[1], g[2]]).collect::<Vec<_>>(),
    });
    std::fs::write(dir.join("problem.json"), problem.to_string())
        .and_then(|_| std::fs::write(dir.join("peers3d.py"), PEERS3D_PY))
        .map_err(|e| format!("OMPL peers skipped: {e}"))?;
    let py = crate::bench_cmd::python();
    let output = Command::new(&py)
        .arg(dir.join("peers3d.py"))
        .arg(dir.join("problem.json"))
        .arg(BUDGET_S.to_string())
        .output();
    let _ = std::fs::remove_dir_all(&dir);
    let output = match output {
        Ok(o) if o.status.success() => o,
        Ok(o) => {
            return Err(format!(
                "OMPL peers failed ({}): {}",
                py.display(),
                String::from_utf8_lossy(&o.stderr).trim()
            ));
        }
        Err(e) => {
            return Err(format!(
                "OMPL peers skipped: cannot run {}: {e}",
                py.display()
            ));
        }
    };
    Ok(parse_peer_lines(&String::from_utf8_lossy(&output.stdout)))
}
