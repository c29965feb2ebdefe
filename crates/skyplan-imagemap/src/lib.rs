//! Grid sources for skyplan besides the FCND colliders map, all without I/O:
//!
//! * [`decode_image`]: PNG (any colour type and depth) or PGM (`P2`/`P5`) bytes to a grey
//!   [`Raster`] (top image row first, as stored in the file);
//! * [`MapYaml`]: the ROS `map_server` metadata (`image`, `resolution`, `origin`,
//!   `occupied_thresh`, `free_thresh`, `negate`, `mode`), from YAML text or [`MapYaml::bare`];
//! * [`image_map`]: a raster and its metadata to a [`Grid2`] and the ROS occupancy values;
//! * [`grid_from_movingai`]: a MovingAI map, north up;
//! * [`random_workspace`] and [`draw_free_cells`]: reproducible random grids and endpoints.
//!
//! **Axes.** Images and MovingAI maps store their top row first; skyplan grids count rows north
//! from the southern edge. [`north_up_grid`] is the one function that turns one into the other:
//! image pixel `(x, y)` (column `x` from the left, row `y` from the top of an image `height` rows
//! high) is grid cell `row = height − 1 − y`, `col = x`. So east = x and north = y upwards from
//! the YAML `origin`, which places the lower-left corner of the lower-left pixel.
//!
//! ```
//! use skyplan_cspace::Cell;
//! use skyplan_imagemap::{decode_image, image_map, MapYaml};
//! // A 3 × 2 PGM: the black (occupied) pixel is in the top-left corner of the picture.
//! let pgm = b"P2\n3 2\n255\n0 255 255\n255 255 255\n";
//! let raster = decode_image(pgm)?;
//! let map = image_map(&raster, &MapYaml::bare(0.5))?;
//! assert!(map.grid.is_blocked(Cell::new(1, 0))); // top row = northern row 1, west column 0
//! assert_eq!(map.grid.blocked_count(), 1);
//! assert_eq!(map.grid.center_ne(Cell::new(1, 0)), (0.75, 0.25));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod image;
mod occupancy;
mod random;
mod yaml;

pub use image::{Raster, decode_image, decode_pgm, decode_png, image_size};
pub use occupancy::{
    ImageMap, OCC_FREE, OCC_OCCUPIED, OCC_UNKNOWN, image_map, image_map_with, occupancy,
};
pub use random::{draw_free_cells, random_workspace};
pub use yaml::{MapMode, MapYaml};

use skyplan_cspace::{Grid2, GridError, GridFrame};

/// Why an image map could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImageMapError {
    /// The PNG decoder refused the bytes.
    #[error("PNG: {0}")]
    Png(String),
    /// A PGM file that does not follow the format.
    #[error("PGM {field}: {message}")]
    Pgm {
        /// The part of the file: `magic`, `width`, `height`, `maxval`, `pixels`.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Neither a PNG nor a PGM.
    #[error("not a PNG or PGM image (expected the PNG signature or `P2`/`P5`)")]
    UnknownFormat,
    /// An image without pixels.
    #[error("the image is empty ({width} × {height} pixels)")]
    Empty {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// A map_server YAML field missing or out of range.
    #[error("{field}: {message}")]
    Yaml {
        /// The field, as named in the file (`resolution`, `origin`, …), or `yaml` for syntax.
        field: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A random workspace parameter out of range.
    #[error("{name} = {value}: expected {expected}")]
    BadParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
    /// The grid could not be built.
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// The one place where top-first rows become north-counted rows: `blocked_top_first[y · width + x]`
/// (row `y` from the top) lands in grid cell `(height − 1 − y, x)`.
///
/// ```
/// use skyplan_cspace::{Cell, GridFrame};
/// let grid = skyplan_imagemap::north_up_grid(2, 2, &[true, false, false, false], GridFrame::default())?;
/// assert!(grid.is_blocked(Cell::new(1, 0))); // the top-left pixel is the north-west cell
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
pub fn north_up_grid(
    width: u32,
    height: u32,
    blocked_top_first: &[bool],
    frame: GridFrame,
) -> Result<Grid2, GridError> {
    let (w, h) = (width as usize, height as usize);
    if blocked_top_first.len() != w * h {
        return Err(GridError::SizeMismatch {
            rows: height,
            cols: width,
            found: blocked_top_first.len(),
        });
    }
    let mut blocked = Vec::with_capacity(w * h);
    for row in 0..h {
        let y = h - 1 - row;
        blocked.extend_from_slice(&blocked_top_first[y * w..(y + 1) * w]);
    }
    Grid2::new(height, width, blocked, frame)
}

/// A MovingAI map as a north-up grid of 1-unit cells: the first map line is the northernmost row,
/// so MovingAI's `(x, y)` (y counted down from the top) is cell `(height − 1 − y, x)`.
///
/// ```
/// use skyplan_cspace::Cell;
/// let map = skyplan_map::movingai::parse_map("type octile\nheight 2\nwidth 2\nmap\n@.\n..\n")?;
/// let grid = skyplan_imagemap::grid_from_movingai(&map)?;
/// assert!(grid.is_blocked(Cell::new(1, 0)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn grid_from_movingai(map: &skyplan_map::movingai::MovingAiMap) -> Result<Grid2, GridError> {
    let too_large = || GridError::TooLarge {
        rows: map.height as u64,
        cols: map.width as u64,
    };
    let width = u32::try_from(map.width).map_err(|_| too_large())?;
    let height = u32::try_from(map.height).map_err(|_| too_large())?;
    let blocked: Vec<bool> = map.passable.iter().map(|&p| !p).collect();
    north_up_grid(width, height, &blocked, GridFrame::default())
}
