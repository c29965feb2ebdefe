//! OpenStreetMap buildings against an independent reader: osmium-tool's `osmium export` of the
//! same file (`data/osm/helsinki-buildings.osmium.geojson`, made by the command in
//! `data/osm/README.md`), and the XML and PBF forms of one extract against each other.

use serde_json::Value;
use skyplan_map::footprints::{DEFAULT_HEIGHT_M, GeoPolygon, parse_geojson};
use skyplan_map::osm::{OsmBuildings, OsmId, parse_osm_pbf, parse_osm_xml};
use std::collections::BTreeMap;

fn data(name: &str) -> Vec<u8> {
    let path = format!("{}/../../data/osm/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// A ring as a canonical list: started at its smallest position, turning one fixed way.
fn canonical(ring: &[[f64; 2]]) -> Vec<[i64; 2]> {
    let mut r: Vec<[i64; 2]> = ring
        .iter()
        .map(|p| [(p[0] * 1e7).round() as i64, (p[1] * 1e7).round() as i64])
        .collect();
    let area2: i128 = (0..r.len())
        .map(|i| {
            let (a, b) = (r[i], r[(i + 1) % r.len()]);
            i128::from(a[0]) * i128::from(b[1]) - i128::from(b[0]) * i128::from(a[1])
        })
        .sum();
    if area2 < 0 {
        r.reverse();
    }
    let k = (0..r.len()).min_by_key(|&i| r[i]).unwrap_or(0);
    r.rotate_left(k);
    r
}

fn canonical_polygons(polygons: &[GeoPolygon]) -> Canonical {
    let mut out: Vec<Vec<Vec<[i64; 2]>>> = polygons
        .iter()
        .map(|p| {
            let mut rings: Vec<_> = p.iter().map(|r| canonical(r)).collect();
            rings[1..].sort();
            rings
        })
        .collect();
    out.sort();
    out
}

fn by_id(b: &OsmBuildings) -> BTreeMap<OsmId, (Canonical, f64, f64)> {
    b.ids
        .iter()
        .zip(&b.geo.buildings)
        .map(|(&id, g)| {
            (
                id,
                (canonical_polygons(&g.polygons), g.min_height_m, g.height_m),
            )
        })
        .collect()
}

type Canonical = Vec<Vec<Vec<[i64; 2]>>>;

/// Whether a point (1e-7 degrees) is in the polygons: inside an outer ring and in none of its
/// holes.
fn covers(polygons: &Canonical) -> impl Fn([f64; 2]) -> bool + '_ {
    let inside = |p: [f64; 2], ring: &[[i64; 2]]| {
        let mut odd = false;
        for k in 0..ring.len() {
            let (a, b) = (
                ring[k].map(|v| v as f64),
                ring[(k + 1) % ring.len()].map(|v| v as f64),
            );
            if (a[1] > p[1]) != (b[1] > p[1])
                && p[0] < a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
            {
                odd = !odd;
            }
        }
        odd
    };
    move |p| {
        polygons
            .iter()
            .any(|rings| inside(p, &rings[0]) && !rings[1..].iter().any(|h| inside(p, h)))
    }
}

fn bounds(polygons: &Canonical) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in polygons.iter().flatten().flatten() {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k] as f64);
            hi[k] = hi[k].max(p[k] as f64);
        }
    }
    (lo, hi)
}

#[test]
fn pbf_buildings_are_osmium_s_areas() {
    let ours = parse_osm_pbf(&data("helsinki-buildings.osm.pbf"), DEFAULT_HEIGHT_M).unwrap();
    let oracle_text = String::from_utf8(data("helsinki-buildings.osmium.geojson")).unwrap();
    let oracle_json: Value = serde_json::from_str(&oracle_text).unwrap();
    let oracle = parse_geojson(&oracle_text, DEFAULT_HEIGHT_M).unwrap();
    let mut theirs = BTreeMap::new();
    for (f, g) in oracle_json["features"]
        .as_array()
        .unwrap()
        .iter()
        .zip(&oracle.buildings)
    {
        let id = f["properties"]["@id"].as_i64().unwrap();
        let id = match f["properties"]["@type"].as_str() {
            Some("way") => OsmId::Way(id),
            Some("relation") => OsmId::Relation(id),
            other => panic!("type {other:?}"),
        };
        theirs.insert(
            id,
            (canonical_polygons(&g.polygons), g.min_height_m, g.height_m),
        );
    }
    let ours_by_id = by_id(&ours);
    assert!(theirs.len() > 400, "{} areas", theirs.len());
    let only_ours: Vec<_> = ours_by_id
        .keys()
        .filter(|k| !theirs.contains_key(k))
        .collect();
    let only_theirs: Vec<_> = theirs
        .keys()
        .filter(|k| !ours_by_id.contains_key(k))
        .collect();
    assert!(
        only_ours.is_empty() && only_theirs.is_empty(),
        "only skyplan: {only_ours:?}; only osmium: {only_theirs:?}; skipped: {:?}",
        ours.skipped
    );
    // Ring for ring, except where rings touch: osmium cuts touching rings at the shared node
    // (one courtyard split in two), skyplan joins member ways as they come (one courtyard with
    // a building part inside it); there the covered area must be the same, sampled finely.
    let mut touching = Vec::new();
    for (id, want) in &theirs {
        let got = &ours_by_id[id];
        if got == want {
            continue;
        }
        assert_eq!((got.1, got.2), (want.1, want.2), "{id}: heights");
        let (a, b) = (covers(&got.0), covers(&want.0));
        let (lo, hi) = bounds(&want.0);
        for i in 0..200 {
            for j in 0..200 {
                let p = [
                    lo[0] + (hi[0] - lo[0]) * (f64::from(i) + 0.5137) / 200.0,
                    lo[1] + (hi[1] - lo[1]) * (f64::from(j) + 0.4871) / 200.0,
                ];
                assert_eq!(a(p), b(p), "{id}: at {p:?}");
            }
        }
        touching.push(*id);
    }
    assert!(touching.len() <= 2, "rings differ in {touching:?}");
    // Relations with holes are among them.
    assert!(
        ours.geo
            .buildings
            .iter()
            .any(|b| b.polygons.iter().any(|p| p.len() > 1)),
        "no courtyard"
    );
}

#[test]
fn xml_and_pbf_of_one_extract_are_the_same_buildings() {
    let xml = String::from_utf8(data("helsinki-sample.osm")).unwrap();
    let from_xml = parse_osm_xml(&xml, DEFAULT_HEIGHT_M).unwrap();
    let from_pbf = parse_osm_pbf(&data("helsinki-sample.osm.pbf"), DEFAULT_HEIGHT_M).unwrap();
    assert!(from_xml.ids.len() > 40, "{} buildings", from_xml.ids.len());
    assert_eq!(from_xml, from_pbf);
}

#[test]
fn broken_buildings_are_skipped_and_named_and_bad_files_refused() {
    let node =
        |id: i64, lat: f64, lon: f64| format!(r#"<node id="{id}" lat="{lat}" lon="{lon}"/>"#);
    let nodes = [
        node(1, 60.0, 24.0),
        node(2, 60.0, 24.001),
        node(3, 60.001, 24.001),
        node(4, 60.001, 24.0),
    ]
    .concat();
    let doc =
        |body: &str| format!(r#"<?xml version="1.0"?><osm version="0.6">{nodes}{body}</osm>"#);
    let way = |id: i64, refs: &[i64], extra: &str| {
        let nds: String = refs.iter().map(|r| format!(r#"<nd ref="{r}"/>"#)).collect();
        format!(r#"<way id="{id}">{nds}<tag k="building" v="yes"/>{extra}</way>"#)
    };
    let good = way(10, &[1, 2, 3, 4, 1], r#"<tag k="height" v="25 m"/>"#);
    let cases = [
        (way(11, &[1, 2, 3], ""), OsmId::Way(11), "the way is not closed"),
        (way(12, &[1, 2, 99, 1], ""), OsmId::Way(12), "node 99 is not in the file"),
        (way(13, &[1, 3, 2, 4, 1], ""), OsmId::Way(13), "the ring crosses or touches itself"),
        (
            r#"<relation id="20"><member type="way" ref="77" role="outer"/><tag k="type" v="multipolygon"/><tag k="building" v="yes"/></relation>"#.to_string(),
            OsmId::Relation(20),
            "its member way 77 is not in the file",
        ),
    ];
    for (body, id, why) in cases {
        let b = parse_osm_xml(&doc(&format!("{good}{body}")), DEFAULT_HEIGHT_M).unwrap();
        assert_eq!(b.ids, vec![OsmId::Way(10)]);
        assert_eq!(b.geo.buildings[0].height_m, 25.0);
        assert_eq!(b.skipped.len(), 1);
        assert_eq!(b.skipped[0].0, id);
        assert!(b.skipped[0].1.contains(why), "{}", b.skipped[0].1);
    }
    // A relation: two outer ways joined into one ring, with a hole.
    let hole = [
        node(5, 60.0004, 24.0004),
        node(6, 60.0004, 24.0006),
        node(7, 60.0006, 24.0005),
    ]
    .concat();
    let body = format!(
        r#"{hole}<way id="30"><nd ref="1"/><nd ref="2"/><nd ref="3"/></way><way id="31"><nd ref="1"/><nd ref="4"/><nd ref="3"/></way><way id="32"><nd ref="5"/><nd ref="6"/><nd ref="7"/><nd ref="5"/></way><relation id="40"><member type="way" ref="30" role="outer"/><member type="way" ref="31" role="outer"/><member type="way" ref="32" role="inner"/><tag k="type" v="multipolygon"/><tag k="building" v="yes"/><tag k="building:levels" v="5"/></relation>"#
    );
    let b = parse_osm_xml(&doc(&body), DEFAULT_HEIGHT_M).unwrap();
    assert_eq!(b.ids, vec![OsmId::Relation(40)]);
    let g = &b.geo.buildings[0];
    assert_eq!((g.polygons.len(), g.polygons[0].len()), (1, 2));
    assert_eq!((g.polygons[0][0].len(), g.polygons[0][1].len()), (4, 3));
    assert_eq!(g.height_m, 15.0);

    for (text, want) in [
        ("<osm><node id=\"1\"", "XML: line 1, column "),
        ("<gpx></gpx>", "root element: expected <osm>, found <gpx>"),
        (
            r#"<osm><node id="1" lat="95" lon="24"/></osm>"#,
            "line 1, node 1 lat: expected a number of degrees within ±90",
        ),
        (
            r#"<osm><way id="x"/></osm>"#,
            "line 1, way id: expected an integer, found \"x\"",
        ),
        ("<osm></osm>", "buildings: the file has no building"),
        (
            &doc(&way(11, &[1, 2, 3], "")),
            "buildings: no building could be made (1 skipped; the first, way 11: the way is not closed",
        ),
    ] {
        let e = parse_osm_xml(text, DEFAULT_HEIGHT_M)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(want), "{e}");
    }
    let e = parse_osm_pbf(b"not a pbf file at all", DEFAULT_HEIGHT_M)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("PBF: not a readable .osm.pbf file: "), "{e}");
}
