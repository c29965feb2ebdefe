//! "An OSM file and the same buildings as GeoJSON give the same routes": the bundled Helsinki
//! extract read from OpenStreetMap PBF by skyplan, and as GeoJSON assembled by an independent
//! reader (osmium-tool's `osmium export`, `data/osm/README.md`), planned with a grid and an
//! any-angle planner between the same points.

use skyplan_plan::{PlanRequest, PlannerId, Session, World};

fn data(name: &str) -> Vec<u8> {
    let path = format!("{}/../../data/osm/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

#[test]
fn osm_and_osmium_geojson_give_the_same_routes() {
    let home = Some([60.1716, 24.9443]);
    let osm = World::from_osm(
        "helsinki-buildings.osm.pbf",
        &data("helsinki-buildings.osm.pbf"),
        home,
        true,
    )
    .unwrap();
    let geojson = World::from_geojson(
        "helsinki-buildings.osmium.geojson",
        &data("helsinki-buildings.osmium.geojson"),
        home,
    )
    .unwrap();
    // The same heights; the OSM file also holds buildings cut by the extract's edge (osmium
    // leaves them out too), named.
    let (notes, oracle_notes) = (osm.notes(), geojson.notes());
    assert_eq!(notes[0], oracle_notes[0], "the same heights");
    assert_eq!(oracle_notes.len(), 1);
    assert!(
        notes[1]
            .starts_with("54 buildings skipped: way 17361610: node 179789037 is not in the file; "),
        "{}",
        notes[1]
    );
    let (mut a, mut b) = (Session::new(osm), Session::new(geojson));
    let mut planned = 0;
    for (start, goal) in [
        ([0.0, 0.0], [600.0, 300.0]),
        ([-500.0, -400.0], [500.0, 450.0]),
        ([300.0, -350.0], [-600.0, 400.0]),
    ] {
        for planner in [PlannerId::Jps, PlannerId::Theta] {
            let request = PlanRequest {
                planner: Some(planner),
                start_ne: Some(start),
                goal_ne: Some(goal),
                alt_m: Some(20.0),
                ..Default::default()
            };
            let (pa, pb) = (a.plan(&request), b.plan(&request));
            match (pa, pb) {
                (Ok(pa), Ok(pb)) => {
                    assert_eq!(
                        pa.waypoints, pb.waypoints,
                        "{planner:?} {start:?} → {goal:?}"
                    );
                    assert_eq!(pa.cost_m, pb.cost_m);
                    planned += 1;
                }
                (Err(ea), Err(eb)) => assert_eq!(ea.message, eb.message),
                (ra, rb) => panic!(
                    "{planner:?} {start:?} → {goal:?}: {:?} against {:?}",
                    ra.err(),
                    rb.err()
                ),
            }
        }
    }
    assert!(planned >= 4, "only {planned} routes planned");
}
