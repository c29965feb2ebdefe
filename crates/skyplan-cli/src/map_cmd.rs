//! `skyplan map tile`: big test worlds from a colliders map.

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
