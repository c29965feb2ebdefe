//! A MovingAI replay ([`Replay`]) told as `skyplan scen` tells it: the totals, the table per
//! bucket, the JSON summary and the mismatch message. No I/O: the caller prints.

use crate::replay::{REL_TOL, Replay};
use serde_json::json;
use skyplan_plan::PlannerId;

/// What a replay ran on: the map's name and size, and the planner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplayOf<'a> {
    /// The map's name (its file).
    pub map: &'a str,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The grid-search planner.
    pub planner: PlannerId,
}

/// Every bucket's scenarios together.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Totals {
    /// Scenarios.
    pub scenarios: u64,
    /// Scenarios whose cost matched the published optimum.
    pub matched: u64,
    /// Mean search time, microseconds (0 without scenarios).
    pub mean_us: f64,
}

impl Replay {
    /// The totals over every bucket.
    pub fn totals(&self) -> Totals {
        let scenarios: u64 = self.buckets.values().map(|b| b.count).sum();
        let total_us: f64 = self.buckets.values().map(|b| b.total_us).sum();
        Totals {
            scenarios,
            matched: self.buckets.values().map(|b| b.matched).sum(),
            mean_us: total_us / scenarios.max(1) as f64,
        }
    }

    /// The summary object that follows the scenarios' objects in `--json` output.
    pub fn json_summary(&self, of: &ReplayOf) -> serde_json::Value {
        let t = self.totals();
        let mut v = json!({ "summary": true, "map": of.map, "scenarios": t.scenarios, "matched": t.matched,
                "mean_time_us": t.mean_us, "planner": of.planner, "precompute_ms": self.table_ms });
        if let Some(pick) = &self.auto {
            v["auto"] = json!(pick);
        }
        v
    }

    /// The table: what ran on what, then a row per bucket (scenarios, matched, mean time) and
    /// the row of them all.
    ///
    /// ```
    /// use skyplan_bench::replay::{Bucket, Replay};
    /// use skyplan_bench::replay_report::ReplayOf;
    /// use skyplan_plan::PlannerId;
    ///
    /// let bucket = Bucket { count: 2, matched: 2, total_us: 30.0 };
    /// let replay = Replay { buckets: [(0, bucket)].into(), failures: vec![], table_ms: 0.0, auto: None };
    /// let of = ReplayOf { map: "a.map", width: 8, height: 4, planner: PlannerId::Astar };
    /// let table = replay.table(&of);
    /// assert!(table.starts_with("a.map: 8 × 4 grid, 2 scenarios, planner astar\n"));
    /// assert!(table.ends_with("   all         2         2           15.0\n"));
    /// assert_eq!(replay.mismatches(), None);
    /// ```
    pub fn table(&self, of: &ReplayOf) -> String {
        let Totals {
            scenarios,
            matched,
            mean_us,
        } = self.totals();
        let ran = self.auto.as_ref().map_or(of.planner, |p| p.planner);
        let table = match ran {
            PlannerId::JpsPlus => format!(" (JPS+ table ready in {:.1} ms)", self.table_ms),
            PlannerId::Ch => format!(" (hierarchy ready in {:.1} ms)", self.table_ms),
            PlannerId::Subgoal => format!(" (subgoal graph ready in {:.1} ms)", self.table_ms),
            PlannerId::FirstMove => format!(" (first-move table ready in {:.1} ms)", self.table_ms),
            _ => String::new(),
        };
        let mut s = format!(
            "{}: {} × {} grid, {scenarios} scenarios, planner {}{table}\n",
            of.map, of.width, of.height, of.planner
        );
        if let Some(pick) = &self.auto {
            s += &format!("auto picked {}: {}\n", pick.planner.info().label, pick.why);
        }
        s += &format!(
            "{:>6} {:>9} {:>9} {:>14}\n",
            "bucket", "scenarios", "matched", "mean time µs"
        );
        for (bucket, b) in &self.buckets {
            let mean = b.total_us / b.count as f64;
            s += &format!("{bucket:>6} {:>9} {:>9} {mean:>14.1}\n", b.count, b.matched);
        }
        s + &format!("{:>6} {scenarios:>9} {matched:>9} {mean_us:>14.1}\n", "all")
    }

    /// How many scenarios do not match their published optimum, with the first five reasons;
    /// `None` when every one matches.
    pub fn mismatches(&self) -> Option<String> {
        if self.failures.is_empty() {
            return None;
        }
        let shown: Vec<&str> = (self.failures.iter().take(5))
            .filter_map(|o| o.why.as_deref())
            .collect();
        Some(format!(
            "{} of {} scenarios do not match optimal_length (relative {REL_TOL}): {}",
            self.failures.len(),
            self.totals().scenarios,
            shown.join("; ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use crate::replay::{Bucket, Outcome, Replay};
    use crate::replay_report::ReplayOf;
    use skyplan_plan::PlannerId;

    fn bucket(count: u64, matched: u64, total_us: f64) -> Bucket {
        Bucket {
            count,
            matched,
            total_us,
        }
    }

    #[test]
    fn totals_table_and_summary_sum_every_bucket() {
        let failure = Outcome {
            line: 7,
            bucket: 1,
            cost: None,
            optimal_length: 3.0,
            ok: false,
            time_us: 5.0,
            expansions: 4,
            why: Some("line 7: no path".into()),
        };
        let replay = Replay {
            buckets: [(0, bucket(2, 2, 10.0)), (1, bucket(2, 1, 30.0))].into(),
            failures: vec![failure],
            table_ms: 1.26,
            auto: None,
        };
        let t = replay.totals();
        assert_eq!((t.scenarios, t.matched, t.mean_us), (4, 3, 10.0));
        let of = ReplayOf {
            map: "m.map",
            width: 3,
            height: 2,
            planner: PlannerId::JpsPlus,
        };
        let table = replay.table(&of);
        assert!(table.starts_with(
            "m.map: 3 × 2 grid, 4 scenarios, planner jps-plus (JPS+ table ready in 1.3 ms)\n"
        ));
        assert_eq!(table.lines().count(), 5);
        let json = replay.json_summary(&of);
        assert_eq!(
            (json["scenarios"].as_u64(), json["matched"].as_u64()),
            (Some(4), Some(3))
        );
        assert_eq!(json["precompute_ms"], 1.26);
        let m = replay.mismatches().unwrap();
        assert!(m.starts_with("1 of 4 scenarios do not match optimal_length"));
        assert!(m.ends_with(": line 7: no path"));
    }
}
