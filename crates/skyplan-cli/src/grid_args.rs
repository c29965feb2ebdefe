//! Options of the grid-map planners (`plan --planner wavefront|costmap`, image, MovingAI and
//! random maps) and of `skyplan navigate`.

use clap::Args;
use skyplan_plan::cli::{finite, pair};
use std::path::PathBuf;

/// A grid size typed as `WxH` (columns × rows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

fn parse_size(s: &str) -> Result<Size, String> {
    let (w, h) = s
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT like `20x10`, found {s:?}"))?;
    let num = |t: &str| match t.trim().parse::<u32>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!("expected a whole number ≥ 1, found {t:?} in {s:?}")),
    };
    Ok(Size {
        width: num(w)?,
        height: num(h)?,
    })
}

fn parse_probability(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(p) if (0.0..=1.0).contains(&p) => Ok(p),
        _ => Err(format!("expected a probability in [0, 1], found {s:?}")),
    }
}

/// A list of targets typed as `N,E;N,E;…`.
#[derive(Debug, Clone, PartialEq)]
pub struct Targets(pub Vec<[f64; 2]>);

/// `N,E;N,E;…`
pub fn parse_targets(s: &str) -> Result<Targets, String> {
    s.split(';')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(pair)
        .collect::<Result<Vec<_>, _>>()
        .and_then(|v| {
            if v.is_empty() {
                Err("expected at least one target N,E".into())
            } else {
                Ok(Targets(v))
            }
        })
}

/// `STEP:N,E`
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChangeArg {
    pub at_step: u64,
    pub target: [f64; 2],
}

fn parse_change(s: &str) -> Result<ChangeArg, String> {
    let (step, target) = s
        .split_once(':')
        .ok_or_else(|| format!("expected STEP:N,E like `12:40,30`, found {s:?}"))?;
    let at_step = step
        .trim()
        .parse::<u64>()
        .map_err(|_| format!("expected a step count before `:`, found {step:?}"))?;
    Ok(ChangeArg {
        at_step,
        target: pair(target)?,
    })
}

/// How grid maps are read or drawn (flattened into `plan`, `fly` and `navigate`).
#[derive(Debug, Args, Default)]
pub struct GridMapArgs {
    /// Metres per pixel of a bare .png/.pgm map (a .yaml map gives its own).
    #[arg(long, value_name = "M", value_parser = finite, allow_negative_numbers = true)]
    pub resolution: Option<f64>,
    /// Count unknown pixels of an image map as free (default: blocked).
    #[arg(long)]
    pub unknown_free: bool,
    /// Plan on a random workspace of WIDTHxHEIGHT 1 m cells instead of a map file.
    #[arg(long, value_name = "WxH", value_parser = parse_size, conflicts_with = "map")]
    pub random: Option<Size>,
    /// Probability that a cell of the random workspace is blocked.
    #[arg(long, value_name = "P", value_parser = parse_probability, default_value_t = 0.25)]
    pub density: f64,
    /// Geodetic home LAT,LON of the map's origin, for lat/lon of waypoints on maps without one
    /// (images, MovingAI, random); on a .geojson map, the home its footprints are placed about
    /// (default: the centre of the data).
    #[arg(long, value_name = "LAT,LON", value_parser = skyplan_plan::cli::pair, allow_hyphen_values = true)]
    pub home: Option<[f64; 2]>,
}

#[derive(Debug, Args)]
pub struct NavigateArgs {
    /// Map: .csv colliders, .yaml map_server, .png/.pgm (with --resolution) or .map MovingAI
    /// [default: the bundled FCND city map].
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    #[command(flatten)]
    pub slice: crate::args::SliceArgs,
    /// Where the vehicle starts, metres north,east of the map's origin.
    #[arg(long, value_name = "N,E", value_parser = pair, allow_hyphen_values = true)]
    pub start_ne: Option<[f64; 2]>,
    /// Targets to visit in order: `N,E;N,E;…` (metres north,east).
    #[arg(long, value_name = "N,E;…", value_parser = parse_targets, allow_hyphen_values = true)]
    pub targets: Option<Targets>,
    /// File of targets, one `N,E` per line (`#` comments).
    #[arg(long, value_name = "FILE", conflicts_with = "targets")]
    pub targets_file: Option<PathBuf>,
    /// At step STEP, replace the current target by N,E and replan (repeatable).
    #[arg(long, value_name = "STEP:N,E", value_parser = parse_change, allow_hyphen_values = true)]
    pub change_target_at: Vec<ChangeArg>,
    #[command(flatten)]
    pub moves: crate::args::MovesArgs,
    /// Heat map of the cost map with the route (.png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub memory: crate::args::MemoryArgs,
    /// Print the workspace and the ride as text (grids up to 80 × 60).
    #[arg(long)]
    pub show: bool,
    #[command(flatten)]
    pub grid: GridMapArgs,
    /// Seed of the random workspace (--random) and of its drawn start and target.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub costmap: skyplan_plan::CostmapOptions,
}
