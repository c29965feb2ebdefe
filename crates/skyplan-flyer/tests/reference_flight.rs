//! A whole run flown by a reference made from the plan: the simulator in-process, the plan from
//! where the vehicle is, a minimum-jerk reference through the plan's waypoints, the summary's
//! tracking line.

use skyplan_flight::executor::{ExecutorConfig, Outcome};
use skyplan_flight::reference::{MinJerkLine, Reference};
use skyplan_flyer::flight::Observer;
use skyplan_flyer::runner::{
    self, Ended, FlyOptions, Mode, ReferenceSource, RunError, RunObserver,
};
use skyplan_link::ground::GroundConfig;
use skyplan_link::vehicle::SimServerConfig;
use skyplan_plan::{Limits, PlanRequest, World};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};

/// Two buildings off the route, at the corners of the map.
const MAP: &str = "lat0 37.792480, lon0 -122.397450\nposX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n-40,-40,10,5,5,10\n130,120,10,5,5,10\n";

#[derive(Default)]
struct Lines(Vec<String>);

impl Observer for Lines {
    fn say(&mut self, line: &str) {
        self.0.push(line.to_string());
    }
}

impl RunObserver for Lines {
    type Error = RunError;
}

#[test]
fn a_run_flies_the_reference_made_from_its_plan_and_tells_the_tracking() {
    let world = World::from_colliders_csv("one.csv", MAP).unwrap();
    let frame = *world.frame().unwrap();
    let request = PlanRequest {
        goal_ne: Some([70.0, 60.0]),
        alt_m: Some(10.0),
        ..PlanRequest::default()
    };
    let speedup = 20.0;
    let config = SimServerConfig {
        speedup,
        ekf_delay_s: 1.0,
        ..SimServerConfig::at(frame.home())
    };
    let (sim, _) = runner::start_sim(
        runner::map_obstacles(&world).unwrap().unwrap(),
        &frame,
        &request,
        config,
    )
    .unwrap();
    let options = FlyOptions {
        ground: GroundConfig {
            speedup,
            timeout_s: Some(60.0),
            ..GroundConfig::default()
        },
        executor: ExecutorConfig::default(),
        wait_s: 60.0,
        mode: Mode::Guided(None),
        fence: false,
        user_start: false,
    };
    // The plan's waypoints at 7 m/s at most, rest to rest; kept to check against.
    let made: Arc<Mutex<Option<Arc<MinJerkLine>>>> = Arc::default();
    let keep = Arc::clone(&made);
    let source = ReferenceSource::FromPlan(Arc::new(move |plan| {
        let points = plan.waypoints.iter().map(|w| [w[0], w[1], -w[2]]).collect();
        let r = Arc::new(MinJerkLine::at_peak_speed(points, 7.0).map_err(|e| e.to_string())?);
        *keep.lock().unwrap() = Some(Arc::clone(&r));
        Ok(r as Arc<dyn Reference>)
    }));
    let mut lines = Lines::default();
    let flight = runner::fly_mission_with(
        &sim.address(),
        &frame,
        (world, Limits::default(), request),
        &options,
        Some(&source),
        Some(&sim),
        Arc::new(AtomicBool::new(false)),
        &mut lines,
    )
    .unwrap();
    let (report, _) = sim.finish();
    let text = lines.0.join("\n");
    assert_eq!(
        flight.ended,
        Ended::Flight(Some(Outcome::Completed)),
        "{text}"
    );
    assert_eq!(
        runner::verdict(
            Some(Outcome::Completed),
            report.as_ref(),
            runner::plan_margin_m(&flight.plan),
            flight.tracking.as_ref(),
            None
        ),
        Ok(())
    );
    let r = made.lock().unwrap().clone().unwrap();
    let goal = r.setpoint(r.duration_s()).point_ned;
    let last = flight.log.last().unwrap();
    assert!(
        (last.north_m - goal[0]).hypot(last.east_m - goal[1]) < 1.5,
        "{text}"
    );
    assert!((goal[0] - 70.0).hypot(goal[1] - 60.0) < 1.0, "{goal:?}");
    // The reference line: plain words, units in names, its numbers.
    let line = lines
        .0
        .iter()
        .find(|l| l.starts_with("reference  max tracking error "))
        .unwrap_or_else(|| panic!("{text}"));
    let error_m: f64 = line["reference  max tracking error ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(error_m <= 0.5, "{line}");
    assert!(
        line.contains(&format!("reference duration {:.1} s", r.duration_s())),
        "{line}"
    );
    assert!(
        lines
            .0
            .iter()
            .any(|l| l.starts_with("reference  ") && l.contains(" s from N ")),
        "{text}"
    );
    assert!(
        text.contains("result     landed and disarmed after flying the reference to its end"),
        "{text}"
    );
    assert!(!text.contains("Some(") && !text.contains("{ "), "{text}");
}

#[test]
fn a_reference_is_not_uploaded() {
    let world = World::from_colliders_csv("one.csv", MAP).unwrap();
    let frame = *world.frame().unwrap();
    let options = FlyOptions {
        ground: GroundConfig::default(),
        executor: ExecutorConfig::default(),
        wait_s: 1.0,
        mode: Mode::Upload { fly: true },
        fence: false,
        user_start: false,
    };
    let r = MinJerkLine::new(vec![[0.0, 0.0, -5.0], [10.0, 0.0, -5.0]], vec![5.0]).unwrap();
    let source = ReferenceSource::Given(Arc::new(r));
    let got = runner::fly_mission_with(
        &skyplan_link::Address::TcpOut("127.0.0.1:9".into()),
        &frame,
        (world, Limits::default(), PlanRequest::default()),
        &options,
        Some(&source),
        None,
        Arc::new(AtomicBool::new(false)),
        &mut Lines::default(),
    );
    assert!(matches!(got, Err(RunError::BadInput(e)) if e.contains("GUIDED")));
}
