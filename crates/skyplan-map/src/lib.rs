//! Map sources for skyplan, parsed from text without any I/O.
//!
//! * [`colliders`]: the FCND city map `colliders.csv` — a geodetic home on line 1, then
//!   axis-aligned boxes `posX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ` in metres
//!   (north, east, up; centre and half sizes).
//! * [`movingai`]: MovingAI / GPPC benchmark grids (`.map`) and scenarios (`.scen`).
//! * [`maze`]: seeded perfect mazes shaped like MovingAI's, and scenarios for them with exact
//!   Dijkstra lengths.
//! * [`footprints`]: building footprints from GeoJSON (polygons with holes and heights, in
//!   longitude/latitude), projected to local metres about a home.
//! * [`terrain`]: digital elevation models (GeoTIFF, SRTM `.hgt`) and routes that keep a height
//!   above the ground.
//!
//! Every parser returns a [`ParseError`] that names the line, the column and what was expected;
//! the caller adds the file name. No parser panics on any input.
//!
//! ```
//! let text = "lat0 37.792480, lon0 -122.397450\n\
//!             posX,posY,posZ,halfSizeX,halfSizeY,halfSizeZ\n\
//!             10,20,5,2,3,5\n";
//! let map = skyplan_map::colliders::parse_colliders(text)?;
//! assert_eq!(map.home.lat_deg, 37.792480);
//! assert_eq!(map.boxes.len(), 1);
//! assert_eq!(map.boxes[0].top_m(), 10.0);
//! # Ok::<(), skyplan_map::ParseError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod civil;
pub mod colliders;
pub mod contour;
pub mod footprints;
pub mod maze;
pub mod movingai;
pub mod nofly;
pub mod osm;
pub mod planar;
pub mod terrain;
mod tile;

pub use tile::{tile, to_colliders_csv};

use std::fmt;

/// A parse failure at a precise place in the input text.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct ParseError {
    /// 1-based line number; 0 when the error concerns the input as a whole.
    pub line: usize,
    /// 1-based column: the comma-separated field for CSV files, the character otherwise.
    pub column: Option<usize>,
    /// What the parser was reading there (for example `halfSizeX` or `home line`).
    pub field: String,
    /// What was expected and what was found instead.
    pub message: String,
}

impl ParseError {
    pub(crate) fn new(
        line: usize,
        column: Option<usize>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            line,
            column,
            field: field.into(),
            message: message.into(),
        }
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.column) {
            (0, _) => write!(f, "{}: {}", self.field, self.message),
            (line, Some(col)) => {
                write!(
                    f,
                    "line {line}, column {col} ({}): {}",
                    self.field, self.message
                )
            }
            (line, None) => write!(f, "line {line} ({}): {}", self.field, self.message),
        }
    }
}

/// The lines of `text` numbered from 1, each without a trailing `\r`.
pub(crate) fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
}

/// Shortens a token for an error message so that a garbled file cannot flood the terminal.
pub(crate) fn shown(token: &str) -> String {
    const MAX: usize = 40;
    let mut out: String = token.chars().take(MAX).collect();
    if token.chars().count() > MAX {
        out.push('…');
    }
    format!("{out:?}")
}
