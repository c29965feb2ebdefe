//! `skyplan sim`: the built-in simulated multicopter as a MAVLink vehicle.

use crate::args::SimArgs;
use crate::exit::{Classify, Kind, Result, bad_input};
use crate::files::{map_text, read_text};
use skyplan_flyer::flight::sim_listening_line;
use skyplan_flyer::words::sim_note_line;
use skyplan_frames::Lla;
use skyplan_link::vehicle::{SimServer, SimServerConfig};
use skyplan_link::{Address, Role};
use skyplan_plan::FCND_CITY_NAME;
use std::time::Duration;

/// Reads `--hidden FILE`: boxes in the colliders format whose `lat0/lon0` line must be the
/// map's home (the boxes are in the map's frame).
pub(crate) fn load_hidden(
    path: &std::path::Path,
    map_home: &skyplan_map::colliders::GeodeticHome,
) -> Result<Vec<skyplan_map::colliders::ObstacleBox>> {
    skyplan_map::colliders::parse_hidden(&read_text(path)?, map_home)
        .map_err(|e| bad_input(format!("--hidden {}: {e}", path.display())))
}

/// The map's home, and where the vehicle starts: `--home`, else the map's home.
fn homes(args: &SimArgs, map_home: &skyplan_map::colliders::GeodeticHome) -> (Lla, Lla) {
    let at = |[lat_deg, lon_deg]: [f64; 2]| Lla {
        lat_deg,
        lon_deg,
        alt_m: 0.0,
    };
    let map_home = at([map_home.lat_deg, map_home.lon_deg]);
    (map_home, args.home.map_or(map_home, at))
}

/// The simulator's map: a colliders file (or the bundled city), or building footprints
/// (`.geojson`, `.osm`, `.osm.pbf`, about the data's centre as `plan` and `fly` place them).
fn sim_world(args: &SimArgs) -> Result<(String, skyplan_plan::World)> {
    use skyplan_plan::MapFormat;
    if let Some(path) = args.map.as_deref()
        && matches!(
            MapFormat::of_path(path),
            Some(MapFormat::GeoJson | MapFormat::Osm | MapFormat::OsmPbf)
        )
    {
        let world = crate::world_load::load_world(
            Some(path),
            &crate::grid_args::GridMapArgs::default(),
            1,
            &skyplan_plan::Limits::default(),
        )?;
        return Ok((path.display().to_string(), world));
    }
    let (map_name, text) = map_text(args.map.as_deref(), FCND_CITY_NAME)?;
    let world = skyplan_plan::World::from_colliders_csv(&map_name, &text)
        .map_err(|e| bad_input(format!("{map_name}: {}", e.message)))?;
    Ok((map_name, world))
}

pub fn run(args: SimArgs) -> Result<()> {
    let address = Address::parse(&args.listen, Role::Server).map_err(bad_input)?;
    let (map_name, mut map_world) = sim_world(&args)?;
    if let Some(path) = &args.terrain {
        map_world = crate::world_load::with_terrain(map_world, path)?;
    }
    let (Some(world), Some(frame)) = (
        skyplan_flyer::runner::map_obstacles(&map_world)?,
        map_world.frame(),
    ) else {
        return Err(bad_input(format!(
            "{map_name}: the simulator needs a map of obstacles with a geodetic home (FCND colliders, GeoJSON or OpenStreetMap footprints)"
        )));
    };
    let map_home = skyplan_map::colliders::GeodeticHome {
        lat_deg: frame.home().lat_deg,
        lon_deg: frame.home().lon_deg,
    };
    let (map_home_lla, mut home) = homes(&args, &map_home);
    if let Some(t) = map_world.terrain() {
        // The vehicle stands on the ground: its home's height above mean sea level.
        let at = (frame.ned_from_lla(home)).map_err(|e| bad_input(format!("--home: {e}")))?;
        let ground_m = (t.ground_m(at.north_m, at.east_m))
            .map_err(|e| bad_input(format!("--terrain: under the vehicle's home: {e}")))?;
        home.alt_m = t.amsl_m(ground_m);
    }
    let hidden = (args.hidden.as_ref())
        .map(|path| load_hidden(path, &map_home))
        .transpose()?
        .unwrap_or_default();
    let config = SimServerConfig {
        hidden,
        sensor_range_m: args.sensor_range_m,
        proximity: args.proximity.into(),
        speedup: args.speedup,
        drop_link_after_s: args.drop_link_after_s,
        ekf_delay_s: args.ekf_delay_s,
        map_home: Some(map_home_lla),
        terrain: map_world.terrain_shared(),
        ..SimServerConfig::at(home)
    };
    let server = SimServer::bind(&address, config.clone()).or_exit(Kind::Runtime)?;
    let shown = match (server.local_addr(), &address) {
        (Some(a), Address::TcpIn(_)) => format!("tcp:{a}"),
        _ => address.to_string(),
    };
    let hidden_from = args.hidden.as_ref().map(|p| p.display().to_string());
    let line = sim_listening_line(&shown, &config, &map_name, hidden_from.as_deref());
    println!("{line}");
    let mut live = match &args.view {
        Some(addr) => crate::live::Live::start(&map_world, Some(addr), None)?,
        None => crate::live::Live::default(),
    };
    let stop = SimServer::stop_after(args.duration_s);
    let map_boxes = world.len();
    let report = server.run_with_state(
        Some(&world),
        &stop,
        |n| {
            if let Some(line) = sim_note_line(&n) {
                println!("sim        {line}");
            }
        },
        Duration::from_millis(100),
        |s| live.events.sim_status(s),
    );
    println!(
        "{}",
        skyplan_flyer::flight::sim_stopped_line(&report, map_boxes)
    );
    Ok(())
}
