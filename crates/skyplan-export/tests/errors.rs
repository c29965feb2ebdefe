mod common;

use skyplan_export::{
    ExportError, ExportOptions, Format, QgcPlanOptions, encode, encode_with, to_qgc_plan,
};

#[test]
fn non_finite_values_are_rejected_by_every_format() {
    let mut mission = common::sample();
    mission.waypoints[2].heading_rad = f64::NAN;
    for format in Format::ALL {
        let err = encode(format, &mission, &serde_json::Value::Null).unwrap_err();
        match &err {
            ExportError::NonFinite { what, value } => {
                assert_eq!(what, "waypoint 2 heading_rad");
                assert!(value.is_nan());
            }
            other => panic!("{format}: unexpected error {other:?}"),
        }
        assert_eq!(
            err.to_string(),
            "waypoint 2 heading_rad is not finite (NaN)"
        );
    }

    let mut mission = common::sample();
    mission.home.alt_m = f64::INFINITY;
    let err = encode(Format::Csv, &mission, &serde_json::Value::Null).unwrap_err();
    assert_eq!(err.to_string(), "home alt_m is not finite (inf)");
}

#[test]
fn empty_missions() {
    let empty = common::empty();
    let meta = serde_json::Value::Null;
    // Tabular formats accept an empty mission.
    assert!(encode(Format::Json, &empty, &meta).is_ok());
    assert!(encode(Format::Csv, &empty, &meta).is_ok());
    assert!(encode(Format::Hdf5, &empty, &meta).is_ok());
    // Route formats need a position.
    for format in [Format::GeoJson, Format::QgcPlan] {
        let err = encode(format, &empty, &meta).unwrap_err();
        assert!(
            matches!(
                err,
                ExportError::TooFewWaypoints {
                    needed: 1,
                    got: 0,
                    ..
                }
            ),
            "{err:?}"
        );
        assert_eq!(
            err.to_string(),
            format!("{format} export needs at least 1 waypoint(s), but the mission has 0")
        );
    }
}

#[test]
fn bad_speeds_are_rejected() {
    let mission = common::sample();
    for speed in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let options = QgcPlanOptions {
            hover_speed_m_s: speed,
            ..QgcPlanOptions::default()
        };
        let err = to_qgc_plan(&mission, &options).unwrap_err();
        assert!(
            matches!(
                err,
                ExportError::InvalidOption {
                    name: "hover_speed_m_s",
                    ..
                }
            ),
            "{err:?}"
        );
    }
    let options = ExportOptions {
        qgc_plan: QgcPlanOptions {
            cruise_speed_m_s: 0.0,
            ..QgcPlanOptions::default()
        },
    };
    let err = encode_with(
        Format::QgcPlan,
        &mission,
        &serde_json::Value::Null,
        &options,
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "invalid option cruise_speed_m_s = 0: must be finite and positive"
    );
}

#[test]
fn encode_dispatches_to_the_encoders() {
    let mission = common::sample();
    let meta = serde_json::json!({ "planner": "a*" });
    let check = |format, want: Vec<u8>| {
        assert_eq!(encode(format, &mission, &meta).unwrap(), want, "{format}")
    };
    check(
        Format::Json,
        skyplan_export::to_json(&mission, &meta)
            .unwrap()
            .into_bytes(),
    );
    check(
        Format::Csv,
        skyplan_export::to_csv(&mission).unwrap().into_bytes(),
    );
    check(Format::Hdf5, skyplan_export::to_hdf5(&mission).unwrap());
    check(
        Format::GeoJson,
        skyplan_export::to_geojson(&mission).unwrap().into_bytes(),
    );
    check(
        Format::QgcPlan,
        to_qgc_plan(&mission, &QgcPlanOptions::default())
            .unwrap()
            .into_bytes(),
    );
}
