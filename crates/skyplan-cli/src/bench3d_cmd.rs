//! `skyplan bench --3d`: skyplan's PRM, RRT-Connect and Informed RRT\* on the same 3D queries
//! (random free points far apart, plus the FCND route), and with `--peers` OMPL's PRM,
//! RRTConnect and RRT\* through its Python wheels (`bench/peers3d.py`). Every path of either side
//! is re-checked exactly (continuous segment–box tests).

use crate::args::BenchArgs;
use crate::exit::{Result, bad_input};
use crate::files::read_text;
use serde_json::{Value, json};
use skyplan_bench::Stats;
use skyplan_plan::FCND_CITY_CSV as BUNDLED_COLLIDERS;
use skyplan_sampling::{Budget, PlannerKind, Request, Status};
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu, WorldSpec, distance_m};
use std::process::Command;
use std::time::Duration;

/// The OMPL peers script, compiled in.
const PEERS3D_PY: &str = include_str!("../../../bench/peers3d.py");

/// Budget of every run, seconds (RRT\* uses all of it; the others stop at the first path).
const BUDGET_S: f64 = 1.0;

struct Rec {
    time_us: f64,
    length_m: Option<f64>,
    recheck_ok: bool,
}

/// Random free points at least half the footprint's diagonal apart, altitudes 5–60 m (xorshift,
/// seeded), after the FCND route (home → 420, 390 at 5 m).
fn queries(world: &BoxWorld3, count: usize, seed: u64) -> Vec<(Neu, Neu)> {
    let b = world.bounds();
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let draw = |next: &mut dyn FnMut() -> f64| loop {
        let p = [
            b.min[0] + next() * (b.max[0] - b.min[0]),
            b.min[1] + next() * (b.max[1] - b.min[1]),
            5.0 + next() * 55.0,
        ];
        if world.is_free(p) {
            return p;
        }
    };
    let min_d = 0.5 * (b.max[0] - b.min[0]).hypot(b.max[1] - b.min[1]);
    let mut out = vec![([0.0, 0.0, 5.0], [420.0, 390.0, 5.0])];
    out.retain(|(s, g)| world.is_free(*s) && world.is_free(*g));
    let mut tries = 0;
    while out.len() < count + 1 && tries < 1_000_000 {
        tries += 1;
        let (s, g) = (draw(&mut next), draw(&mut next));
        if distance_m(s, g) >= min_d {
            out.push((s, g));
        }
    }
    out
}

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
    let exact = world.brute_force();
    let qs = queries(&world, args.random.unwrap_or(10), args.seed);
    let kinds = [
        PlannerKind::RrtConnect,
        PlannerKind::Prm,
        PlannerKind::RrtStar,
    ];
    let mut runs: Vec<(String, Vec<Rec>)> = Vec::new();
    for kind in kinds {
        let mut recs = Vec::new();
        for (k, &(start, goal)) in qs.iter().enumerate() {
            let request = Request {
                start,
                goal,
                seed: args.seed + k as u64,
                budget: Budget::time(Duration::from_secs_f64(BUDGET_S)),
                range_m: None,
                simplify: true,
            };
            let s = skyplan_sampling::plan(&world, kind, &request);
            let ok = s.status == Status::Exact;
            recs.push(Rec {
                time_us: s.first_solution_us.map_or(BUDGET_S * 1e6, |t| t as f64),
                length_m: ok.then_some(s.cost_m),
                recheck_ok: ok && skyplan_world3::first_blocked_segment(&exact, &s.path).is_none(),
            });
        }
        runs.push((format!("skyplan {}", kind.name()), recs));
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
    let straight: Vec<f64> = qs.iter().map(|(s, g)| distance_m(*s, *g)).collect();
    let fastest = runs
        .iter()
        .filter_map(|(_, r)| Stats::of(&r.iter().map(|x| x.time_us).collect::<Vec<_>>()))
        .map(|s| s.median)
        .fold(f64::INFINITY, f64::min);
    let mut rows = Vec::new();
    for (planner, recs) in &runs {
        let Some(t) = Stats::of(&recs.iter().map(|x| x.time_us).collect::<Vec<_>>()) else {
            continue;
        };
        let ratios: Vec<f64> = recs
            .iter()
            .zip(&straight)
            .filter_map(|(r, d)| r.length_m.map(|l| l / d))
            .collect();
        let solved = ratios.len();
        let ratio = Stats::of(&ratios).map(|s| s.median);
        let rechecked = recs.iter().filter(|r| r.recheck_ok).count();
        rows.push(json!({
            "planner": planner, "queries": recs.len(), "solved": solved, "recheck_ok": rechecked,
            "median_first_ms": t.median / 1e3, "p95_first_ms": t.p95 / 1e3,
            "median_length_over_straight": ratio, "median_over_fastest": t.median / fastest,
        }));
    }
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
    println!(
        "{:<22} {:>7} {:>7} {:>13} {:>13} {:>14} {:>14}",
        "planner",
        "solved",
        "exact ✓",
        "median 1st ms",
        "p95 1st ms",
        "length/line",
        "×fastest 1st"
    );
    for r in &rows {
        println!(
            "{:<22} {:>7} {:>7} {:>13.3} {:>13.3} {:>14} {:>14.1}",
            r["planner"].as_str().unwrap_or("?"),
            format!("{}/{}", r["solved"], r["queries"]),
            format!("{}/{}", r["recheck_ok"], r["solved"]),
            r["median_first_ms"].as_f64().unwrap_or(f64::NAN),
            r["p95_first_ms"].as_f64().unwrap_or(f64::NAN),
            r["median_length_over_straight"]
                .as_f64()
                .map_or("-".to_string(), |x| format!("{x:.3}")),
            r["median_over_fastest"].as_f64().unwrap_or(f64::NAN),
        );
    }
    for n in &notes {
        println!("note     {n}");
    }
    Ok(())
}

type PeerRuns = (Vec<(String, Vec<Rec>)>, Vec<String>);

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
    let mut runs: Vec<(String, Vec<Rec>)> = Vec::new();
    let mut notes = Vec::new();
    for line in String::from_utf8_lossy(&output.stdout).lines() {
        let Ok(v) = serde_json::from_str::<Value>(line) else {
            continue;
        };
        let peer = v["peer"].as_str().unwrap_or("?").to_string();
        if let Some(why) = v["unavailable"].as_str() {
            notes.push(format!(
                "{peer} unavailable ({why}); run bench/setup-peers.sh"
            ));
            continue;
        }
        let solved = v["solved"].as_bool().unwrap_or(false);
        let rec = Rec {
            time_us: v["time_s"].as_f64().unwrap_or(f64::NAN) * 1e6,
            length_m: if solved { v["length_m"].as_f64() } else { None },
            recheck_ok: v["recheck_ok"].as_bool().unwrap_or(false),
        };
        match runs.iter_mut().find(|(n, _)| *n == peer) {
            Some((_, r)) => r.push(rec),
            None => runs.push((peer, vec![rec])),
        }
    }
    Ok((runs, notes))
}
