//! The indexed checker against the brute-force one, and the slab test against independent
//! geometry (dense sampling finds only true hits; a reported hit has a witness point inside).

use proptest::prelude::*;
use skyplan_map::colliders::ObstacleBox;
use skyplan_world3::{Aabb, BoxWorld3, CollisionChecker, Neu, WorldSpec, lerp, segment_hits_box};

fn arb_box() -> impl Strategy<Value = ObstacleBox> {
    skyplan_testkit::arb_box(0.0..30.0, 0.5..15.0, 0.5..30.0)
}

fn arb_point() -> impl Strategy<Value = Neu> {
    // Coordinates snapped to a 0.25 m lattice part of the time so faces and edges get touched.
    (
        -20.0..120.0f64,
        -20.0..120.0f64,
        -5.0..70.0f64,
        any::<bool>(),
    )
        .prop_map(|(n, e, a, snap)| {
            if snap {
                [
                    (n * 4.0).round() / 4.0,
                    (e * 4.0).round() / 4.0,
                    (a * 4.0).round() / 4.0,
                ]
            } else {
                [n, e, a]
            }
        })
}

fn world(boxes: &[ObstacleBox], safety_m: f64) -> BoxWorld3 {
    skyplan_testkit::box_world(boxes, safety_m, 60.0, 5.0)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn index_agrees_with_brute_force(
        boxes in prop::collection::vec(arb_box(), 1..40),
        safety_m in prop_oneof![Just(0.0), 0.0..6.0],
        segs in prop::collection::vec((arb_point(), arb_point()), 1..40),
    ) {
        let w = world(&boxes, safety_m);
        let bf = w.brute_force();
        for (a, b) in segs {
            prop_assert_eq!(w.is_free(a), bf.is_free(a), "point {:?}", a);
            prop_assert_eq!(w.segment_is_free(a, b), bf.segment_is_free(a, b), "segment {:?} {:?}", a, b);
            // Axis-parallel and vertical segments through the same points.
            let c = [b[0], a[1], a[2]];
            prop_assert_eq!(w.segment_is_free(a, c), bf.segment_is_free(a, c));
            let v = [a[0], a[1], b[2]];
            prop_assert_eq!(w.segment_is_free(a, v), bf.segment_is_free(a, v));
        }
    }

    #[test]
    fn slab_test_matches_geometry(
        lo in (-5.0..5.0f64, -5.0..5.0f64, -5.0..5.0f64),
        size in (0.0..4.0f64, 0.0..4.0f64, 0.0..4.0f64),
        a in (-10.0..10.0f64, -10.0..10.0f64, -10.0..10.0f64),
        b in (-10.0..10.0f64, -10.0..10.0f64, -10.0..10.0f64),
    ) {
        let bx = Aabb { min: [lo.0, lo.1, lo.2], max: [lo.0 + size.0, lo.1 + size.1, lo.2 + size.2] };
        let (a, b) = ([a.0, a.1, a.2], [b.0, b.1, b.2]);
        let hit = segment_hits_box(a, b, &bx);
        // Any sampled point inside the box proves a hit.
        let sampled = (0..=2000).any(|k| bx.contains(lerp(a, b, k as f64 / 2000.0)));
        if sampled {
            prop_assert!(hit);
        }
        // A hit has a witness: the clipped parameter interval's midpoint is in the box (to 1e-9).
        if hit {
            let mut t0 = 0.0f64;
            let mut t1 = 1.0f64;
            for i in 0..3 {
                let d = b[i] - a[i];
                if d != 0.0 {
                    let (u, v) = ((bx.min[i] - a[i]) / d, (bx.max[i] - a[i]) / d);
                    t0 = t0.max(u.min(v));
                    t1 = t1.min(u.max(v));
                }
            }
            let m = lerp(a, b, 0.5 * (t0 + t1));
            prop_assert!(bx.grown(1e-9).contains(m), "witness {:?} not in {:?}", m, bx);
        }
    }
}

#[test]
fn margin_applies_in_all_three_axes() {
    let b = ObstacleBox::from_row([50.0, 50.0, 10.0, 5.0, 5.0, 10.0]);
    let w = skyplan_testkit::box_world(&[b], 3.0, 60.0, 30.0);
    assert!(w.is_free([30.0, 42.0, 23.0]) && w.is_free([70.0, 42.0, 23.0]));
    assert!(!w.is_free([50.0, 50.0, 23.0])); // roof 20 + 3: touching is a collision
    assert!(w.is_free([50.0, 50.0, 23.001]));
    assert!(!w.is_free([42.0, 50.0, 10.0])); // side face 45 − 3
    assert!(w.is_free([41.99, 50.0, 10.0]));
    // Grazing the inflated top edge counts as a hit.
    assert!(!w.segment_is_free([30.0, 42.0, 23.0], [70.0, 42.0, 23.0]));
    assert!(w.segment_is_free([30.0, 42.0, 23.0], [70.0, 41.999, 23.0]));
}

#[test]
fn ground_and_bounds_are_obstacles() {
    let b = ObstacleBox::from_row([50.0, 50.0, 10.0, 5.0, 5.0, 10.0]);
    let spec = WorldSpec {
        safety_m: 1.0,
        min_alt_m: 2.0,
        max_alt_m: 40.0,
        margin_bounds_m: 0.0,
    };
    let w = BoxWorld3::new(&[b], &spec).unwrap();
    assert_eq!(w.bounds().min, [45.0, 45.0, 2.0]);
    assert!(!w.is_free([45.0, 45.0, 1.99]));
    assert!(!w.is_free([44.99, 45.0, 30.0]));
    assert!(w.is_free([45.0, 45.0, 30.0]));
    assert!(!w.segment_is_free([45.0, 45.0, 30.0], [45.0, 45.0, 41.0]));
    assert!(
        BoxWorld3::new(
            &[b],
            &WorldSpec {
                safety_m: -1.0,
                ..spec
            }
        )
        .is_err()
    );
    assert!(BoxWorld3::new(&[], &spec).is_err());
}

#[test]
fn city_map_agrees_with_brute_force_on_long_segments() {
    let w = skyplan_testkit::city_world(5.0, 250.0);
    let bf = w.brute_force();
    let bounds = w.bounds();
    // A deterministic low-discrepancy walk over the map.
    let mut x = [0.1f64, 0.4, 0.7];
    let mut disagreements = 0;
    let mut free = 0;
    for _ in 0..400 {
        let mut p = [[0.0; 3]; 2];
        for q in &mut p {
            for i in 0..3 {
                x[i] = (x[i] + [0.618_034, 0.754_877_7, 0.569_840_3][i]).fract();
                q[i] = bounds.min[i]
                    + x[i] * (bounds.max[i] - bounds.min[i]) * if i == 2 { 0.4 } else { 1.0 };
            }
        }
        let got = w.segment_is_free(p[0], p[1]);
        disagreements += usize::from(got != bf.segment_is_free(p[0], p[1]));
        free += usize::from(got);
    }
    assert_eq!(disagreements, 0);
    assert!(free > 0, "some long segments over the city are free");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The indexed box test agrees with testing every box, and a box it calls free has no
    /// corner, centre or face centre inside an inflated box (independent point tests).
    #[test]
    fn box_test_agrees_with_brute_force_and_points(
        boxes in prop::collection::vec(arb_box(), 1..40),
        safety_m in prop_oneof![Just(0.0), 0.0..6.0],
        corners in prop::collection::vec((arb_point(), arb_point()), 1..40),
    ) {
        let w = world(&boxes, safety_m);
        let bf = w.brute_force();
        for (p, q) in corners {
            let b = Aabb {
                min: [p[0].min(q[0]), p[1].min(q[1]), p[2].min(q[2])],
                max: [p[0].max(q[0]), p[1].max(q[1]), p[2].max(q[2])],
            };
            let free = w.box_is_free(&b);
            prop_assert_eq!(free, bf.box_is_free(&b), "box {:?}", b);
            if free {
                for i in 0..27 {
                    let f = [i % 3, (i / 3) % 3, i / 9].map(|k| k as f64 / 2.0);
                    let pt = [0, 1, 2].map(|k| b.min[k] + f[k] * (b.max[k] - b.min[k]));
                    prop_assert!(bf.is_free(pt), "free box {:?} holds blocked point {:?}", b, pt);
                }
            }
        }
    }
}
