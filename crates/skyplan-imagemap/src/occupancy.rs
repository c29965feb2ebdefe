//! Pixels to ROS occupancy values and to a skyplan grid.

use crate::{ImageMapError, MapMode, MapYaml, Raster, north_up_grid};
use skyplan_cspace::{Grid2, GridFrame};

/// ROS occupancy of a free cell.
pub const OCC_FREE: i8 = 0;
/// ROS occupancy of an occupied cell.
pub const OCC_OCCUPIED: i8 = 100;
/// ROS occupancy of an unknown cell.
pub const OCC_UNKNOWN: i8 = -1;

/// The occupancy of every pixel as ROS 2 `map_server` (nav2 `map_io`) computes it, in the
/// raster's own order (top row first): `shade = grey / 255`, `occ = negate ? shade : 1 − shade`;
/// trinary: `occ > occupied_thresh` → 100, `occ < free_thresh` → 0, else −1; scale: transparent
/// → −1, between the thresholds `rint((occ − free) / (occupied − free) · 100)`; raw: the grey
/// level if ≤ 100, else −1.
pub fn occupancy(raster: &Raster, meta: &MapYaml) -> Vec<i8> {
    raster
        .gray
        .iter()
        .enumerate()
        .map(|(i, &g)| {
            let shade = f64::from(g) / 255.0;
            let occ = if meta.negate { shade } else { 1.0 - shade };
            let opaque = raster.alpha.as_ref().is_none_or(|a| a[i] == 255);
            match meta.mode {
                MapMode::Trinary | MapMode::Scale if occ > meta.occupied_thresh => OCC_OCCUPIED,
                MapMode::Scale if !opaque => OCC_UNKNOWN,
                MapMode::Trinary | MapMode::Scale if occ < meta.free_thresh => OCC_FREE,
                MapMode::Trinary => OCC_UNKNOWN,
                MapMode::Scale => {
                    let span = meta.occupied_thresh - meta.free_thresh;
                    if span > 0.0 {
                        ((occ - meta.free_thresh) / span * 100.0).round_ties_even() as i8
                    } else {
                        OCC_OCCUPIED
                    }
                }
                MapMode::Raw if g <= 100 => g as i8,
                MapMode::Raw => OCC_UNKNOWN,
            }
        })
        .collect()
}

/// An occupancy image as a skyplan grid.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageMap {
    /// The grid: a cell is blocked if occupied (100) or unknown (−1), unless unknown cells were
    /// asked to be free; scaled values below 100 are free, as in Nav2's static layer.
    pub grid: Grid2,
    /// ROS occupancy per cell, in grid order (row 0 = the BOTTOM image row).
    pub occupancy: Vec<i8>,
    /// Number of unknown cells.
    pub unknown_cells: usize,
}

/// Builds the grid of an image map (unknown cells blocked): cell `(row, col)` is pixel
/// `(x = col, y = height − 1 − row)`, the frame's origin is the YAML origin (`origin_east_m = x`,
/// `origin_north_m = y`) and its cell size the resolution.
pub fn image_map(raster: &Raster, meta: &MapYaml) -> Result<ImageMap, ImageMapError> {
    image_map_with(raster, meta, false)
}

/// As [`image_map`], choosing whether unknown cells are free.
pub fn image_map_with(
    raster: &Raster,
    meta: &MapYaml,
    unknown_is_free: bool,
) -> Result<ImageMap, ImageMapError> {
    meta.validate()?;
    if raster.width == 0 || raster.height == 0 {
        return Err(ImageMapError::Empty {
            width: raster.width,
            height: raster.height,
        });
    }
    let occ_top_first = occupancy(raster, meta);
    let blocked_top_first: Vec<bool> = occ_top_first
        .iter()
        .map(|&o| o == OCC_OCCUPIED || (o == OCC_UNKNOWN && !unknown_is_free))
        .collect();
    let frame = GridFrame {
        origin_north_m: meta.origin[1],
        origin_east_m: meta.origin[0],
        cell_m: meta.resolution,
    };
    let grid = north_up_grid(raster.width, raster.height, &blocked_top_first, frame)?;
    // The same flip for the occupancy values, through the same function's row order.
    let w = raster.width as usize;
    let mut occupancy = Vec::with_capacity(occ_top_first.len());
    for row in 0..raster.height as usize {
        let y = raster.height as usize - 1 - row;
        occupancy.extend_from_slice(&occ_top_first[y * w..(y + 1) * w]);
    }
    let unknown_cells = occupancy.iter().filter(|&&o| o == OCC_UNKNOWN).count();
    Ok(ImageMap {
        grid,
        occupancy,
        unknown_cells,
    })
}
