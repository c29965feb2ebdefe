//! What the user typed, validated by clap without I/O.

use clap::builder::TypedValueParser;
use clap::{Args, Parser, Subcommand, ValueEnum};
use skyplan_plan::cli::{finite, lat_lon};
use skyplan_plan::{PlanRequest, PlannerId};
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
    /// Plan a route with any planner on an FCND colliders map (.csv), an occupancy image (.png/.pgm
    /// or a ROS map_server .yaml), a MovingAI grid (.map) or a random workspace (--random).
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
    /// Make maps: `skyplan map tile` copies a colliders map K × K times (big test worlds);
    /// `skyplan map maze` makes a MovingAI maze and scenarios with exact lengths.
    #[command(subcommand)]
    Map(MapCommand),
    /// Serve the planning API over HTTP (JSON, server-sent events, OpenAPI) and the live-view page.
    Serve(ServeArgs),
    /// Plan many missions against a shared airspace store, in order, reserving each accepted
    /// flight's operational intent (its departure shifted within its window around the others);
    /// a report per flight and totals, and a picture.
    Fleet(Box<FleetArgs>),
}

#[derive(Debug, Args)]
pub struct FleetArgs {
    /// Mission file, .json or .toml: a list of missions (JSON `[{…}]` or `{"missions": […]}`;
    /// TOML `[[missions]]`), each with id, start_ne [N, E] or start_lla [LAT, LON], goal_ne or
    /// goal_lla, alt_m, departure (seconds after --start, an RFC 3339 time, or {earliest,
    /// latest}), window_s (default 900), priority (0 to 100, default 0), owner; see docs/FLEET.md.
    #[arg(
        value_name = "FILE",
        required_unless_present = "random",
        conflicts_with = "random"
    )]
    pub file: Option<PathBuf>,
    /// Instead of a file: N random missions between far-apart free places of the map (priority 0).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub random: Option<u32>,
    /// Seed of the random missions.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// With --random: departures spread uniformly over this many seconds after --start.
    #[arg(long, value_name = "S", default_value_t = 3600.0, value_parser = within(0.0, 86_400.0))]
    pub spread_s: f64,
    /// With --random: how much later than its departure each mission may leave, seconds.
    #[arg(long, value_name = "S", default_value_t = 900.0, value_parser = within(0.0, 86_400.0))]
    pub window_s: f64,
    /// With --random: least start–goal distance, metres.
    #[arg(long, value_name = "M", default_value_t = 300.0, value_parser = within(0.0, 1e6))]
    pub min_distance_m: f64,
    /// What departures given in seconds count from (RFC 3339) [default: now, rounded up to the next minute].
    #[arg(long, value_name = "TIME")]
    pub start: Option<String>,
    /// The airspace store: sqlite:FILE, postgres://USER@HOST:PORT/DATABASE (TLS with ?sslmode=require or verify-full, &sslrootcert=CA.pem for your own CA, &sslcert=C.pem&sslkey=K.pem for a client certificate) or sqlite::memory:
    /// [default: a fresh SQLite file in the temporary directory, named on stderr].
    #[arg(long, value_name = "URL")]
    pub airspace: Option<String>,
    /// The baseline: refuse a flight whose earliest departure conflicts instead of shifting it.
    #[arg(long)]
    pub reject_on_conflict: bool,
    /// Re-route each flight in space and time around the others (safe-interval search on the
    /// map's grid: a later departure, hovering and detours, the earliest arrival) instead of
    /// only shifting its departure.
    #[arg(long)]
    pub space_time: bool,
    /// With --space-time: each flight's answer is due this many milliseconds after its planning
    /// started. Its search around the others proves the earliest arrival over half the time
    /// left when it starts, then heads for the goal (the report says how much sooner the
    /// flight could arrive at most), and gives up at four-fifths of it: the flight is then
    /// `timed_out` and nothing is reserved for it [default: no deadline: every arrival proven
    /// the earliest].
    #[arg(long, value_name = "MS", requires = "space_time", value_parser = clap::value_parser!(u64).range(1..=3_600_000))]
    pub deadline_ms: Option<u64>,
    /// Map: FCND colliders .csv (as `plan`; a map with a geodetic home) [default: the bundled city].
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// Planner of every route [default: auto].
    #[arg(long, value_name = "PLANNER")]
    pub planner: Option<PlannerId>,
    #[command(flatten)]
    pub slice: SliceArgs,
    /// Write the report (every flight and the totals) as JSON to FILE instead of the table on stdout.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Draw the map and the routes, one colour per accepted flight, refused ones grey (.png or .svg).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
pub enum MapCommand {
    /// The map copied K × K times at a pitch (north and east), same home: a city of cities.
    Tile(TileArgs),
    /// A seeded perfect maze in MovingAI's format (corridors C cells wide, walls 1 cell, as in
    /// maze512-C-k), and optionally scenarios with exact optimal lengths.
    Maze(crate::map_cmd::MazeArgs),
    /// Seeded rooms in MovingAI's format (square rooms R cells wide, walls 1 cell, doors D
    /// cells wide, as in the Rroom_k maps), and optionally scenarios with exact optimal lengths.
    Rooms(crate::map_cmd::RoomsArgs),
}

#[derive(Debug, Args)]
pub struct TileArgs {
    /// Colliders map to copy [default: the bundled FCND city map].
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// Copies along each axis (1 to 100).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=100))]
    pub times: u32,
    /// Distance between copies, metres [default: the map's extent, rounded up to 10 m].
    #[arg(long, value_name = "M", value_parser = positive_up_to(1e6), allow_negative_numbers = true)]
    pub pitch_m: Option<f64>,
    /// The new map (.csv).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// A finite number from `lo` to `hi`.
fn within(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s| match finite(s)? {
        x if (lo..=hi).contains(&x) => Ok(x),
        _ => Err(format!("expected a number from {lo} to {hi}, found {s}")),
    }
}

/// A finite number above 0 and at most `hi`.
fn positive_up_to(hi: f64) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s| match finite(s)? {
        x if x > 0.0 && x <= hi => Ok(x),
        _ => Err(format!(
            "expected a number above 0 and at most {hi}, found {s}"
        )),
    }
}

/// `--planner` for `scen`: the exact cell searches (from the registry).
fn grid_search_planner() -> impl TypedValueParser<Value = PlannerId> {
    let values = (PlannerId::ALL.iter())
        .filter(|&&p| p.is_cell_search() && p.is_exact_on_grids())
        .filter_map(|p| p.to_possible_value());
    clap::builder::PossibleValuesParser::new(values)
        .map(|s| s.parse::<PlannerId>().unwrap_or_default())
}

/// How the route is planned: the map, the request and the planner (shared by `plan` and `fly`).
#[derive(Debug, Args)]
pub struct RouteArgs {
    /// Map file, by extension: .csv FCND colliders, .yaml ROS map_server, .png/.pgm (with
    /// --resolution), .map MovingAI; default: the bundled FCND city map.
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// TOML file with default values for these options (command-line options win).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// No-fly zones: a GeoJSON FeatureCollection (Polygon features, or Point features with
    /// radius_m; floor_m and ceiling_m above home; "inclusion": true for a boundary to stay
    /// inside) or a QGroundControl .plan file's geoFence. Grown by the margin; the 2D planners
    /// go around the zones whose band holds the flight altitude.
    #[arg(long = "no-fly", value_name = "FILE")]
    pub no_fly: Option<PathBuf>,
    /// The ground under the map: a DEM as GeoTIFF (WGS84 lon/lat or UTM) or SRTM .hgt, covering
    /// the map's home and the route. The route then keeps --alt-agl-m (else --alt-m) above the
    /// ground everywhere along it; altitudes stay above home, whose ground is the DEM's there.
    #[arg(long, value_name = "FILE")]
    pub terrain: Option<PathBuf>,
    #[command(flatten)]
    pub request: PlanRequest,
    #[command(flatten)]
    pub memory: MemoryArgs,
    #[command(flatten)]
    pub grid: crate::grid_args::GridMapArgs,
}

/// `1G`, `512M`, `300K` or a number of bytes.
/// `bench --planners`' help: the names it takes and its defaults, from the registry (a new grid
/// planner is named here without an edit).
fn bench_planners_help() -> String {
    let names = |movingai| {
        let defaults = skyplan_bench::default_contenders(movingai, false);
        defaults
            .iter()
            .map(|c| c.name())
            .collect::<Vec<_>>()
            .join(",")
    };
    format!(
        "Comma-separated planners: {} [default: {}; on MovingAI .map files: {}]",
        skyplan_bench::grid_bench::contender_names(),
        names(false),
        names(true)
    )
}

fn parse_size_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, mult) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let m = match c.to_ascii_uppercase() {
                'K' => 1u64 << 10,
                'M' => 1 << 20,
                'G' => 1 << 30,
                'T' => 1 << 40,
                _ => return Err(format!("expected a size like 512M or 2G, found {s:?}")),
            };
            (&t[..i], m)
        }
        _ => (t, 1),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v * (mult as f64) < 1.8e19 => {
            Ok((v * mult as f64) as u64)
        }
        _ => Err(format!("expected a size like 512M or 2G, found {s:?}")),
    }
}

/// `--max-memory` (`plan`, `fly`, `navigate`).
#[derive(Debug, Args)]
pub struct MemoryArgs {
    /// Most memory a map or plan may need, estimated before anything is allocated: bytes, or
    /// with a suffix K, M, G [default: half the machine's memory].
    #[arg(long, value_name = "SIZE", value_parser = parse_size_bytes)]
    pub max_memory: Option<u64>,
}

impl MemoryArgs {
    /// The planning API's limits of the option.
    pub fn limits(&self) -> skyplan_plan::Limits {
        limits(self.max_memory)
    }
}

/// `--max-memory` as the planning API's limits [default: [`default_max_memory`]].
pub(crate) fn limits(max_memory: Option<u64>) -> skyplan_plan::Limits {
    skyplan_plan::Limits {
        max_memory_bytes: max_memory.unwrap_or_else(default_max_memory),
    }
}

/// Half the machine's memory (`/proc/meminfo`), or 8 GiB where it cannot be read.
fn default_max_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map_or(8 << 30, |kb| kb * 1024 / 2)
}

#[derive(Debug, Args)]
pub struct PlanArgs {
    #[command(flatten)]
    pub route: RouteArgs,
    /// Waypoint file; the format follows the extension (.json .csv .h5 .geojson .plan) [default: waypoints.json].
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Waypoint file format, overriding the extension: json, csv, hdf5, geojson, plan.
    #[arg(long, value_name = "FORMAT")]
    pub format: Option<String>,
    /// Also draw the map, the route and what the planner built to this picture (.png or .svg;
    /// wavefront/costmap: a .png heat map).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// With --trajectory: write its samples (t_s, north_m, east_m, alt_m, velocities, accelerations, yaw_deg at --sample-hz) to this file: .csv, or .h5 (HDF5 dataset `samples`).
    #[arg(long, value_name = "FILE")]
    pub samples: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
    /// Print the workspace, the distance matrix and the path as text (grids up to 80 × 60).
    #[arg(long)]
    pub show: bool,
    /// prm, lazy-prm: save the roadmap after the run (JSON with the map's fingerprint).
    #[arg(long, value_name = "FILE")]
    pub save_roadmap: Option<PathBuf>,
    /// prm, lazy-prm: start from a saved roadmap (refused if built for another map, margin or volume).
    #[arg(long, value_name = "FILE")]
    pub load_roadmap: Option<PathBuf>,
    /// jps-plus, ch, subgoal, first-move: plan with the JPS+ table, contraction hierarchy,
    /// subgoal graph or first-move table saved in FILE (by --save-preprocess) instead of
    /// building one (auto: any of them, where it answers fastest); refused unless FILE was built
    /// for this map's grid (altitude, margin, cell size) and corner rule.
    #[arg(long, value_name = "FILE", conflicts_with = "save_preprocess")]
    pub preprocess: Option<PathBuf>,
    /// jps-plus, ch, subgoal, first-move: save the JPS+ table (with landmarks), contraction
    /// hierarchy, subgoal graph or first-move table this plan used to FILE (for --preprocess in
    /// later runs: a far query on a large map then needs no preprocessing).
    #[arg(long, value_name = "FILE")]
    pub save_preprocess: Option<PathBuf>,
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
    /// Grid-search planner.
    #[arg(long, value_name = "PLANNER", default_value = "auto", value_parser = grid_search_planner())]
    pub planner: PlannerId,
    /// Use the preprocessing saved in FILE (by --save-preprocess) instead of building it: a
    /// contraction hierarchy (with --planner ch, or auto on maps where a hierarchy is the
    /// fastest), a subgoal graph (with --planner subgoal, or auto on maps with a mean free run
    /// of at most 24 cells), a first-move table (with --planner first-move or auto, on any map)
    /// or a JPS+ table with landmarks (with --planner jps-plus, or auto where it picks JPS or
    /// JPS+); refused unless FILE was built for this map.
    #[arg(long, value_name = "FILE", conflicts_with = "save_preprocess")]
    pub preprocess: Option<PathBuf>,
    /// Save the contraction hierarchy, subgoal graph, first-move table or JPS+ table (with
    /// landmarks) this run builds (--planner ch, subgoal, first-move or jps-plus, or auto when
    /// it picks one) to FILE, for --preprocess in later runs.
    #[arg(long, value_name = "FILE")]
    pub save_preprocess: Option<PathBuf>,
    /// --planner first-move: build a table of up to SIZE (bytes, or with a suffix K, M, G;
    /// at most half the machine's memory) instead of refusing one over 64M. Half a byte per
    /// cell for every free cell: Paris_1_256's is 1.5 GB (--max-table 1.5G; 36–41 s on 2
    /// cores); with --save-preprocess, the file is as large.
    #[arg(long, value_name = "SIZE", value_parser = parse_size_bytes, conflicts_with = "preprocess")]
    pub max_table: Option<u64>,
}

/// Where a colliders map is sliced into a grid (`bench`, `navigate`; `plan` and `fly` take
/// these options from `PlanRequest`).
#[derive(Debug, Args)]
pub struct SliceArgs {
    /// Flight altitude above home, metres [default: 5].
    #[arg(long, value_name = "M", value_parser = finite, allow_hyphen_values = true)]
    pub alt_m: Option<f64>,
    /// Safety margin around obstacles, metres [default: 5].
    #[arg(long, value_name = "M", value_parser = finite, allow_hyphen_values = true)]
    pub safety_m: Option<f64>,
    /// Grid cell size of colliders maps, metres [default: 1].
    #[arg(long, value_name = "M", value_parser = finite, allow_hyphen_values = true)]
    pub cell_m: Option<f64>,
}

impl SliceArgs {
    /// These options as a plan request's fields: the planning API applies the defaults and
    /// checks the ranges, as for `plan`.
    pub fn request(&self) -> PlanRequest {
        PlanRequest {
            alt_m: self.alt_m,
            safety_m: self.safety_m,
            cell_m: self.cell_m,
            ..PlanRequest::default()
        }
    }

    /// The slice as the planning API resolves it (defaults applied, ranges checked).
    pub fn spec(&self) -> crate::exit::Result<skyplan_plan::PlanSpec> {
        Ok(self.request().spec()?)
    }
}

/// How a grid path may move (`navigate`; `plan` and `fly` take these options from `PlanRequest`).
#[derive(Debug, Args)]
pub struct MovesArgs {
    /// Grid connectivity: 8 (diagonals cost √2) or 4 [default: 8].
    #[arg(long, value_name = "4|8", value_parser = clap::value_parser!(u8).range(4..=8))]
    pub connectivity: Option<u8>,
    /// Let diagonal moves pass between two blocked cells (the FCND move model).
    #[arg(long)]
    pub corner_cutting: bool,
}

impl MovesArgs {
    /// `request` with these options (the planning API resolves them).
    pub fn apply(&self, request: PlanRequest) -> PlanRequest {
        PlanRequest {
            connectivity: self.connectivity,
            corner_cutting: self.corner_cutting.then_some(true),
            ..request
        }
    }
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Trajectory mode: --random N far routes on the bundled city (default 20, at least 600 m apart), a trajectory of each within the default limits: compute time, duration against the route at the speed limit and against stopping at each waypoint, violations (checked independently); TOPP-RA and ruckig on the same routes with --peers.
    #[arg(long, conflicts_with_all = ["three_d", "replan", "scen", "map"])]
    pub trajectory: bool,
    /// 3D mode: every skyplan 3D planner (and OMPL's PRM, RRT-Connect and RRT* with --peers) on
    /// random free 3D queries plus the FCND route, among the boxes grown by --safety-m.
    #[arg(long = "3d")]
    pub three_d: bool,
    /// Map: FCND colliders .csv (default: the bundled city map) or MovingAI .map.
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    #[command(flatten)]
    pub slice: SliceArgs,
    /// Number of random far-apart queries [default: 26]; with --scen: at most this many scenarios (first in file order) [default with --scen: every scenario of the file].
    #[arg(long, value_name = "N")]
    pub random: Option<usize>,
    /// Seed of the random queries.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Minimum start-goal distance of random queries, metres [default: half the grid diagonal].
    #[arg(long, value_name = "M", value_parser = finite, allow_negative_numbers = true)]
    pub min_distance_m: Option<f64>,
    /// Take the queries from a MovingAI .scen file instead.
    #[arg(long, value_name = "FILE")]
    pub scen: Option<PathBuf>,
    // Comma-separated planners: the help names them from the registry (`bench_planners_help`).
    #[arg(long, value_name = "LIST", help = bench_planners_help())]
    pub planners: Option<String>,
    /// Use the corner-cutting move model (FCND) instead of no corner cutting.
    #[arg(long)]
    pub corner_cutting: bool,
    /// Also run the peers: the Rust `pathfinding` crate, and Python A*s (set up with bench/setup-peers.sh).
    #[arg(long)]
    pub peers: bool,
    /// Time budget of each Python peer, seconds (a slow peer runs fewer queries).
    #[arg(long, value_name = "S", default_value_t = 60.0, value_parser = finite, allow_negative_numbers = true)]
    pub peer_budget_s: f64,
    /// Write every record (planner, query, time, expansions, cost) to a .csv or .json file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print the table as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// JPS+ (and auto, where it picks JPS or JPS+) uses the table saved in FILE (by
    /// --save-preprocess, with its landmarks) instead of building one; or, for a first-move
    /// table (saved by scen or plan --save-preprocess), first-move and auto use it; for a
    /// contraction hierarchy (saved by scen or plan --save-preprocess), ch and auto (on maps
    /// where it picks the hierarchy) use it; for a subgoal graph (saved likewise), subgoal and
    /// auto (on maps with a mean free run of at most 24 cells) use it; refused unless FILE was
    /// built for this map, altitude, margin, cell size and corner rule.
    #[arg(long, value_name = "FILE", conflicts_with = "save_preprocess")]
    pub preprocess: Option<PathBuf>,
    /// Build the JPS+ table of this grid, with landmarks, and save it to FILE (for --preprocess
    /// in later runs).
    #[arg(long, value_name = "FILE")]
    pub save_preprocess: Option<PathBuf>,
    /// Replanning mode: fly N seeded flights per replanner (dstar-lite, scratch) on the in-process simulator into hidden buildings, one row each: success, collisions, replans, latency, expansions, flown length over the full-knowledge optimum.
    #[arg(long, value_name = "N", conflicts_with_all = ["three_d", "scen", "peers", "preprocess", "save_preprocess"])]
    pub replan: Option<usize>,
    /// Fleet mode: N random missions over the map (bundled city, or --map such as `skyplan map
    /// tile`'s) planned and reserved in order with departures shifted and with the
    /// reject-on-conflict baseline, each on a fresh store: share planned, delays, plan-and-reserve
    /// latency as the store fills, intents checked, conflicts (all pairs) — on SQLite, and on
    /// PostgreSQL with --airspace postgres://… or SKYPLAN_TEST_POSTGRES.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000), conflicts_with_all = ["three_d", "scen", "peers", "preprocess", "save_preprocess", "replan", "trajectory"])]
    pub fleet: Option<u32>,
    /// With --fleet: also run on this PostgreSQL server (postgres://USER@HOST:PORT/DATABASE; a fresh database is made per run).
    #[arg(long, value_name = "URL", requires = "fleet")]
    pub airspace: Option<String>,
    /// With --fleet: the space-time run's flights' answers are due this many milliseconds after
    /// their planning started, as `fleet --deadline-ms` (proving the earliest arrival over half
    /// the time left when the search starts, `timed_out` past four-fifths of it) [default: no
    /// deadline].
    #[arg(long, value_name = "MS", requires = "fleet", value_parser = clap::value_parser!(u64).range(1..=3_600_000))]
    pub deadline_ms: Option<u64>,
    /// With --replan: hidden buildings per flight.
    #[arg(long, value_name = "K", default_value_t = 3, requires = "replan")]
    pub hidden_random: usize,
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
    #[arg(long, value_name = "K", default_value_t = 1.0, value_parser = within(0.1, 1000.0), allow_negative_numbers = true)]
    pub speedup: f64,
    /// Write the flight log (time, state, position, target) as CSV.
    #[arg(long, value_name = "FILE")]
    pub log: Option<PathBuf>,
    /// Wall-clock budget of the flight, seconds: past it the vehicle is told to land, and the exit is non-zero.
    #[arg(long, value_name = "T", value_parser = positive_up_to(1e6), allow_negative_numbers = true)]
    pub timeout_s: Option<f64>,
    /// A vehicle silent this long (no heartbeat, wall seconds) has lost the link.
    #[arg(long, value_name = "S", default_value_t = 5.0, value_parser = positive_up_to(1e6), allow_negative_numbers = true)]
    pub link_timeout_s: f64,
    /// How long to wait for the vehicle's heartbeat, EKF origin and position, vehicle seconds (wall seconds × --speedup); ArduCopter's EKF needs ~40 s after boot.
    #[arg(long, value_name = "S", default_value_t = 90.0, value_parser = positive_up_to(1e6), allow_negative_numbers = true)]
    pub wait_s: f64,
    /// Waypoint deadband, horizontal metres.
    #[arg(long, value_name = "M", default_value_t = 1.0, value_parser = positive_up_to(1e6), allow_negative_numbers = true)]
    pub deadband_m: f64,
    /// Serve the live view on this address (e.g. 127.0.0.1:8080): the map, the route and the
    /// vehicle (position, heading, trail, state, waypoint) at 5 updates per second.
    #[arg(long, value_name = "ADDR")]
    pub view: Option<String>,
    /// Record the flight (route, vehicle pose and state) as MCAP with Foxglove's JSON schemas.
    #[arg(long, value_name = "FILE.mcap")]
    pub record: Option<PathBuf>,
    /// Upload the plan as a mission (take-off, waypoints with headings, land) and fly it in AUTO. With --trajectory, each leg's speed (DO_CHANGE_SPEED) and each waypoint's acceptance radius come from the trajectory.
    #[arg(long)]
    pub upload: bool,
    /// Before take-off, upload the --no-fly zones as the vehicle's fence (MAVLink mission
    /// protocol, mission_type FENCE: polygon vertices and circles, inclusion or exclusion), read
    /// it back and check it item by item; a refusal or a difference stops before arming. Zones
    /// go as the file gives them, not grown by the margin (the autopilot applies its own
    /// FENCE_MARGIN). A fence is 2D and has no holes: exclusion zones whose band the route flies
    /// clear of are left out, bands and time windows are lost, an inclusion polygon's holes go as
    /// exclusion polygons, an exclusion polygon's holes are refused if the route uses them —
    /// each told. FENCE_ENABLE and FENCE_TYPE are not set (with the fence enabled, the
    /// autopilot's FENCE_ACTION acts on a breach). Works in GUIDED and with --upload.
    #[arg(long)]
    pub fence: bool,
    /// Upload the mission and exit without flying (interop tests).
    #[arg(long, hide = true)]
    pub upload_only: bool,
    /// What Ctrl-C commands in flight.
    #[arg(long, value_enum, value_name = "ACTION", default_value = "land")]
    pub on_interrupt: skyplan_flight::executor::FailsafeAction,
    /// What to command when a lost link comes back within 6 × --link-timeout-s [default: none, a lost link ends the flight at once].
    #[arg(long, value_enum, value_name = "ACTION")]
    pub failsafe: Option<skyplan_flight::executor::FailsafeAction>,
    /// With --sim: simulated seconds after boot until the vehicle's EKF has a position (its origin at half of it); ArduCopter SITL needs ~40 s.
    #[arg(long, value_name = "S", default_value_t = skyplan_link::vehicle::DEFAULT_EKF_DELAY_S, value_parser = within(0.0, 1e6), allow_negative_numbers = true, requires = "sim")]
    pub sim_ekf_delay_s: f64,
    /// Fault injection for tests: the simulated vehicle goes silent after this many simulated seconds.
    #[arg(long, value_name = "S", value_parser = within(0.0, 1e6), allow_negative_numbers = true, hide = true, requires = "sim")]
    pub sim_drop_link_after_s: Option<f64>,
    /// Fault injection for tests: the silence lasts this many simulated seconds, then the link comes back.
    #[arg(long, value_name = "S", value_parser = within(0.0, 1e6), allow_negative_numbers = true, hide = true, requires = "sim_drop_link_after_s")]
    pub sim_link_gap_s: Option<f64>,
    /// With --sim: obstacles in the simulated world that the map does not have (colliders format, same lat0/lon0 as the map); the sensor and the collision check see them.
    #[arg(long, value_name = "FILE", requires = "sim")]
    pub hidden: Option<PathBuf>,
    /// With --sim: range of the simulated obstacle sensor (OBSTACLE_DISTANCE), metres, 0.5 to 650.
    #[arg(long, value_name = "M", default_value_t = skyplan_link::vehicle::DEFAULT_SENSOR_RANGE_M, value_parser = within(0.5, 650.0), allow_negative_numbers = true, requires = "sim")]
    pub sensor_range_m: f64,
    /// With --sim: how the simulated vehicle reports its sensor: obstacle-distance (OBSTACLE_DISTANCE, 72 sectors of 5°, as a companion computer's sensor) or distance-sensor (eight DISTANCE_SENSOR wedges of 45°, only when asked, as ArduCopter's proximity library)
    #[arg(long, value_enum, default_value_t = ProximityArg::ObstacleDistance, requires = "sim")]
    pub proximity: ProximityArg,
    /// With --sim: N random buildings on or near the planned route, unknown to the map (seeded by --seed; never on the ends, never sealing the goal).
    #[arg(long, value_name = "N", default_value_t = 0, requires = "sim")]
    pub hidden_random: usize,
    /// Replan in flight from the vehicle's OBSTACLE_DISTANCE readings (2D grid planners, GUIDED): D* Lite repairing one search, JPS from scratch, or off. --max-alt-m bounds climbing over what blocks the way.
    #[arg(long, value_enum, default_value_t = crate::replan_cmd::ReplannerArg::DstarLite)]
    pub replanner: crate::replan_cmd::ReplannerArg,
    /// Draw the flight (.png/.svg): the map, the first plan, hidden obstacles, learned cells, replanned routes and the flown track.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Also write the planned waypoints to this file (.json .csv .h5 .geojson .plan).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Waypoint file format, overriding the extension.
    #[arg(long, value_name = "FORMAT")]
    pub format: Option<String>,
    #[command(flatten)]
    pub route: RouteArgs,
}

#[derive(Debug, Args)]
pub struct SimArgs {
    /// Where to listen: tcp:HOST:PORT (TCP server; port 0 picks one), tcpin:, udpin:HOST:PORT.
    #[arg(long, value_name = "ADDRESS", default_value = "tcp:127.0.0.1:5760")]
    pub listen: String,
    /// Home (start position) as latitude,longitude; default: the map's home.
    #[arg(long, value_name = "LAT,LON", value_parser = lat_lon, allow_hyphen_values = true)]
    pub home: Option<[f64; 2]>,
    /// Map whose obstacles the flown track is checked against and the sensor sees: .csv (colliders), .geojson or .osm/.osm.pbf (building footprints about the data's centre, as fly places them) [default: the bundled city map].
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// Simulated seconds per wall second.
    #[arg(long, value_name = "K", default_value_t = 1.0, value_parser = within(0.1, 1000.0), allow_negative_numbers = true)]
    pub speedup: f64,
    /// Stop after this many wall seconds (default: run until killed).
    #[arg(long, value_name = "S", value_parser = positive_up_to(1e6), allow_negative_numbers = true)]
    pub duration_s: Option<f64>,
    /// Simulated seconds after boot until the EKF has a position (its origin at half of it); ArduCopter SITL needs ~40 s.
    #[arg(long, value_name = "S", default_value_t = skyplan_link::vehicle::DEFAULT_EKF_DELAY_S, value_parser = within(0.0, 1e6), allow_negative_numbers = true)]
    pub ekf_delay_s: f64,
    /// Fault injection for tests: go silent after this many simulated seconds.
    #[arg(long, value_name = "S", value_parser = within(0.0, 1e6), allow_negative_numbers = true, hide = true)]
    pub drop_link_after_s: Option<f64>,
    /// Obstacles in the simulated world that the map does not have (colliders format, same lat0/lon0 as the map); the sensor and the collision check see them.
    #[arg(long, value_name = "FILE")]
    pub hidden: Option<PathBuf>,
    /// The ground, a DEM (GeoTIFF or SRTM .hgt) covering the map: the vehicle stands on it, lands on it, and flying into it is a ground strike; the map's buildings stand on it.
    #[arg(long, value_name = "FILE")]
    pub terrain: Option<PathBuf>,
    /// Range of the simulated obstacle sensor (OBSTACLE_DISTANCE), metres, 0.5 to 650.
    #[arg(long, value_name = "M", default_value_t = skyplan_link::vehicle::DEFAULT_SENSOR_RANGE_M, value_parser = within(0.5, 650.0), allow_negative_numbers = true)]
    pub sensor_range_m: f64,
    /// How the simulated vehicle reports its sensor: obstacle-distance (OBSTACLE_DISTANCE, 72 sectors of 5°, as a companion computer's sensor) or distance-sensor (eight DISTANCE_SENSOR wedges of 45°, only when asked, as ArduCopter's proximity library)
    #[arg(long, value_enum, default_value_t = ProximityArg::ObstacleDistance)]
    pub proximity: ProximityArg,
    /// Serve the live view on this address (e.g. 127.0.0.1:8080): the map, the vehicle (position, heading, mode, armed) and what its sensor sees, at 10 updates per second.
    #[arg(long, value_name = "ADDR")]
    pub view: Option<String>,
}

#[derive(Debug, Args)]
pub struct ServeArgs {
    /// Map to serve: .csv (colliders), .yaml (map_server), .png/.pgm (with --resolution), .map (MovingAI), .geojson (building footprints) or .osm/.osm.pbf (OpenStreetMap buildings) [default: the bundled city].
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// The map's options: --resolution, --unknown-free, --random, --density, --home.
    #[command(flatten)]
    pub grid: crate::grid_args::GridMapArgs,
    /// The ground under the map, a DEM (GeoTIFF or SRTM .hgt): plans keep alt_agl_m above it, and the page draws its contours.
    #[arg(long, value_name = "FILE")]
    pub terrain: Option<PathBuf>,
    /// No-fly zones (GeoJSON, as plan --no-fly reads): the page draws them and plans around them (API requests give their own no_fly).
    #[arg(long, value_name = "FILE")]
    pub no_fly: Option<PathBuf>,
    /// Address to listen on; only loopback unless another address is named.
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1:8080")]
    pub bind: std::net::SocketAddr,
    /// Plans computed at once; more requests wait in the queue [default: the number of cores].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=1024))]
    pub max_concurrent: Option<u16>,
    /// Requests that may wait for a worker, first in first out; more get 503 with Retry-After (0: no queue) [default: 64 per worker].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=1_000_000))]
    pub queue_depth: Option<u32>,
    /// Time budget of one request from its arrival, queue included, milliseconds; past it the answer is 504.
    #[arg(long, value_name = "MS", default_value_t = 10_000, value_parser = clap::value_parser!(u64).range(1..=600_000))]
    pub timeout_ms: u64,
    /// Where the shared airspace's operational intents are kept: sqlite:FILE (a SQLite file in WAL mode; servers on the same file share one airspace), postgres://USER@HOST:PORT/DATABASE (PostgreSQL; servers on the same database, on any machines, share one airspace; TLS with ?sslmode=require or verify-full, the server's certificate always checked, against &sslrootcert=CA.pem or the public web CAs; &sslcert=C.pem&sslkey=K.pem for a client certificate) or sqlite::memory: (this server's memory, gone when it stops).
    #[arg(long, value_name = "URL", default_value = skyplan_server::DEFAULT_AIRSPACE)]
    pub airspace: String,
}

/// How a simulated vehicle reports its proximity sensor (`--proximity`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ProximityArg {
    /// OBSTACLE_DISTANCE: 72 sectors of 5°, unrequested.
    ObstacleDistance,
    /// DISTANCE_SENSOR: eight 45° wedges, once asked for (ArduCopter).
    DistanceSensor,
}

impl From<ProximityArg> for skyplan_link::vehicle::Proximity {
    fn from(p: ProximityArg) -> Self {
        match p {
            ProximityArg::ObstacleDistance => Self::ObstacleDistance,
            ProximityArg::DistanceSensor => Self::DistanceSensor,
        }
    }
}
