//! Lazy PRM and saved roadmaps. Lazy PRM on random box worlds (its paths and enclosed goals are
//! checked with the other planners' in `properties.rs`): it tests no more roadmap edges than eager
//! PRM on the same roadmap (far fewer on the city).
//! Saved roadmaps: a loaded roadmap answers the same query with the same route, grows on with
//! the same samples, and a roadmap for another margin, map or flight volume is refused.

use proptest::prelude::*;
use skyplan_map::colliders::ObstacleBox;
use skyplan_sampling::prm::{PrmConfig, Roadmap, RoadmapFileError, solve};
use skyplan_sampling::{Budget, Status};
use skyplan_world3::{BoxWorld3, CollisionChecker, Neu, distance_m, first_blocked_segment};
use std::time::Instant;

mod common;
use common::{arb_case, world};

fn city(safety_m: f64) -> BoxWorld3 {
    skyplan_testkit::city_world(safety_m, 100.0)
}

fn config(seed: u64, samples: usize, lazy: bool) -> PrmConfig {
    PrmConfig {
        samples,
        seed,
        lazy,
        ..PrmConfig::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn lazy_prm_tests_no_more_edges_than_prm_on_the_same_roadmap(
        (boxes, start, goal, seed) in arb_case(1..14),
    ) {
        let w = world(&boxes, 1.0);
        let eager = Roadmap::build(&w, &config(seed, 300, false));
        let mut lazy = Roadmap::build(&w, &config(seed, 300, true));
        prop_assert_eq!(eager.vertices(), lazy.vertices());
        prop_assert_eq!(lazy.stats.edges_tested, 0);
        let s = lazy.query_lazy(&w, start, goal);
        prop_assert!(lazy.stats.edges_tested <= eager.stats.edges_tested);
        // Every edge the lazy roadmap found blocked is blocked, and it kept every free edge.
        prop_assert!(lazy.edges() >= eager.edges());
        if s.status == Status::Exact {
            prop_assert_eq!(first_blocked_segment(&w.brute_force(), &s.path), None);
        }
        // The eager roadmap connects the ends through its checked edges ⇒ lazy finds a path too
        // (unless its unchecked connectors all fail; then eager's 3k candidates did better).
        let e = eager.query(&w, start, goal);
        if e.status == Status::Exact && s.status != Status::Exact {
            prop_assert_eq!(s.status, Status::Timeout);
        }
    }

    #[test]
    fn saved_roadmaps_load_back_identically(
        (boxes, start, goal, seed) in arb_case(1..10),
        lazy in any::<bool>(),
    ) {
        let w = world(&boxes, 1.0);
        let (mut saved, s) = solve(&w, start, goal, &config(seed, 200, lazy), Budget::iterations(600));
        let bytes = saved.to_json(&w);
        let mut loaded = Roadmap::from_json(&bytes, &w).unwrap();
        prop_assert_eq!(loaded.vertices(), saved.vertices());
        prop_assert_eq!(loaded.edge_list(), saved.edge_list());
        prop_assert_eq!(loaded.unchecked_edges(), saved.unchecked_edges());
        prop_assert_eq!(loaded.to_json(&w), bytes);
        let (a, b) = (saved.query(&w, start, goal), loaded.query(&w, start, goal));
        prop_assert_eq!(a.status, b.status);
        prop_assert_eq!(&a.path, &b.path);
        if s.status == Status::Exact {
            prop_assert_eq!(&b.path, &s.path);
        }
        // The sampler continues where it stopped.
        saved.grow(&w, 20);
        loaded.grow(&w, 20);
        prop_assert_eq!(loaded.vertices(), saved.vertices());
        prop_assert_eq!(loaded.edge_list(), saved.edge_list());
    }
}

#[test]
fn a_roadmap_for_another_world_is_refused() {
    let boxes = [ObstacleBox::from_row([50.0, 50.0, 10.0, 10.0, 10.0, 10.0])];
    let w = world(&boxes, 1.0);
    let bytes = Roadmap::build(&w, &config(3, 100, false)).to_json(&w);
    assert!(Roadmap::from_json(&bytes, &w).is_ok());
    let err = Roadmap::from_json(&bytes, &world(&boxes, 2.0)).unwrap_err();
    assert!(
        matches!(&err, RoadmapFileError::OtherWorld(m) if m.contains("margin of 1 m, not 2 m")),
        "{err}"
    );
    let mut moved = boxes;
    moved[0].north_m += 0.5;
    let err = Roadmap::from_json(&bytes, &world(&moved, 1.0)).unwrap_err();
    assert!(
        matches!(&err, RoadmapFileError::OtherWorld(m) if m.contains("another map")),
        "{err}"
    );
    let higher = skyplan_testkit::box_world(&boxes, 1.0, 60.0, 15.0);
    let err = Roadmap::from_json(&bytes, &higher).unwrap_err();
    assert!(
        matches!(&err, RoadmapFileError::OtherWorld(m) if m.contains("flight volume")),
        "{err}"
    );
    assert!(matches!(
        Roadmap::from_json(b"{\"not\": 1}", &w),
        Err(RoadmapFileError::Parse(_))
    ));
    let text = String::from_utf8(bytes.clone()).unwrap();
    let bad = text.replacen("\"version\":1", "\"version\":99", 1);
    assert!(matches!(
        Roadmap::from_json(bad.as_bytes(), &w),
        Err(RoadmapFileError::Version { .. })
    ));
    let bad = text.replacen("\"neighbours\":[[", "\"neighbours\":[[100000,", 1);
    assert!(matches!(
        Roadmap::from_json(bad.as_bytes(), &w),
        Err(RoadmapFileError::Invalid(_))
    ));
}

/// On the city, lazy PRM tests a small fraction of the edges eager PRM tests on the same roadmap,
/// and both routes re-check free. Prints the counts (`--nocapture`).
#[test]
fn lazy_prm_tests_far_fewer_edges_than_prm_on_the_city() {
    let w = city(5.0);
    let bf = w.brute_force();
    let (start, goal): (Neu, Neu) = ([0.0, 0.0, 5.0], [420.0, 390.0, 5.0]);
    assert!(w.is_free(start) && w.is_free(goal));
    let t = Instant::now();
    let eager = Roadmap::build(&w, &config(1, 2000, false));
    let eager_us = t.elapsed().as_micros();
    let t = Instant::now();
    let mut lazy = Roadmap::build(&w, &config(1, 2000, true));
    let lazy_build_us = t.elapsed().as_micros();
    let e = eager.query(&w, start, goal);
    let t = Instant::now();
    let l = lazy.query_lazy(&w, start, goal);
    let lazy_query_us = t.elapsed().as_micros();
    assert_eq!(e.status, Status::Exact);
    assert_eq!(l.status, Status::Exact);
    assert_eq!(first_blocked_segment(&bf, &e.path), None);
    assert_eq!(first_blocked_segment(&bf, &l.path), None);
    eprintln!(
        "city, 2000 samples, seed 1: eager PRM tested {} edges ({} kept) in {eager_us} µs; lazy PRM tested {} \
         ({} blocked, removed; {} connector tests) — build {lazy_build_us} µs + query {lazy_query_us} µs; \
         routes {:.1} m / {:.1} m (straight {:.1} m)",
        eager.stats.edges_tested,
        eager.edges(),
        lazy.stats.edges_tested,
        lazy.stats.edges_removed,
        lazy.stats.connector_tests,
        e.cost_m,
        l.cost_m,
        distance_m(start, goal)
    );
    assert!(lazy.stats.edges_tested * 10 < eager.stats.edges_tested);
    // A second query reuses what the first one learned.
    let before = lazy.stats.edges_tested;
    let again = lazy.query_lazy(&w, start, goal);
    assert_eq!(again.path, l.path);
    assert_eq!(lazy.stats.edges_tested, before);
    // Saved and loaded: the same route; sizes and times for the report.
    let t = Instant::now();
    let bytes = eager.to_json(&w);
    let save_us = t.elapsed().as_micros();
    let t = Instant::now();
    let loaded = Roadmap::from_json(&bytes, &w).unwrap();
    let load_us = t.elapsed().as_micros();
    assert_eq!(loaded.query(&w, start, goal).path, e.path);
    eprintln!(
        "saved roadmap: {} vertices, {} edges, {} bytes of JSON, saved in {save_us} µs, loaded in {load_us} µs",
        eager.vertices().len(),
        eager.edges(),
        bytes.len()
    );
    assert!(Roadmap::from_json(&bytes, &city(4.0)).is_err());
}
