//! HDF5 file in the layout FCND reads.

use hdf5_writer::{
    AttributeBuilder, ByteOrder, DatasetBuilder, Datatype, Hdf5Builder, WriteOptions,
};
use skyplan_mission::Mission;

use crate::{ExportError, check_finite};

/// The name of the dataset written by [`to_hdf5`].
pub const HDF5_DATASET: &str = "data";

/// A little-endian float64 scalar attribute.
fn f64_attribute(name: &str, value: f64) -> AttributeBuilder {
    let datatype = Datatype::FloatingPoint {
        size: 8,
        byte_order: ByteOrder::LittleEndian,
    };
    AttributeBuilder::new(name, datatype, Vec::new(), value.to_le_bytes().to_vec())
}

/// Encodes a mission as an HDF5 file holding one dataset, `data`: little-endian float64 of shape
/// `[n, 4]`, the rows `[north, east, alt, heading]` of [`Mission::rows`]. This is what FCND code
/// reads with `h5py.File(path)['data'][:]`.
///
/// The file also carries float64 scalar attributes `home_lat_deg`, `home_lon_deg` and
/// `home_alt_m` on the root group, and a `columns` string attribute on `data`
/// (`"north_m,east_m,alt_m,heading_rad"`).
///
/// An empty mission gives a valid file whose `data` has shape `[0, 4]`.
pub fn to_hdf5(mission: &Mission) -> Result<Vec<u8>, ExportError> {
    check_finite(mission)?;
    let values: Vec<f64> = mission.rows().into_iter().flatten().collect();
    let rows = mission.waypoints.len() as u64;
    let dataset = DatasetBuilder::typed_with_order::<f64>(
        HDF5_DATASET,
        vec![rows, 4],
        ByteOrder::LittleEndian,
    )
    .data(&values)?
    .attribute(AttributeBuilder::fixed_string(
        "columns",
        "north_m,east_m,alt_m,heading_rad",
    ));
    let home = &mission.home;
    let plan = Hdf5Builder::new()
        .dataset(dataset)
        .attribute(f64_attribute("home_lat_deg", home.lat_deg))
        .attribute(f64_attribute("home_lon_deg", home.lon_deg))
        .attribute(f64_attribute("home_alt_m", home.alt_m))
        .into_plan()?;
    let options = WriteOptions {
        byte_order: ByteOrder::LittleEndian,
        ..WriteOptions::default()
    };
    Ok(plan.encode(options)?)
}
