//! `skyplan sim`: the built-in simulated multicopter as a MAVLink vehicle.

use crate::args::SimArgs;
use crate::exit::{Classify, Kind, Result, bad_input};
use crate::files::{map_text, read_text};
use skyplan_flight::collision::BoxWorld;
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

/// `--view ADDR`: the live view of the simulator's state.
fn live_view(args: &SimArgs, map_name: &str, text: &str) -> Result<crate::live::Live> {
    let Some(addr) = &args.view else {
        return Ok(crate::live::Live::default());
    };
    let world = skyplan_plan::World::from_colliders_csv(map_name, text)
        .map_err(|e| bad_input(format!("{map_name}: {}", e.message)))?;
    crate::live::Live::start(&world, Some(addr), None)
}

pub fn run(args: SimArgs) -> Result<()> {
    let address = Address::parse(&args.listen, Role::Server).map_err(bad_input)?;
    let (map_name, text) = map_text(args.map.as_deref(), FCND_CITY_NAME)?;
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{map_name}: {e}")))?;
    let (map_home, home) = homes(&args, &map.home);
    let hidden = (args.hidden.as_ref())
        .map(|path| load_hidden(path, &map.home))
        .transpose()?
        .unwrap_or_default();
    let config = SimServerConfig {
        hidden,
        sensor_range_m: args.sensor_range_m,
        proximity: args.proximity.into(),
        speedup: args.speedup,
        drop_link_after_s: args.drop_link_after_s,
        ekf_delay_s: args.ekf_delay_s,
        map_home: Some(map_home),
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
    let mut live = live_view(&args, &map_name, &text)?;
    let stop = SimServer::stop_after(args.duration_s);
    let world = BoxWorld::new(&map.boxes);
    let map_boxes = map.boxes.len();
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
