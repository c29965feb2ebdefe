//! What the user typed, validated by clap without I/O.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

#[derive(Debug, Parser)]
#[command(
    name = "skyplan",
    version,
    about = "Plan collision-free flight paths through real maps",
    long_about = "Plan collision-free flight paths through real maps.\n\n\
        Exit codes: 0 success, 1 runtime error (files, checks), 2 bad input, 3 no path."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Plan on an FCND colliders map: grid at altitude → optimal path → pruned, geo-referenced waypoints.
    Plan(Box<PlanArgs>),
    /// Replay MovingAI scenarios and check every cost against the published optimal length.
    Scen(ScenArgs),
    /// Time every planner (and, with --peers, the tools people use instead) on the same queries.
    Bench(BenchArgs),
    /// Follow the cost map's gradient from a start through targets, which may change mid-ride.
    Navigate(Box<crate::grid_args::NavigateArgs>),
    /// Plan from the vehicle's position and fly it over MAVLink (--sim: a built-in simulated vehicle).
    Fly(Box<FlyArgs>),
    /// Run the built-in simulated multicopter as a MAVLink vehicle (for `fly`, pymavlink, QGroundControl).
    Sim(SimArgs),
}

/// A pair of numbers typed as `A,B`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair(pub f64, pub f64);

pub(crate) fn parse_pair(s: &str) -> Result<Pair, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [a, b] = parts[..] else {
        return Err(format!(
            "expected two comma-separated numbers like `12.5,-40`, found {s:?}"
        ));
    };
    let num = |t: &str| match t.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("expected a finite number, found {t:?} in {s:?}")),
    };
    Ok(Pair(num(a)?, num(b)?))
}

pub(crate) fn parse_finite(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("expected a finite number, found {s:?}")),
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlannerArg {
    /// A* with the octile (8-connected) or Manhattan (4-connected) heuristic.
    Astar,
    /// Dijkstra (no heuristic).
    Dijkstra,
    /// Jump Point Search: A*'s optimal costs, far fewer expansions (octile grids).
    Jps,
    /// Theta*: any-angle paths through cell centres, shorter than any grid path.
    Theta,
    /// JPS+: JPS with precomputed jumps; pays off over many queries on one grid.
    #[value(name = "jps-plus")]
    #[serde(rename = "jps-plus")]
    JpsPlus,
    /// Wavefront navigation function: distance field from the goal, then gradient descent.
    Wavefront,
    /// Inflated cost map: A* minimising length + weight · cost (Nav2-style inflation).
    Costmap,
    /// 3D probabilistic roadmap among the boxes (grown until start and goal connect), graph A*.
    Prm,
    /// 3D lazy PRM: the same roadmap, edges checked only on found paths (blocked ones removed, search repeated).
    #[value(name = "lazy-prm")]
    #[serde(rename = "lazy-prm")]
    LazyPrm,
    /// 3D RRT-Connect: bidirectional trees, stops at the first path.
    #[value(name = "rrt-connect")]
    #[serde(rename = "rrt-connect")]
    RrtConnect,
    /// 3D Informed RRT*: improves the path until --time-limit-ms.
    #[value(name = "rrt-star")]
    #[serde(rename = "rrt-star")]
    RrtStar,
    /// 3D voxel A* (26-connected, altitude layers): may climb over low buildings; --climb-weight.
    Voxel,
    /// 2D Voronoi roadmap of the obstacles' grown footprints at --alt-m: exactly free edges, graph A*, grid fallback.
    Voronoi,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PruneArg {
    /// Exact collinearity on grid cells.
    Collinear,
    /// Keep every cell of the grid path.
    None,
}

#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Map file, by extension: .csv FCND colliders, .yaml map_server, .png/.pgm (with
    /// --resolution), .map MovingAI; default: the bundled FCND city map.
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// TOML file with default values for these options (command-line options win).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Flight altitude above home, metres [default: 5].
    #[arg(long, value_name = "M", value_parser = parse_finite)]
    pub alt_m: Option<f64>,
    /// Safety margin around obstacles, metres [default: 5].
    #[arg(long, value_name = "M", value_parser = parse_finite)]
    pub safety_m: Option<f64>,
    /// Grid cell size, metres [default: 1].
    #[arg(long, value_name = "M", value_parser = parse_finite)]
    pub cell_m: Option<f64>,
    /// Start as local metres north,east of home [default: 0,0, the home].
    #[arg(long, value_name = "N,E", value_parser = parse_pair, conflicts_with = "start_lla", allow_hyphen_values = true)]
    pub start_ne: Option<Pair>,
    /// Start as latitude,longitude in degrees (the vehicle's current global position).
    #[arg(long, value_name = "LAT,LON", value_parser = parse_pair, allow_hyphen_values = true)]
    pub start_lla: Option<Pair>,
    /// Goal as local metres north,east of home.
    #[arg(long, value_name = "N,E", value_parser = parse_pair, conflicts_with = "goal_lla", allow_hyphen_values = true)]
    pub goal_ne: Option<Pair>,
    /// Goal as latitude,longitude in degrees.
    #[arg(long, value_name = "LAT,LON", value_parser = parse_pair, allow_hyphen_values = true)]
    pub goal_lla: Option<Pair>,
    /// Heading of the first waypoint, degrees clockwise from north [default: 0].
    #[arg(long, value_name = "DEG", value_parser = parse_finite, allow_hyphen_values = true)]
    pub start_heading_deg: Option<f64>,
    /// Grid connectivity: 8 (diagonals cost √2) or 4 [default: 8].
    #[arg(long, value_name = "4|8", value_parser = clap::value_parser!(u8).range(4..=8))]
    pub connectivity: Option<u8>,
    /// Let diagonal moves pass between two blocked cells (the FCND move model).
    #[arg(long)]
    pub corner_cutting: bool,
    /// Search algorithm [default: jps; 4-connected grids use astar].
    #[arg(long, value_enum)]
    pub planner: Option<PlannerArg>,
    /// Collinearity pruning [default: collinear].
    #[arg(long, value_enum)]
    pub prune: Option<PruneArg>,
    /// Use the FCND determinant collinearity test with this tolerance (cells²) instead of exact pruning.
    #[arg(long, value_name = "EPS", value_parser = parse_finite)]
    pub epsilon: Option<f64>,
    /// Skip line-of-sight shortcutting.
    #[arg(long)]
    pub no_shortcut: bool,
    /// Waypoint file; the format follows the extension (.json .csv .h5 .geojson .plan) [default: waypoints.json].
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Waypoint file format, overriding the extension: json, csv, hdf5, geojson, plan.
    #[arg(long, value_name = "FORMAT")]
    pub format: Option<String>,
    /// Also draw the map, path and waypoints to this picture (.png or .svg).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub grid: crate::grid_args::GridMapArgs,
    #[command(flatten)]
    pub plan3d: crate::plan3d_cmd::Plan3dArgs,
}

#[derive(Debug, Args)]
pub struct ScenArgs {
    /// MovingAI map (.map).
    pub map: PathBuf,
    /// MovingAI scenarios (.map.scen).
    pub scen: PathBuf,
    /// Print one JSON object per scenario (then a summary object) instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Search algorithm.
    #[arg(long, value_enum, default_value = "jps-plus")]
    pub planner: PlannerArg,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// 3D mode: skyplan's PRM, RRT-Connect and RRT* (and OMPL's with --peers) on random free 3D
    /// queries plus the FCND route, among the boxes grown by --safety-m.
    #[arg(long = "3d")]
    pub three_d: bool,
    /// Map: FCND colliders .csv (default: the bundled city map) or MovingAI .map.
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// Flight altitude for colliders maps, metres.
    #[arg(long, value_name = "M", default_value_t = 5.0, value_parser = parse_finite)]
    pub alt_m: f64,
    /// Safety margin for colliders maps, metres.
    #[arg(long, value_name = "M", default_value_t = 5.0, value_parser = parse_finite)]
    pub safety_m: f64,
    /// Cell size for colliders maps, metres.
    #[arg(long, value_name = "M", default_value_t = 1.0, value_parser = parse_finite)]
    pub cell_m: f64,
    /// Number of random far-apart queries (with --scen: at most this many scenarios) [default: 26].
    #[arg(long, value_name = "N")]
    pub random: Option<usize>,
    /// Seed of the random queries.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Minimum start-goal distance of random queries, metres [default: half the grid diagonal].
    #[arg(long, value_name = "M", value_parser = parse_finite)]
    pub min_distance_m: Option<f64>,
    /// Take the queries from a MovingAI .scen file instead.
    #[arg(long, value_name = "FILE")]
    pub scen: Option<PathBuf>,
    /// Comma-separated planners: jps-plus, jps, astar, dijkstra, rust-pathfinding-astar [default: jps-plus,jps,astar].
    #[arg(long, value_name = "LIST")]
    pub planners: Option<String>,
    /// Use the corner-cutting move model (FCND) instead of no corner cutting.
    #[arg(long)]
    pub corner_cutting: bool,
    /// Also run the peers: the Rust `pathfinding` crate, and Python A*s (set up with bench/setup-peers.sh).
    #[arg(long)]
    pub peers: bool,
    /// Time budget of each Python peer, seconds (a slow peer runs fewer queries).
    #[arg(long, value_name = "S", default_value_t = 60.0, value_parser = parse_finite)]
    pub peer_budget_s: f64,
    /// Write every record (planner, query, time, expansions, cost) to a .csv or .json file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print the table as one JSON object.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct FlyArgs {
    /// The vehicle: tcp:HOST:PORT (client), tcpout:, udpin:HOST:PORT (listen, e.g. 0.0.0.0:14550), udpout:.
    #[arg(long, value_name = "ADDRESS", default_value = "tcp:127.0.0.1:5760")]
    pub connect: String,
    /// Start the built-in simulated vehicle in-process (at the plan's start) and fly it; ignores --connect.
    #[arg(long)]
    pub sim: bool,
    /// Vehicle seconds per wall second: the simulator's speed with --sim, or `skyplan sim --speedup`.
    #[arg(long, value_name = "K", default_value_t = 1.0, value_parser = parse_finite)]
    pub speedup: f64,
    /// Write the flight log (time, state, position, target) as CSV.
    #[arg(long, value_name = "FILE")]
    pub log: Option<PathBuf>,
    /// Wall-clock budget of the flight, seconds: past it the vehicle is told to land, and the exit is non-zero.
    #[arg(long, value_name = "T", value_parser = parse_finite)]
    pub timeout_s: Option<f64>,
    /// A vehicle silent this long (no heartbeat, wall seconds) has lost the link.
    #[arg(long, value_name = "S", default_value_t = 5.0, value_parser = parse_finite)]
    pub link_timeout_s: f64,
    /// How long to wait for the vehicle's heartbeat, EKF origin and position, vehicle seconds (wall seconds × --speedup); ArduCopter's EKF needs ~40 s after boot.
    #[arg(long, value_name = "S", default_value_t = 90.0, value_parser = parse_finite)]
    pub wait_s: f64,
    /// Waypoint deadband, horizontal metres.
    #[arg(long, value_name = "M", default_value_t = 1.0, value_parser = parse_finite)]
    pub deadband_m: f64,
    /// Upload the plan as a mission (take-off, waypoints with headings, land) and fly it in AUTO.
    #[arg(long)]
    pub upload: bool,
    /// Upload the mission and exit without flying (interop tests).
    #[arg(long, hide = true)]
    pub upload_only: bool,
    /// What Ctrl-C commands in flight: land, or hold the position (LOITER) and leave the vehicle to the pilot.
    #[arg(long, value_enum, value_name = "ACTION", default_value = "land")]
    pub on_interrupt: crate::fly_cmd::InterruptArg,
    /// What to command when a lost link comes back within 6 × --link-timeout-s: land, rtl or hold [default: none, a lost link ends the flight at once].
    #[arg(long, value_enum, value_name = "ACTION")]
    pub failsafe: Option<crate::fly_cmd::FailsafeArg>,
    /// With --sim: simulated seconds after boot until the vehicle's EKF has a position (its origin at half of it); ArduCopter SITL needs ~40 s.
    #[arg(long, value_name = "S", default_value_t = skyplan_link::vehicle::DEFAULT_EKF_DELAY_S, value_parser = parse_finite, requires = "sim")]
    pub sim_ekf_delay_s: f64,
    /// Fault injection for tests: the simulated vehicle goes silent after this many simulated seconds.
    #[arg(long, value_name = "S", value_parser = parse_finite, hide = true, requires = "sim")]
    pub sim_drop_link_after_s: Option<f64>,
    /// Fault injection for tests: the silence lasts this many simulated seconds, then the link comes back.
    #[arg(long, value_name = "S", value_parser = parse_finite, hide = true, requires = "sim_drop_link_after_s")]
    pub sim_link_gap_s: Option<f64>,
    #[command(flatten)]
    pub plan: PlanArgs,
}

#[derive(Debug, Args)]
pub struct SimArgs {
    /// Where to listen: tcp:HOST:PORT (TCP server; port 0 picks one), tcpin:, udpin:HOST:PORT.
    #[arg(long, value_name = "ADDRESS", default_value = "tcp:127.0.0.1:5760")]
    pub listen: String,
    /// Home (start position) as latitude,longitude; default: the map's home.
    #[arg(long, value_name = "LAT,LON", value_parser = parse_pair, allow_hyphen_values = true)]
    pub home: Option<Pair>,
    /// Map whose obstacles the flown track is checked against (default: the bundled city map).
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// Simulated seconds per wall second.
    #[arg(long, value_name = "K", default_value_t = 1.0, value_parser = parse_finite)]
    pub speedup: f64,
    /// Stop after this many wall seconds (default: run until killed).
    #[arg(long, value_name = "S", value_parser = parse_finite)]
    pub duration_s: Option<f64>,
    /// Simulated seconds after boot until the EKF has a position (its origin at half of it); ArduCopter SITL needs ~40 s.
    #[arg(long, value_name = "S", default_value_t = skyplan_link::vehicle::DEFAULT_EKF_DELAY_S, value_parser = parse_finite)]
    pub ekf_delay_s: f64,
    /// Fault injection for tests: go silent after this many simulated seconds.
    #[arg(long, value_name = "S", value_parser = parse_finite, hide = true)]
    pub drop_link_after_s: Option<f64>,
}
