//! `skyplan bench --3d` without the terminal: every 3D planner of skyplan's registry (and, with
//! peers, OMPL's in C++ through `bench/peers3d.cpp` and in Python through `bench/peers3d.py`) on
//! the same 3D queries of a colliders map, and the
//! report: a JSON object or the text the CLI prints.

use crate::python_peers::ompl_peers;
use crate::three_d::{Row3, format_table, random_queries, skyplan_runs, table};
use serde_json::json;
use skyplan_map::colliders::CollidersMap;
use skyplan_plan::{Session, World};
use skyplan_world3::{BoxWorld3, WorldSpec};

/// What a 3D bench runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bench3d {
    /// Margin the boxes grow by in all three axes, metres.
    pub safety_m: f64,
    /// Random free query pairs (the FCND route comes first).
    pub random: usize,
    /// Seed of the queries and of the planners.
    pub seed: u64,
    /// Budget of every run, seconds (RRT\* uses all of it; the others stop at the first path).
    pub budget_s: f64,
    /// Also run OMPL's planners (C++ against libompl-dev, and Python); a missing peer is a note,
    /// not an error.
    pub peers: bool,
}

/// A 3D bench's result: what ran on what, the table and its notes.
#[derive(Debug, Clone, PartialEq)]
pub struct Report3d {
    /// The map's name.
    pub map: String,
    /// Its obstacle boxes.
    pub boxes: usize,
    /// What ran.
    pub bench: Bench3d,
    /// Queries run (the FCND route and the random pairs).
    pub queries: usize,
    /// One row per planner.
    pub rows: Vec<Row3>,
    /// Notes under the table (peers that did not run).
    pub notes: Vec<String>,
}

/// The 3D world the bench plans in: the map's boxes grown by `safety_m` on every axis, 0–120 m.
pub fn bench_world(map: &CollidersMap, safety_m: f64) -> Result<BoxWorld3, String> {
    let spec = WorldSpec {
        safety_m,
        min_alt_m: 0.0,
        max_alt_m: 120.0,
        margin_bounds_m: 0.0,
    };
    BoxWorld3::new(&map.boxes, &spec).map_err(|e| e.to_string())
}

/// Runs the 3D bench on `map` (named `name`); errors name what is wrong with the map.
pub fn run(name: &str, map: CollidersMap, bench: Bench3d) -> Result<Report3d, String> {
    let world = bench_world(&map, bench.safety_m)?;
    let qs = random_queries(&world, bench.random, bench.seed);
    let boxes = map.boxes.len();
    let mut session = Session::new(World::from_colliders(name, map).map_err(|e| e.message)?);
    let (safety_m, seed, budget_s) = (bench.safety_m, bench.seed, bench.budget_s);
    let mut runs = skyplan_runs(&mut session, &qs, safety_m, seed, budget_s);
    let mut notes = Vec::new();
    if bench.peers {
        match crate::cpp_peers::ompl_cpp_peers(&world, &qs, budget_s) {
            Ok(((peer_runs, peer_notes), _)) => {
                runs.extend(peer_runs);
                notes.extend(peer_notes);
            }
            Err(e) => notes.push(e),
        }
        match ompl_peers(&world, &qs, budget_s) {
            Ok((peer_runs, peer_notes)) => {
                runs.extend(peer_runs);
                notes.extend(peer_notes);
            }
            Err(e) => notes.push(e),
        }
    }
    Ok(Report3d {
        map: name.to_string(),
        boxes,
        bench,
        queries: qs.len(),
        rows: table(&runs, &qs),
        notes,
    })
}

impl Report3d {
    /// One JSON object: `map`, `safety_m`, `queries`, `budget_s`, `rows`, `notes`.
    pub fn json(&self) -> serde_json::Value {
        json!({ "map": self.map, "safety_m": self.bench.safety_m, "queries": self.queries, "budget_s": self.bench.budget_s, "rows": self.rows, "notes": self.notes })
    }
}

impl std::fmt::Display for Report3d {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let b = &self.bench;
        writeln!(
            f,
            "map      {}: {} boxes grown by {} m in all three axes",
            self.map, self.boxes, b.safety_m
        )?;
        writeln!(
            f,
            "queries  {} (FCND route + {} random free pairs, seed {}), budget {} s each (RRT* uses all of it)",
            self.queries,
            self.queries.saturating_sub(1),
            b.seed,
            b.budget_s
        )?;
        writeln!(f)?;
        write!(f, "{}", format_table(&self.rows))?;
        for n in &self.notes {
            writeln!(f, "note     {n}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_bench_on_the_city_has_a_row_per_planner_and_says_what_ran() {
        let map = skyplan_map::colliders::parse_colliders(skyplan_plan::FCND_CITY_CSV).unwrap();
        let bench = Bench3d {
            safety_m: 5.0,
            random: 2,
            seed: 7,
            budget_s: 0.05,
            peers: false,
        };
        let report = run("city", map, bench).unwrap();
        assert_eq!(report.queries, 3);
        let three_d = skyplan_plan::PlannerId::ALL
            .iter()
            .filter(|p| p.info().dims == 3);
        assert_eq!(report.rows.len(), three_d.count());
        let text = report.to_string();
        assert!(text.starts_with("map      city: "));
        assert!(
            text.contains(
                "queries  3 (FCND route + 2 random free pairs, seed 7), budget 0.05 s each"
            )
        );
        let json = report.json();
        assert_eq!(json["queries"], 3);
        assert_eq!(json["budget_s"], 0.05);
        assert_eq!(
            json["rows"].as_array().map(Vec::len),
            Some(report.rows.len())
        );
    }
}
