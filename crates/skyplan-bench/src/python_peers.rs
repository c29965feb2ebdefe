//! The Python peers as child processes (`skyplan bench --peers`, `bench --3d --peers`): the
//! script compiled in, its inputs written to a temporary folder, its stdout (one JSON object per
//! line) parsed into runs. Running them is this module's I/O, by design.

use crate::Run;
use crate::three_d::Rec3;
use serde_json::json;
use skyplan_cspace::{Cell, Grid2};
use skyplan_search::MoveModel;
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The 2D peers script (`bench/peers.py`), compiled in so that `bench --peers` works from any
/// directory.
const PEERS_PY: &str = include_str!("../../../bench/peers.py");

/// The OMPL peers script (`bench/peers3d.py`), compiled in.
const PEERS3D_PY: &str = include_str!("../../../bench/peers3d.py");

/// The trajectory peers script (`bench/peers_trajectory.py`), compiled in.
const PEERS_TRAJECTORY_PY: &str = include_str!("../../../bench/peers_trajectory.py");

/// Runs TOPP-RA and ruckig (`bench/peers_trajectory.py`) on the routes with the limits: its
/// stdout (one JSON object per peer and route), or the note why it did not run.
pub fn trajectory_peers(
    routes: &[Vec<Neu>],
    limits: &skyplan_plan::TrajectoryLimits,
) -> Result<String, String> {
    let files = [("routes.json", json!(routes).to_string().into_bytes())];
    run_script(
        "trajectory peers",
        ("peers_trajectory", PEERS_TRAJECTORY_PY),
        &files,
        |dir| {
            vec![
                dir.join("routes.json").into(),
                limits.max_speed_m_s.to_string().into(),
                limits.max_accel_m_s2.to_string().into(),
                limits.max_jerk_m_s3.to_string().into(),
            ]
        },
    )
}

/// The 3D peers' runs (name, one record per query) and notes.
pub type PeerRuns3 = (Vec<(String, Vec<Rec3>)>, Vec<String>);

/// The Python that runs the peers: `$SKYPLAN_PYTHON`, else `bench/.venv` (here or in the source
/// tree), else `python3`.
pub fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("SKYPLAN_PYTHON") {
        return PathBuf::from(p);
    }
    let candidates = [
        PathBuf::from("bench/.venv/bin/python"),
        PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../bench/.venv/bin/python"
        )),
    ];
    candidates
        .into_iter()
        .find(|p| p.exists())
        .unwrap_or_else(|| PathBuf::from("python3"))
}

/// Runs `script` as `<stem>.py` in a fresh temporary folder that holds `files`, with the
/// arguments `args` makes from the folder; its stdout, or the note why it did not run.
fn run_script(
    label: &str,
    (stem, script): (&str, &str),
    files: &[(&str, Vec<u8>)],
    args: impl FnOnce(&Path) -> Vec<OsString>,
) -> Result<String, String> {
    let dir = std::env::temp_dir().join(format!("skyplan-{stem}-{}", std::process::id()));
    std::fs::create_dir_all(&dir)
        .map_err(|e| format!("{label} skipped: cannot create {}: {e}", dir.display()))?;
    let file = dir.join(format!("{stem}.py"));
    let written = files
        .iter()
        .try_for_each(|(name, bytes)| std::fs::write(dir.join(name), bytes))
        .and_then(|()| std::fs::write(&file, script));
    if let Err(e) = written {
        let _ = std::fs::remove_dir_all(&dir);
        return Err(format!("{label} skipped: {e}"));
    }
    let py = python();
    let output = Command::new(&py).arg(&file).args(args(&dir)).output();
    let _ = std::fs::remove_dir_all(&dir);
    match output {
        Ok(o) if o.status.success() => Ok(String::from_utf8_lossy(&o.stdout).into_owned()),
        Ok(o) => Err(format!(
            "{label} failed ({}): {}",
            py.display(),
            String::from_utf8_lossy(&o.stderr).trim()
        )),
        Err(e) => Err(format!("{label} skipped: cannot run {}: {e}", py.display())),
    }
}

/// Runs the Python A\* peers (`bench/peers.py`) on the same grid and queries, each within
/// `budget_s` seconds; their runs and any notes (a peer unavailable, the script not run).
pub fn grid_peers(
    grid: &Grid2,
    queries: &[(Cell, Cell)],
    model: MoveModel,
    budget_s: f64,
) -> (Vec<Run>, Vec<String>) {
    let grid_bytes: Vec<u8> = grid.blocked_cells().iter().map(|&b| u8::from(b)).collect();
    let q: Vec<[u32; 4]> = queries
        .iter()
        .map(|(a, b)| [a.row, a.col, b.row, b.col])
        .collect();
    let model_name = if model == MoveModel::OctileCornerCutting {
        "octile-cc"
    } else {
        "octile"
    };
    let files = [
        ("grid.bin", grid_bytes),
        ("queries.json", json!(q).to_string().into_bytes()),
    ];
    let out = run_script("python peers", ("peers", PEERS_PY), &files, |dir| {
        vec![
            dir.join("grid.bin").into(),
            grid.rows().to_string().into(),
            grid.cols().to_string().into(),
            dir.join("queries.json").into(),
            model_name.into(),
            budget_s.to_string().into(),
        ]
    });
    match out {
        Ok(stdout) => crate::parse_peer_lines(&stdout),
        Err(note) => (Vec::new(), vec![note]),
    }
}

/// Runs OMPL's PRM, RRTConnect and RRT\* (`bench/peers3d.py`) on the world's grown boxes and
/// the queries, each within `budget_s` seconds.
pub fn ompl_peers(
    world: &BoxWorld3,
    qs: &[(Neu, Neu)],
    budget_s: f64,
) -> Result<PeerRuns3, String> {
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
    let files = [("problem.json", problem.to_string().into_bytes())];
    let stdout = run_script("OMPL peers", ("peers3d", PEERS3D_PY), &files, |dir| {
        vec![dir.join("problem.json").into(), budget_s.to_string().into()]
    })?;
    Ok(crate::three_d::parse_peer_lines(&stdout))
}
