mod common;

use proptest::prelude::*;
use skyplan_export::{CSV_HEADER, csv_row, to_csv};
use skyplan_mission::{Mission, Waypoint};

/// Parses CSV text back into `[north, east, alt, heading, lat, lon]` rows, checking the header.
fn read_back(text: &str) -> Vec<[f64; 6]> {
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    assert_eq!(
        reader.headers().unwrap(),
        &csv::StringRecord::from(CSV_HEADER.to_vec())
    );
    reader
        .records()
        .map(|record| {
            let record = record.unwrap();
            assert_eq!(record.len(), 6);
            let mut row = [0.0; 6];
            for (slot, field) in row.iter_mut().zip(record.iter()) {
                *slot = field.parse().unwrap();
            }
            row
        })
        .collect()
}

#[test]
fn csv_round_trip_is_exact() {
    let mission = common::sample();
    let text = to_csv(&mission).unwrap();
    assert!(text.starts_with("north_m,east_m,alt_m,heading_rad,lat_deg,lon_deg\n"));
    let rows = read_back(&text);
    let want: Vec<_> = mission.waypoints.iter().map(csv_row).collect();
    // Bitwise equality, not just ==, so -0.0 survives too.
    let bits = |rows: &[[f64; 6]]| rows.iter().map(|r| r.map(f64::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits(&rows), bits(&want));
}

#[test]
fn csv_uses_display_formatting() {
    let text = to_csv(&common::single()).unwrap();
    assert_eq!(
        text,
        "north_m,east_m,alt_m,heading_rad,lat_deg,lon_deg\n1,2,3,0.5,37.79249,-122.39743\n"
    );
}

#[test]
fn csv_of_empty_mission_is_the_header() {
    assert_eq!(
        to_csv(&common::empty()).unwrap(),
        "north_m,east_m,alt_m,heading_rad,lat_deg,lon_deg\n"
    );
}

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        prop::num::f64::NORMAL | prop::num::f64::SUBNORMAL | prop::num::f64::ZERO,
        -1e4..1e4_f64,
    ]
}

proptest! {
    #[test]
    fn csv_round_trips_any_finite_values(values in prop::collection::vec(prop::array::uniform6(finite()), 0..20)) {
        let waypoints = values
            .iter()
            .map(|v| Waypoint { north_m: v[0], east_m: v[1], alt_m: v[2], heading_rad: v[3], lat_deg: v[4], lon_deg: v[5] })
            .collect();
        let mission = Mission { home: common::home(), waypoints };
        let rows = read_back(&to_csv(&mission).unwrap());
        prop_assert_eq!(rows.len(), values.len());
        for (got, want) in rows.iter().zip(&values) {
            prop_assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
        }
    }
}
