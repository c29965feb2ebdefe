//! What `fly --view ADDR` / `sim --view ADDR` will do, with a made-up vehicle: plan the default
//! route, serve the page, and publish the route and the vehicle's state at 10 Hz along it
//! (take-off, waypoints, landing, MANUAL). Open the printed address while it runs.
//!
//! `cargo run --release -p skyplan-server --example view_flight -- 127.0.0.1:8080 [SPEEDUP]`

use skyplan_plan::{PlanRequest, Session, World};
use skyplan_server::{FlightEvent, RouteEvent, ViewEvent, ViewServer};
use std::time::Duration;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let addr = args.next().unwrap_or_else(|| "127.0.0.1:8080".into());
    let speedup: f64 = args.next().map_or(Ok(1.0), |s| s.parse())?;
    let world = World::fcnd_city();
    let plan = Session::new(world.clone()).plan(&PlanRequest::default())?;

    // The two lines fly/sim need: start the view, publish events.
    let view = ViewServer::start(world, &addr)?;
    view.publish(&ViewEvent::Route(RouteEvent {
        reason: "plan".into(),
        planner: plan.planner.to_string(),
        waypoints: plan.points_nea(),
        trajectory: None,
    }));
    println!("view: http://{}/", view.addr());

    let speed_m_s = 10.0;
    let dt_s = 0.1;
    let mut t_s = 0.0;
    let state = |t_s: f64, p: [f64; 3], heading_deg: f64, state: &str, wp: Option<usize>| {
        view.publish(&ViewEvent::Flight(FlightEvent {
            time_s: t_s,
            north_m: p[0],
            east_m: p[1],
            alt_m: p[2],
            heading_deg,
            speed_m_s: if state == "WAYPOINT" { speed_m_s } else { 0.0 },
            state: state.into(),
            waypoint_index: wp,
            armed: state != "MANUAL",
        }));
        std::thread::sleep(Duration::from_secs_f64(dt_s / speedup));
    };
    let points = plan.points_nea();
    let Some(&first) = points.first() else {
        return Ok(());
    };
    let cruise_m = first[2];
    for k in 0..=20 {
        let alt_m = cruise_m * f64::from(k) / 20.0;
        state(t_s, [first[0], first[1], alt_m], 0.0, "TAKEOFF", None);
        t_s += dt_s;
    }
    let mut here = first;
    for (i, target) in points.iter().enumerate().skip(1) {
        let (dn, de) = (target[0] - here[0], target[1] - here[1]);
        let heading_deg = de.atan2(dn).to_degrees().rem_euclid(360.0);
        let steps = ((dn.hypot(de) / (speed_m_s * dt_s)).ceil() as usize).max(1);
        let start = here;
        for s in 1..=steps {
            let f = s as f64 / steps as f64;
            here = [start[0] + f * dn, start[1] + f * de, target[2]];
            state(t_s, here, heading_deg, "WAYPOINT", Some(i));
            t_s += dt_s;
        }
    }
    for k in (0..=20).rev() {
        let alt_m = here[2] * f64::from(k) / 20.0;
        state(t_s, [here[0], here[1], alt_m], 0.0, "LANDING", None);
        t_s += dt_s;
    }
    state(t_s, [here[0], here[1], 0.0], 0.0, "MANUAL", None);
    // Keep serving a little so late pages still see the end.
    std::thread::sleep(Duration::from_secs(2));
    Ok(())
}
