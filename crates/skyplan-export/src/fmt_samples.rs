//! A table of samples (a trajectory's): CSV with a header, or HDF5 with one dataset.

use hdf5_writer::{AttributeBuilder, ByteOrder, DatasetBuilder, Hdf5Builder, WriteOptions};

use crate::ExportError;

/// The name of the dataset written by [`samples_hdf5`].
pub const SAMPLES_DATASET: &str = "samples";

fn check_rows<const N: usize>(rows: &[[f64; N]]) -> Result<(), ExportError> {
    for (i, r) in rows.iter().enumerate() {
        if let Some(&value) = r.iter().find(|v| !v.is_finite()) {
            return Err(ExportError::NonFinite {
                what: format!("sample {i}"),
                value,
            });
        }
    }
    Ok(())
}

/// Encodes rows of samples as CSV: the header `columns`, then one line a row (numbers in
/// their shortest exact text).
///
/// ```
/// let text = skyplan_export::samples_csv(&["t_s", "x_m"], &[[0.0, 1.5], [0.1, 2.0]])?;
/// assert_eq!(text, "t_s,x_m\n0,1.5\n0.1,2\n");
/// # Ok::<(), skyplan_export::ExportError>(())
/// ```
pub fn samples_csv<const N: usize>(
    columns: &[&str; N],
    rows: &[[f64; N]],
) -> Result<String, ExportError> {
    check_rows(rows)?;
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(columns)?;
    for r in rows {
        writer.write_record(r.iter().map(f64::to_string))?;
    }
    let bytes = writer
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// Encodes rows of samples as an HDF5 file with one dataset, `samples`: little-endian float64
/// of shape `[rows, N]`, with a `columns` string attribute (the names joined by commas), as
/// `h5py.File(path)['samples'][:]` reads it.
pub fn samples_hdf5<const N: usize>(
    columns: &[&str; N],
    rows: &[[f64; N]],
) -> Result<Vec<u8>, ExportError> {
    check_rows(rows)?;
    let values: Vec<f64> = rows.iter().flatten().copied().collect();
    let dataset = DatasetBuilder::typed_with_order::<f64>(
        SAMPLES_DATASET,
        vec![rows.len() as u64, N as u64],
        ByteOrder::LittleEndian,
    )
    .data(&values)?
    .attribute(AttributeBuilder::fixed_string("columns", columns.join(",")));
    let plan = Hdf5Builder::new().dataset(dataset).into_plan()?;
    let options = WriteOptions {
        byte_order: ByteOrder::LittleEndian,
        ..WriteOptions::default()
    };
    Ok(plan.encode(options)?)
}
