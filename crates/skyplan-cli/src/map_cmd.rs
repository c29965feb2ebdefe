//! `skyplan map tile`: big test worlds from a colliders map; `skyplan map maze` and `map rooms`:
//! MovingAI mazes and room maps, with scenarios of exact lengths.

use crate::args::TileArgs;
use crate::exit::{Result, bad_input};
use crate::files::{map_text, output_target, write_target};

pub fn tile(args: TileArgs) -> Result<()> {
    let target = output_target("--out", &args.out)?;
    let (name, text) = map_text(args.map.as_deref(), skyplan_plan::FCND_CITY_NAME)?;
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{name}: {e}")))?;
    let world = skyplan_plan::World::from_colliders(&name, map.clone())?;
    let b = world.bounds_ne(1.0);
    let extent_m = (b.north_max_m - b.north_min_m).max(b.east_max_m - b.east_min_m);
    let pitch_m = args.pitch_m.unwrap_or((extent_m / 10.0).ceil() * 10.0);
    let big = skyplan_map::tile(&map, args.times, pitch_m);
    write_target(&target, skyplan_map::to_colliders_csv(&big).as_bytes())?;
    let side_km = (f64::from(args.times - 1) * pitch_m + extent_m) / 1000.0;
    println!(
        "wrote      {}: {} boxes, {k} × {k} copies of {name} every {pitch_m} m ({side_km:.1} km square)",
        args.out.display(),
        big.boxes.len(),
        k = args.times
    );
    Ok(())
}

/// Where a generated MovingAI map and its scenarios go (`map maze`, `map rooms`).
#[derive(Debug, clap::Args)]
pub struct GeneratedOut {
    /// Seed: the same options make the same map and scenarios on every machine.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// The map (.map, MovingAI octile format).
    #[arg(long, value_name = "FILE")]
    pub out: std::path::PathBuf,
    /// Also write scenarios (.scen, MovingAI version 1) whose optimal lengths are exact
    /// (Dijkstra, 8-connected, no corner cutting: what `skyplan scen` checks).
    #[arg(long, value_name = "FILE")]
    pub scen: Option<std::path::PathBuf>,
    /// Scenarios to write with --scen.
    #[arg(long, value_name = "N", default_value_t = 1000, requires = "scen",
          value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub queries: u64,
}

/// `skyplan map maze`: a seeded perfect maze shaped like MovingAI's `maze512-C-k` maps.
#[derive(Debug, clap::Args)]
pub struct MazeArgs {
    /// Columns and rows of the map.
    #[arg(long, num_args = 2, value_names = ["W", "H"], required = true,
          value_parser = clap::value_parser!(u32).range(2..=32768))]
    pub size: Vec<u32>,
    /// Corridor width, cells (walls are one cell thick, as in MovingAI's mazes).
    #[arg(long, value_name = "C", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub corridor_cells: u32,
    #[command(flatten)]
    pub out: GeneratedOut,
}

/// `skyplan map rooms`: seeded rooms shaped like MovingAI's `Rroom_k` maps.
#[derive(Debug, clap::Args)]
pub struct RoomsArgs {
    /// Columns and rows of the map.
    #[arg(long, num_args = 2, value_names = ["W", "H"], required = true,
          value_parser = clap::value_parser!(u32).range(2..=32768))]
    pub size: Vec<u32>,
    /// Room width, cells (walls are one cell thick).
    #[arg(long, value_name = "R", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub room_cells: u32,
    /// Door width, cells (1 to R) [default: a quarter of R, at least 1].
    #[arg(long, value_name = "D", value_parser = clap::value_parser!(u32).range(1..=64))]
    pub door_cells: Option<u32>,
    #[command(flatten)]
    pub out: GeneratedOut,
}

pub fn maze(args: MazeArgs) -> Result<()> {
    let spec = skyplan_map::maze::MazeSpec {
        width: args.size[0] as usize,
        height: args.size[1] as usize,
        corridor_cells: args.corridor_cells as usize,
        seed: args.out.seed,
    };
    write_generated(&args.out, || {
        let map = skyplan_map::maze::generate(&spec)
            .map_err(|e| bad_input(format!("--size/--corridor-cells: {e}")))?;
        let what = format!("maze, corridor width {} cells", spec.corridor_cells);
        Ok((map, what))
    })
}

pub fn rooms(args: RoomsArgs) -> Result<()> {
    let room = args.room_cells as usize;
    let spec = skyplan_map::maze::RoomsSpec {
        width: args.size[0] as usize,
        height: args.size[1] as usize,
        room_cells: room,
        door_cells: args.door_cells.map_or((room / 4).max(1), |d| d as usize),
        seed: args.out.seed,
    };
    write_generated(&args.out, || {
        let map = skyplan_map::maze::generate_rooms(&spec)
            .map_err(|e| bad_input(format!("--size/--room-cells/--door-cells: {e}")))?;
        let what = format!(
            "rooms of {} cells, doors of {} cells",
            spec.room_cells, spec.door_cells
        );
        Ok((map, what))
    })
}

/// Checks the output names, makes the map (`make`: the map and what it is, for the report) and
/// its scenarios, then writes both: a refused run leaves no file.
fn write_generated(
    out: &GeneratedOut,
    make: impl FnOnce() -> Result<(skyplan_map::movingai::MovingAiMap, String)>,
) -> Result<()> {
    use skyplan_map::{maze, movingai};
    let has_ext = |p: &std::path::Path, ext: &str| p.extension().is_some_and(|e| e == ext);
    if !has_ext(&out.out, "map") {
        return Err(bad_input(format!(
            "--out {}: expected a .map file name",
            out.out.display()
        )));
    }
    let map_target = output_target("--out", &out.out)?;
    let scen_target = match &out.scen {
        Some(path) if !has_ext(path, "scen") => {
            return Err(bad_input(format!(
                "--scen {}: expected a .scen file name",
                path.display()
            )));
        }
        Some(path) => Some(output_target("--scen", path)?),
        None => None,
    };
    let (map, what) = make()?;
    // Everything is computed before anything is written.
    let scen = match &out.scen {
        Some(_) => {
            let name = out.out.file_name().map_or_else(
                || out.out.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            let count = usize::try_from(out.queries).unwrap_or(usize::MAX);
            let list = maze::scenarios(&map, &name, count, out.seed)
                .map_err(|e| bad_input(format!("--scen: {e}")))?;
            Some(movingai::to_scen_text(&list, map.width, map.height))
        }
        None => None,
    };
    write_target(&map_target, movingai::to_map_text(&map).as_bytes())?;
    let free = map.passable.iter().filter(|&&p| p).count();
    println!(
        "wrote      {}: {} × {} {what}, seed {} ({free} free cells)",
        out.out.display(),
        map.width,
        map.height,
        out.seed
    );
    if let (Some(target), Some(text), Some(path)) = (scen_target, scen, &out.scen) {
        write_target(&target, text.as_bytes())?;
        println!(
            "wrote      {}: {} scenarios with exact optimal lengths",
            path.display(),
            out.queries
        );
    }
    Ok(())
}
