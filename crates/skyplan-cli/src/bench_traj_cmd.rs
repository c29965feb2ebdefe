//! `skyplan bench --trajectory`: the table of `skyplan_bench::trajectory_bench`'s runs, with
//! ratios against the route at the speed limit and against stopping at each waypoint.

use crate::args::BenchArgs;
use crate::exit::{Result, bad_input, runtime};
use skyplan_bench::trajectory_bench::{self as tb, TrajRow};
use skyplan_plan::{Session, TrajectoryLimits, World};

fn pct(v: &[f64], q: f64) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    s[((s.len() - 1) as f64 * q).round() as usize]
}

fn row_line(row: &TrajRow, base: &[(f64, f64)]) -> String {
    let n = row.duration_s.len().min(base.len());
    let over_len: Vec<f64> = (0..n).map(|i| row.duration_s[i] / base[i].0).collect();
    let over_stop: Vec<f64> = (0..n).map(|i| row.duration_s[i] / base[i].1).collect();
    let violations = row
        .violations
        .map_or("not checked".to_string(), |v| v.to_string());
    format!(
        "{:>9.2} {:>9.2} {:>10.3} {:>8.3} {:>10.3} {:>8.3}  {:<11} {}",
        pct(&row.compute_ms, 0.5),
        pct(&row.compute_ms, 0.99),
        pct(&over_len, 0.5),
        pct(&over_len, 1.0),
        pct(&over_stop, 0.5),
        pct(&over_stop, 1.0),
        violations,
        row.name
    )
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let n = args.random.unwrap_or(20);
    if n == 0 {
        return Err(bad_input("--random 0: expected at least 1 route"));
    }
    let min_m = args.min_distance_m.unwrap_or(600.0);
    let world = World::fcnd_city();
    let request = args.slice.request();
    let spec = request.spec()?;
    let limits = TrajectoryLimits::default();
    let boxes = tb::city_boxes(&world, spec.safety_m)
        .ok_or_else(|| runtime("the bundled city has no boxes"))?;
    let mut session = Session::new(world);
    let routes = tb::far_routes(&mut session, &request, n, (args.seed, min_m));
    if routes.is_empty() {
        return Err(bad_input(format!(
            "--min-distance-m {min_m}: no routes that far apart were found"
        )));
    }
    let base = tb::baselines(&routes, &limits);
    let mut rows: Vec<TrajRow> = tb::skyplan_rows(&routes, &boxes, &limits, 5)
        .map_err(|e| runtime(e.to_string()))?
        .into();
    let mut notes = Vec::new();
    if args.peers {
        match skyplan_bench::python_peers::trajectory_peers(&routes, &limits) {
            Ok(out) => rows.extend(tb::peer_rows(&out, routes.len())),
            Err(note) => notes.push(note),
        }
    }
    let lens: Vec<f64> = routes
        .iter()
        .map(|r| skyplan_world3::path_length_m(r))
        .collect();
    println!(
        "trajectory bench: {} JPS routes on the bundled city at {} m, margin {} m, {:.0}–{:.0} m long (median {:.0} m); limits {} m/s, {} m/s², {} m/s³",
        routes.len(),
        spec.alt_m,
        spec.safety_m,
        pct(&lens, 0.0),
        pct(&lens, 1.0),
        pct(&lens, 0.5),
        limits.max_speed_m_s,
        limits.max_accel_m_s2,
        limits.max_jerk_m_s3
    );
    println!(
        "{:>9} {:>9} {:>10} {:>8} {:>10} {:>8}  {:<11} method",
        "p50 ms", "p99 ms", "÷len/v p50", "max", "÷stop p50", "max", "violations"
    );
    for row in &rows {
        println!("{}", row_line(row, &base));
        for note in &row.notes {
            println!("          note: {note}");
        }
    }
    if let Some(opt) = rows.first() {
        println!(
            "fallbacks  {} of {} routes fell back to stopping at each waypoint",
            opt.fallbacks,
            routes.len()
        );
    }
    if let Some(rss) = skyplan_bench::grid_bench::peak_rss_bytes() {
        println!(
            "memory     peak resident {:.1} MiB (the whole bench process)",
            rss as f64 / (1024.0 * 1024.0)
        );
    }
    for note in notes {
        println!("note       {note}");
    }
    Ok(())
}
