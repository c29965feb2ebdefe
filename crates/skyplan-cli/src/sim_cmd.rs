//! `skyplan sim`: the built-in simulated multicopter as a MAVLink vehicle.

use crate::args::SimArgs;
use crate::exit::{Classify, Kind, Result, bad_input};
use crate::files::read_text;
use skyplan_flight::collision::BoxWorld;
use skyplan_frames::Lla;
use skyplan_link::vehicle::{SimServer, SimServerConfig};
use skyplan_link::words::sim_note_line;
use skyplan_link::{Address, Role};
use skyplan_plan::{FCND_CITY_CSV as BUNDLED_COLLIDERS, FCND_CITY_NAME as BUNDLED_NAME};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

pub fn run(args: SimArgs) -> Result<()> {
    if !(args.speedup >= 0.1 && args.speedup <= 1000.0) {
        return Err(bad_input(format!(
            "--speedup: expected 0.1 to 1000, found {}",
            args.speedup
        )));
    }
    let address = Address::parse(&args.listen, Role::Server).map_err(bad_input)?;
    let (map_name, text) = match &args.map {
        Some(path) => (path.display().to_string(), read_text(path)?),
        None => (BUNDLED_NAME.to_string(), BUNDLED_COLLIDERS.to_string()),
    };
    let map = skyplan_map::colliders::parse_colliders(&text)
        .map_err(|e| bad_input(format!("{map_name}: {e}")))?;
    let home = match args.home {
        Some(p) => {
            if !(-90.0..=90.0).contains(&p.0) || !(-180.0..=180.0).contains(&p.1) {
                return Err(bad_input(format!(
                    "--home: expected latitude in [-90, 90] and longitude in [-180, 180], found {},{}",
                    p.0, p.1
                )));
            }
            Lla {
                lat_deg: p.0,
                lon_deg: p.1,
                alt_m: 0.0,
            }
        }
        None => Lla {
            lat_deg: map.home.lat_deg,
            lon_deg: map.home.lon_deg,
            alt_m: 0.0,
        },
    };
    if args.ekf_delay_s < 0.0 {
        return Err(bad_input(format!(
            "--ekf-delay-s: expected 0 or more, found {}",
            args.ekf_delay_s
        )));
    }
    let config = SimServerConfig {
        speedup: args.speedup,
        drop_link_after_s: args.drop_link_after_s,
        ekf_delay_s: args.ekf_delay_s,
        map_home: Some(Lla {
            lat_deg: map.home.lat_deg,
            lon_deg: map.home.lon_deg,
            alt_m: 0.0,
        }),
        ..SimServerConfig::at(home)
    };
    let server = SimServer::bind(&address, config).or_exit(Kind::Runtime)?;
    let shown = match (server.local_addr(), &address) {
        (Some(a), Address::TcpIn(_)) => format!("tcp:{a}"),
        _ => address.to_string(),
    };
    println!(
        "sim        simulated multicopter (MAVLink system 1, ArduCopter modes) listening on {shown}, \
         {}× real time, home lat {:.7}, lon {:.7}; obstacles from {map_name}",
        args.speedup, home.lat_deg, home.lon_deg
    );
    let stop = Arc::new(AtomicBool::new(false));
    if let Some(d) = args.duration_s {
        let stop = Arc::clone(&stop);
        let d = Duration::from_secs_f64(d.max(0.0));
        std::thread::spawn(move || {
            std::thread::sleep(d);
            stop.store(true, Ordering::Relaxed);
        });
    }
    let world = BoxWorld::new(&map.boxes);
    let report = server.run(Some(&world), &stop, |n| {
        if let Some(line) = sim_note_line(&n) {
            println!("sim        {line}");
        }
    });
    println!(
        "sim        stopped after {:.1} s simulated, {:.1} s wall; flown {:.1} m, {}",
        report.sim_time_s,
        report.wall_time_s,
        report.distance_m,
        match report.track.collision() {
            Some(c) => format!(
                "COLLISION with obstacle #{} at {:.1} s",
                c.box_index, c.time_s
            ),
            None => "no collision".into(),
        }
    );
    Ok(())
}
