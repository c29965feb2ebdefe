//! Reads `to_hdf5` output back with h5py, the way FCND code does.

mod common;

use std::io::Write;
use std::path::Path;
use std::process::Command;

use skyplan_export::{HDF5_DATASET, to_hdf5};
use skyplan_mission::Mission;

/// Prints the `data` dataset's shape, dtype and values (also as IEEE bit patterns, since
/// serde_json's default float parsing may be off by an ULP), plus the home attributes.
const READER: &str = r#"
import h5py, json, struct, sys
f = h5py.File(sys.argv[1], 'r')
d = f['data']
rows = d[:].tolist()
bits = [[struct.unpack('<Q', struct.pack('<d', x))[0] for x in row] for row in rows]
print(json.dumps({
    'shape': list(d.shape),
    'dtype': str(d.dtype),
    'byteorder': d.dtype.byteorder,
    'data': rows,
    'bits': bits,
    'keys': list(f.keys()),
    'home': [float(f.attrs[k]) for k in ('home_lat_deg', 'home_lon_deg', 'home_alt_m')],
}))
"#;

/// The Python that has h5py: `SKYPLAN_PYTHON` (set by `.ci/run` to its virtual environment),
/// else `python3`.
fn python() -> String {
    std::env::var("SKYPLAN_PYTHON").unwrap_or_else(|_| "python3".to_string())
}

/// Writes the HDF5 bytes to a temp file and reads them with h5py.
fn read_with_h5py(bytes: &[u8]) -> serde_json::Value {
    let mut file = tempfile::Builder::new().suffix(".h5").tempfile().unwrap();
    file.write_all(bytes).unwrap();
    file.flush().unwrap();
    run_reader(file.path())
}

fn run_reader(path: &Path) -> serde_json::Value {
    let out = Command::new(python())
        .args(["-c", READER])
        .arg(path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "h5py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn check(mission: &Mission) {
    let bytes = to_hdf5(mission).unwrap();
    assert_eq!(&bytes[..8], b"\x89HDF\r\n\x1a\n");
    let got = read_with_h5py(&bytes);
    let n = mission.waypoints.len();
    assert_eq!(got["shape"], serde_json::json!([n, 4]));
    assert_eq!(got["dtype"], "float64");
    assert!(
        matches!(got["byteorder"].as_str(), Some("<" | "=")),
        "little-endian: {}",
        got["byteorder"]
    );
    assert_eq!(got["keys"], serde_json::json!([HDF5_DATASET]));

    let rows = mission.rows();
    let want_bits: Vec<Vec<u64>> = rows
        .iter()
        .map(|r| r.iter().map(|x| x.to_bits()).collect())
        .collect();
    assert_eq!(
        got["bits"],
        serde_json::json!(want_bits),
        "values bit-for-bit"
    );
    let data = got["data"].as_array().unwrap();
    assert_eq!(data.len(), n);
    for (row, want) in data.iter().zip(&rows) {
        for (x, want) in row.as_array().unwrap().iter().zip(want) {
            common::assert_close(common::num(x), *want);
        }
    }
    let home = common::home();
    let got_home: Vec<u64> = got["home"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| common::num(x).to_bits())
        .collect();
    assert_eq!(got_home.len(), 3);
    common::assert_close(f64::from_bits(got_home[0]), home.lat_deg);
    common::assert_close(f64::from_bits(got_home[1]), home.lon_deg);
    common::assert_close(f64::from_bits(got_home[2]), home.alt_m);
}

#[test]
#[ignore = "needs python3 with h5py (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn h5py_reads_the_fcnd_layout() {
    check(&common::sample());
}

#[test]
#[ignore = "needs python3 with h5py (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn h5py_reads_a_single_waypoint() {
    check(&common::single());
}

#[test]
#[ignore = "needs python3 with h5py (SKYPLAN_PYTHON: .ci/run sets its virtual environment)"]
fn empty_mission_gives_a_0_by_4_dataset() {
    check(&common::empty());
}
