//! One serialisable report of a plan (`--json`) and one human-readable printer, for every
//! planner.

use serde_json::{Value, json};
use skyplan_plan::Plan;

/// The files a command wrote, for the report.
pub struct Written {
    pub waypoints: Option<(String, &'static str)>,
    /// What a mission file's altitudes are measured from, and in which MAVLink frame.
    pub altitudes: Option<&'static str>,
    pub plot: Option<String>,
    pub roadmap: Option<String>,
    pub samples: Option<String>,
}

/// The `--json` object: the plan as the planning API serialises it, plus the outputs.
pub fn json_report(plan: &Plan, written: &Written, wall_time_us: u64) -> Value {
    let mut v = serde_json::to_value(plan)
        .unwrap_or_else(|e| json!({ "status": "error", "error": e.to_string() }));
    v["outputs"] = json!({
        "waypoints": written.waypoints.as_ref().map(|w| w.0.clone()),
        "format": written.waypoints.as_ref().map(|w| w.1),
        "altitudes": written.altitudes,
        "plot": written.plot,
        "roadmap": written.roadmap,
        "samples": written.samples,
    });
    v["wall_time_us"] = json!(wall_time_us);
    v
}

/// The human summary as text: the plan, the files written, the time.
pub fn summary(plan: &Plan, written: &Written, wall_ms: f64) -> String {
    let mut text = plan.to_string();
    let mut files: Vec<String> = Vec::new();
    if let Some((path, format)) = &written.waypoints {
        let path = if path == "-" { "standard output" } else { path };
        match written.altitudes {
            Some(a) => files.push(format!("{path} ({format}; altitudes {a})")),
            None => files.push(format!("{path} ({format})")),
        }
    }
    files.extend(written.plot.iter().cloned());
    files.extend(written.roadmap.iter().map(|r| format!("{r} (roadmap)")));
    files.extend(
        written
            .samples
            .iter()
            .map(|r| format!("{r} (trajectory samples)")),
    );
    if !files.is_empty() {
        text.push_str(&format!("wrote      {}\n", files.join(", ")));
    }
    text.push_str(&format!("time       {wall_ms:.2} ms in all\n"));
    text
}

/// Where the human lines of a command go: standard output, or standard error when standard
/// output carries a document (`--json`, `--out -`) that a script reads whole.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Human {
    Stdout,
    Stderr,
}

impl Human {
    /// Human lines go to stderr when `stdout_is_data`.
    pub fn when_stdout_is_data(stdout_is_data: bool) -> Self {
        if stdout_is_data {
            Human::Stderr
        } else {
            Human::Stdout
        }
    }

    /// Prints `text` as it is (its own line ends) on the chosen stream.
    pub fn print(self, text: &str) {
        match self {
            Human::Stdout => print!("{text}"),
            Human::Stderr => eprint!("{text}"),
        }
    }
}
