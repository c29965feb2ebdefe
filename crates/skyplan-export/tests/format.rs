use std::path::Path;

use skyplan_export::{ExportError, Format};

#[test]
fn from_path_by_extension() {
    let cases = [
        ("a.json", Some(Format::Json)),
        ("dir/b.CSV", Some(Format::Csv)),
        ("c.h5", Some(Format::Hdf5)),
        ("c.hdf5", Some(Format::Hdf5)),
        ("d.geojson", Some(Format::GeoJson)),
        ("e.plan", Some(Format::QgcPlan)),
        ("f.txt", None),
        ("noext", None),
        (".json", None), // a hidden file named "json", not an extension
    ];
    for (path, want) in cases {
        assert_eq!(Format::from_path(Path::new(path)), want, "{path}");
    }
}

#[test]
fn from_name_accepts_aliases() {
    let cases = [
        ("json", Format::Json),
        ("csv", Format::Csv),
        ("hdf5", Format::Hdf5),
        ("h5", Format::Hdf5),
        ("geojson", Format::GeoJson),
        ("plan", Format::QgcPlan),
        ("QGC", Format::QgcPlan),
    ];
    for (name, want) in cases {
        assert_eq!(Format::from_name(name), Some(want), "{name}");
    }
    assert_eq!(Format::from_name("kml"), None);
    let err = "kml".parse::<Format>().unwrap_err();
    assert!(matches!(err, ExportError::UnknownFormat(ref s) if s == "kml"));
    assert!(err.to_string().contains("kml"));
}

#[test]
fn names_and_extensions_round_trip() {
    for format in Format::ALL {
        assert_eq!(Format::from_name(format.name()), Some(format));
        assert_eq!(format.name().parse::<Format>().ok(), Some(format));
        assert_eq!(format.to_string(), format.name());
        let file = format!("out.{}", format.extension());
        assert_eq!(Format::from_path(Path::new(&file)), Some(format));
        assert_eq!(format.is_text(), format != Format::Hdf5);
    }
}
