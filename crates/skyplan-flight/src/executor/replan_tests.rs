//! Routes replaced in flight, and the hold-then-land when no route exists (GUIDED strategy),
//! closed loop against the simulated vehicle in simulated time.

use super::*;
use crate::sensing::ReplanEvent;
use crate::sim::{SimConfig, SimVehicle};
use crate::testkit::{apply, route, telemetry, wp};

fn event(t: f64) -> ReplanEvent {
    ReplanEvent {
        time_s: t,
        position_ned: [0.0; 3],
        reason: "learned cells block leg 3".into(),
        planner: "test".into(),
        latency_ms: 0.1,
        cpu_ms: Some(0.1),
        expansions: 7,
        route_length_m: 0.0,
        learned_cells: 3,
    }
}

/// What the loop does once, when `when(executor)` first holds.
enum Act {
    Replace(Vec<Target>),
    NoRoute,
}

struct Run {
    notes: Vec<Note>,
    /// Vehicle positions (N, E, up) from the act to the end.
    after: Vec<(f64, [f64; 3])>,
    acted_at: Option<(f64, [f64; 3], f64)>,
}

/// Flies at 10 Hz; acts once when `when` holds, recording the executor's answer.
fn fly(
    ex: &mut MissionExecutor,
    v: &mut SimVehicle,
    when: impl Fn(&MissionExecutor) -> bool,
    act: Act,
) -> Run {
    let mut run = Run {
        notes: Vec::new(),
        after: Vec::new(),
        acted_at: None,
    };
    let mut act = Some(act);
    let (mut t, mut pending) = (0.0, Vec::new());
    while ex.outcome().is_none() && t < 400.0 {
        for _ in 0..5 {
            v.step(0.02);
        }
        t += 0.1;
        let mut events = std::mem::take(&mut pending);
        events.push(Event::Telemetry(telemetry(v)));
        let mut outs = Vec::new();
        for e in events {
            outs.push(ex.handle(t, e));
        }
        if act.is_some() && when(ex) {
            let s = v.state();
            let p = [
                s.position_ned_m[0],
                s.position_ned_m[1],
                -s.position_ned_m[2],
            ];
            run.acted_at = Some((t, p, ex.distance_left_m()));
            outs.push(match act.take() {
                Some(Act::Replace(targets)) => ex.replace_route(t, &targets, event(t)).unwrap(),
                Some(Act::NoRoute) => ex.hold_no_route(t, "every way is blocked".into()),
                None => unreachable!(),
            });
        }
        for out in outs {
            run.notes.extend(out.notes);
            for c in out.commands {
                pending.extend(apply(v, c));
            }
        }
        if run.acted_at.is_some() {
            let s = v.state();
            run.after.push((
                t,
                [
                    s.position_ned_m[0],
                    s.position_ned_m[1],
                    -s.position_ned_m[2],
                ],
            ));
        }
    }
    run
}

/// After the second waypoint (20, 0), round by the south to the last.
fn detour_south() -> Vec<Target> {
    vec![
        wp(20.0, -10.0, -90.0),
        wp(-10.0, -10.0, 180.0),
        wp(-10.0, 15.0, 90.0),
    ]
}

#[test]
fn a_replaced_route_is_flown_to_its_end_without_landing_in_between() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    // After the second waypoint (20, 0), heading for (20, 20): go round by the south instead.
    let detour = detour_south();
    let run = fly(
        &mut ex,
        &mut v,
        |ex| ex.reached().len() == 2,
        Act::Replace(detour.clone()),
    );
    assert_eq!(ex.outcome(), Some(&Outcome::Completed), "{:?}", run.notes);
    // The note carries the new route; no state change between the act and the landing.
    let k = run
        .notes
        .iter()
        .position(|n| matches!(n, Note::Replanned { targets, .. } if *targets == detour))
        .expect("a Replanned note");
    let states: Vec<_> = run.notes[k..]
        .iter()
        .filter_map(|n| match n {
            Note::State { to, .. } => Some(*to),
            _ => None,
        })
        .collect();
    use FlightState::*;
    assert_eq!(states, vec![Landing, Disarming, Manual]);
    // Reached: the first route's 0 and 1, then the detour's 0, 1, 2.
    let idx: Vec<usize> = ex.reached().iter().map(|r| r.index).collect();
    assert_eq!(idx, vec![0, 1, 0, 1, 2]);
    assert!(ex.reached().iter().all(|r| r.horizontal_error_m <= 1.0));
    // It landed at the detour's end, never at the first route's end (0, 20).
    let s = v.state();
    assert!(s.on_ground && !s.armed);
    assert!((s.position_ned_m[0] + 10.0).abs() < 1.5 && (s.position_ned_m[1] - 15.0).abs() < 1.5);
    // It never went east of the detour's box: the old leg to (20, 20) was dropped at once.
    let max_east = run.after.iter().map(|(_, p)| p[1]).fold(f64::MIN, f64::max);
    assert!(max_east < 16.5, "went east to {max_east}");
    // Airborne all along the detour until the landing began at its end.
    let landing_t = run
        .after
        .iter()
        .find(|(_, p)| (p[0] + 10.0).abs() < 1.5 && (p[1] - 15.0).abs() < 1.5)
        .map(|(t, _)| *t)
        .unwrap();
    assert!(
        run.after
            .iter()
            .filter(|(t, _)| *t < landing_t)
            .all(|(_, p)| p[2] > 4.0)
    );
}

#[test]
fn distance_left_counts_the_new_route_from_the_vehicle() {
    let mut ex = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let detour = detour_south();
    // Act, then stop at the first telemetry after it: fly until just after the replan.
    let mut ex2 = ex.clone();
    let mut v2 = v.clone();
    let run = fly(
        &mut ex2,
        &mut v2,
        |ex| ex.reached().len() == 2,
        Act::Replace(detour.clone()),
    );
    let (t_act, _, _) = run.acted_at.unwrap();
    // Replay to the act on a fresh pair and read the bookkeeping right after it.
    let (mut t, mut pending) = (0.0, Vec::new());
    while t < t_act - 1e-9 {
        for _ in 0..5 {
            v.step(0.02);
        }
        t += 0.1;
        let mut events = std::mem::take(&mut pending);
        events.push(Event::Telemetry(telemetry(&v)));
        for e in events {
            for c in ex.handle(t, e).commands {
                pending.extend(apply(&mut v, c));
            }
        }
    }
    assert_eq!(ex.reached().len(), 2);
    let out = ex.replace_route(t, &detour, event(t)).unwrap();
    let tel = *ex.last_telemetry().unwrap();
    let expect =
        (detour[0].north_m - tel.north_m).hypot(detour[0].east_m - tel.east_m) + 30.0 + 25.0;
    assert!(
        (ex.distance_left_m() - expect).abs() < 1e-9,
        "{} vs {expect}",
        ex.distance_left_m()
    );
    assert_eq!(ex.remaining_targets(), &detour[..]);
    assert_eq!(ex.current_target(), Some((0, detour[0])));
    // The first target of the new route is sent at once.
    assert!(out.commands.iter().any(|c| {
        c.position_target()
            .is_some_and(|(p, _)| p[0] == 20.0 && p[1] == -10.0)
    }));
    // Outside WAYPOINT a replacement is refused and changes nothing.
    let mut idle = MissionExecutor::new(&route(), ExecutorConfig::default()).unwrap();
    assert!(idle.replace_route(0.0, &detour, event(0.0)).is_err());
    assert_eq!(idle.targets(), &route()[..]);
    // An empty or underground route is refused.
    assert!(ex.replace_route(t, &[], event(t)).is_err());
    assert!(
        ex.replace_route(
            t,
            &[wp(0.0, 0.0, 0.0)].map(|w| Target { alt_m: 0.0, ..w }),
            event(t)
        )
        .is_err()
    );
}

#[test]
fn no_route_holds_then_lands_and_fails() {
    let config = ExecutorConfig::default();
    let mut ex = MissionExecutor::new(&route(), config).unwrap();
    let mut v = SimVehicle::new(SimConfig::default());
    let run = fly(&mut ex, &mut v, |ex| ex.reached().len() == 2, Act::NoRoute);
    let Some(Outcome::Failed(Failure::NoRoute { reason })) = ex.outcome() else {
        panic!("{:?}", ex.outcome());
    };
    assert_eq!(reason, "every way is blocked");
    assert!(run.notes.iter().any(|n| matches!(n, Note::Holding { .. })));
    let (t0, p0, _) = run.acted_at.unwrap();
    // Held: within 1.5 m of where it was (it was flying at up to 5 m/s) for the hold…
    for (t, p) in &run.after {
        if *t < t0 + config.replan_hold_s {
            assert!(
                (p[0] - p0[0]).hypot(p[1] - p0[1]) < 1.5 && p[2] > 4.0,
                "{t}: {p:?}"
            );
        }
    }
    // …then landed there, never reaching the third waypoint.
    let s = v.state();
    assert!(s.on_ground && !s.armed);
    assert!((s.position_ned_m[0] - p0[0]).hypot(s.position_ned_m[1] - p0[1]) < 3.0);
    assert_eq!(ex.reached().len(), 2);
    let failure = Failure::NoRoute {
        reason: reason.clone(),
    };
    assert!(failure.to_string().contains("held position, then landed"));
}
