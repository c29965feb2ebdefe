//! One serialisable report of a plan (`--json`) and one human-readable printer, for every
//! planner.

use serde_json::{Value, json};
use skyplan_plan::Plan;

/// The files a command wrote, for the report.
pub struct Written {
    pub waypoints: Option<(String, &'static str)>,
    pub plot: Option<String>,
    pub roadmap: Option<String>,
}

/// The `--json` object: the plan as the planning API serialises it, plus the outputs.
pub fn json_report(plan: &Plan, written: &Written, wall_time_us: u64) -> Value {
    let mut v = serde_json::to_value(plan)
        .unwrap_or_else(|e| json!({ "status": "error", "error": e.to_string() }));
    v["outputs"] = json!({
        "waypoints": written.waypoints.as_ref().map(|w| w.0.clone()),
        "format": written.waypoints.as_ref().map(|w| w.1),
        "plot": written.plot,
        "roadmap": written.roadmap,
    });
    v["wall_time_us"] = json!(wall_time_us);
    v
}

/// The human summary: the plan, the files written, the time.
pub fn print(plan: &Plan, written: &Written, wall_ms: f64) {
    print!("{plan}");
    let mut files: Vec<String> = Vec::new();
    if let Some((path, format)) = &written.waypoints {
        files.push(format!("{path} ({format})"));
    }
    files.extend(written.plot.iter().cloned());
    files.extend(written.roadmap.iter().map(|r| format!("{r} (roadmap)")));
    if !files.is_empty() {
        println!("wrote      {}", files.join(", "));
    }
    println!("time       {wall_ms:.2} ms in all");
}
