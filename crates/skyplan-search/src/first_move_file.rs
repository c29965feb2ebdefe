//! The first-move table on disk, like the contraction hierarchy ([`crate::ch_file`]): a
//! versioned header, the checksum of the grid it was built for, the table's rows, and a checksum
//! of them.
//!
//! Layout (little-endian), version 1:
//!
//! | bytes | field |
//! |---|---|
//! | 16 | magic `SKYPLAN-FM-FILE\n` |
//! | 4 | version (1) |
//! | 4 | move model: 1 = octile, 2 = octile with corner cutting, 3 = 4-connected |
//! | 4, 4 | grid rows, columns |
//! | 8 | [`grid_checksum`] of the grid |
//! | 4 | free cells `n` (the rows, one per free target in row-major order) |
//! | 8 | checksum of the body |
//! | body | `n` rows of ⌈rows × columns / 2⌉ bytes ([`FirstMoveTable`]'s layout) |
//!
//! Loading ([`FirstMoveTable::read_from`]) checks the header against the grid it is given and
//! the checksum: a damaged or foreign file is a [`FirstMoveFileError`] naming what is wrong,
//! never a panic. Checking every row's structure at load would cost as much as building the
//! table, so queries check instead: every step of a path is checked to be an allowed move onto a
//! free cell, and a path longer than the free cells is a cycle, so a file that passes its
//! checksum but was written wrong gives [`crate::SearchError::Damaged`], never a path through an
//! obstacle. The library opens no files: callers hand it any [`Read`] / [`Write`].

use crate::ch_file::{GridMismatch, HeadError, body_sum, read_head, u32_at, u64_at, write_head};
use crate::first_move::FreeCells;
use crate::{FirstMoveTable, MoveModel};
use skyplan_cspace::Grid2;
use std::io::{self, Read, Write};
use std::sync::Arc;

/// The first 16 bytes of a first-move table file.
pub const MAGIC: &[u8; 16] = b"SKYPLAN-FM-FILE\n";
/// The version this build writes and reads.
pub const VERSION: u32 = 1;
/// Bytes before the body.
pub const HEADER_BYTES: usize = 16 + 4 + 4 + 4 + 4 + 8 + 4 + 8;

/// Why a first-move table file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FirstMoveFileError {
    /// Not a first-move table file.
    #[error("not a skyplan first-move table (expected the header `SKYPLAN-FM-FILE`)")]
    NotATable,
    /// Written by another version of the format.
    #[error(
        "first-move table format version {found}; this skyplan reads version {expected} (rebuild it)"
    )]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        expected: u32,
    },
    /// The file is shorter or longer than its header says.
    #[error("first-move table is {found} bytes; its header says {expected} (truncated or damaged)")]
    Length {
        /// Bytes expected from the header.
        expected: u64,
        /// Bytes found (at least; reading stops one byte past the expected length).
        found: u64,
    },
    /// The body does not match its checksum.
    #[error("first-move table is damaged (its checksum does not match its contents)")]
    Checksum,
    /// Built for another grid or move model.
    #[error("first-move table was built for {0}")]
    OtherGrid(GridMismatch),
    /// The header's counts do not match the grid although its checksum does.
    #[error("first-move table is damaged: {0}")]
    Damaged(String),
    /// The reader or writer failed.
    #[error("first-move table input/output: {0}")]
    Io(String),
}

impl From<io::Error> for FirstMoveFileError {
    fn from(e: io::Error) -> Self {
        FirstMoveFileError::Io(e.to_string())
    }
}

impl FirstMoveTable {
    /// Bytes of its file.
    pub fn file_bytes(&self) -> u64 {
        HEADER_BYTES as u64 + self.moves.len() as u64
    }

    /// Writes the table as a file (see the module docs) to `out`.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{FirstMoveTable, MoveModel};
    /// let grid = Arc::new(Grid2::from_ascii("......\n.####.\n......")?);
    /// let built = FirstMoveTable::build(Arc::clone(&grid), MoveModel::Octile, 1 << 20)?;
    /// let mut bytes = Vec::new();
    /// built.write_to(&mut bytes)?;
    /// assert_eq!(bytes.len() as u64, built.file_bytes());
    /// let loaded = FirstMoveTable::read_from(&bytes[..], grid, MoveModel::Octile)?;
    /// let (a, b) = (Cell::new(0, 0), Cell::new(2, 5));
    /// assert_eq!(loaded.search(a, b)?.cells, built.search(a, b)?.cells);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn write_to(&self, mut out: impl Write) -> Result<(), FirstMoveFileError> {
        let mut header = Vec::with_capacity(HEADER_BYTES);
        write_head(&mut header, MAGIC, VERSION, &self.grid, self.model);
        header.extend_from_slice(&(self.targets.len() as u32).to_le_bytes());
        header.extend_from_slice(&body_sum(&self.moves).to_le_bytes());
        out.write_all(&header)?;
        out.write_all(&self.moves)?;
        out.flush()?;
        Ok(())
    }

    /// Reads a table file written by [`FirstMoveTable::write_to`] for `grid` under `model`;
    /// refused with a [`FirstMoveFileError`] if it is not one, another version, truncated,
    /// damaged, or built for another grid or move model.
    pub fn read_from(
        mut input: impl Read,
        grid: Arc<Grid2>,
        model: MoveModel,
    ) -> Result<Self, FirstMoveFileError> {
        let header = read_head::<HEADER_BYTES>(&mut input, MAGIC, VERSION, &grid, model).map_err(
            |e| match e {
                HeadError::Foreign => FirstMoveFileError::NotATable,
                HeadError::Short { expected, found } => {
                    FirstMoveFileError::Length { expected, found }
                }
                HeadError::Version(found) => FirstMoveFileError::Version {
                    found,
                    expected: VERSION,
                },
                HeadError::OtherGrid(m) => FirstMoveFileError::OtherGrid(m),
                HeadError::Io(e) => e.into(),
            },
        )?;
        let u32_at = |at: usize| u32_at(&header, at);
        let u64_at = |at: usize| u64_at(&header, at);
        let cells = FreeCells::of(&grid, model);
        let n = cells.cell_of.len();
        if u32_at(40) as usize != n {
            return Err(FirstMoveFileError::Damaged(format!(
                "it has {} rows; the grid has {n} free cells",
                u32_at(40)
            )));
        }
        let body_checksum = u64_at(44);
        let row_bytes = grid.len().div_ceil(2);
        let expected = (n * row_bytes) as u64;
        // Read at most one byte past the expected length: memory grows only with what is there.
        let mut moves = Vec::new();
        (&mut input).take(expected + 1).read_to_end(&mut moves)?;
        if moves.len() as u64 != expected {
            return Err(FirstMoveFileError::Length {
                expected: HEADER_BYTES as u64 + expected,
                found: HEADER_BYTES as u64 + moves.len() as u64,
            });
        }
        if body_sum(&moves) != body_checksum {
            return Err(FirstMoveFileError::Checksum);
        }
        Ok(FirstMoveTable::from_parts(grid, model, cells, moves))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_cspace::Cell;

    fn table() -> (Arc<Grid2>, Vec<u8>) {
        let grid = Arc::new(Grid2::from_ascii("......\n.##.#.\n......\n#....#").unwrap());
        let t = FirstMoveTable::build(Arc::clone(&grid), MoveModel::Octile, 1 << 20).unwrap();
        let mut bytes = Vec::new();
        t.write_to(&mut bytes).unwrap();
        (grid, bytes)
    }

    /// The body re-checksummed after an edit, so that only the structure check can catch it.
    fn resealed(mut bytes: Vec<u8>) -> Vec<u8> {
        let sum = body_sum(&bytes[HEADER_BYTES..]);
        bytes[44..52].copy_from_slice(&sum.to_le_bytes());
        bytes
    }

    #[test]
    fn a_saved_table_loads_and_answers_the_same() {
        let (grid, bytes) = table();
        let built = FirstMoveTable::build(Arc::clone(&grid), MoveModel::Octile, 1 << 20).unwrap();
        let loaded =
            FirstMoveTable::read_from(&bytes[..], Arc::clone(&grid), MoveModel::Octile).unwrap();
        for a in 0..grid.len() as u32 {
            for b in 0..grid.len() as u32 {
                let (a, b) = (Cell::new(a / 6, a % 6), Cell::new(b / 6, b % 6));
                let (x, y) = (built.search(a, b), loaded.search(a, b));
                assert_eq!(x.map(|p| p.cells).ok(), y.map(|p| p.cells).ok());
            }
        }
    }

    #[test]
    fn damaged_foreign_and_truncated_files_are_refused_by_name() {
        let (grid, bytes) = table();
        let read =
            |b: &[u8], model| FirstMoveTable::read_from(b, Arc::clone(&grid), model).unwrap_err();
        assert_eq!(
            read(b"SKYPLAN-CH-FILE\n....", MoveModel::Octile),
            FirstMoveFileError::NotATable
        );
        assert!(matches!(
            read(&bytes[..bytes.len() - 1], MoveModel::Octile),
            FirstMoveFileError::Length { .. }
        ));
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(
            read(&longer, MoveModel::Octile),
            FirstMoveFileError::Length { .. }
        ));
        assert!(matches!(
            read(&bytes, MoveModel::FourConnected),
            FirstMoveFileError::OtherGrid(_)
        ));
        let mut version = bytes.clone();
        version[16] = 9;
        assert!(matches!(
            read(&version, MoveModel::Octile),
            FirstMoveFileError::Version { found: 9, .. }
        ));
        let mut flipped = bytes.clone();
        let last = flipped.len() - 1;
        flipped[last] ^= 0x10;
        assert_eq!(
            read(&flipped, MoveModel::Octile),
            FirstMoveFileError::Checksum
        );
        let other = Grid2::from_ascii("......\n.##.#.\n......\n#.....").unwrap();
        let err =
            FirstMoveTable::read_from(&bytes[..], Arc::new(other), MoveModel::Octile).unwrap_err();
        assert!(matches!(err, FirstMoveFileError::OtherGrid(_)), "{err}");
        // Every single-entry edit that keeps the checksum right loads; its queries then give
        // valid paths (the entry was one of several first moves of shortest paths), or refuse
        // as damaged, never a path off the free cells.
        let row_bytes = grid.len().div_ceil(2);
        let mut caught = 0;
        for byte in HEADER_BYTES..bytes.len() {
            for value in [0x00, 0x11, 0x88, 0xff, 0x37, 0x65] {
                let mut edited = bytes.clone();
                edited[byte] = value;
                let edited = resealed(edited);
                let t =
                    FirstMoveTable::read_from(&edited[..], Arc::clone(&grid), MoveModel::Octile)
                        .unwrap();
                let b = t.targets[(byte - HEADER_BYTES) / row_bytes];
                for a in 0..grid.len() as u32 {
                    let (a, b) = (Cell::new(a / 6, a % 6), Cell::new(b / 6, b % 6));
                    match t.search(a, b) {
                        Ok(p) => {
                            crate::check_path(&grid, &p.cells, MoveModel::Octile).unwrap();
                            assert_eq!((p.cells[0], *p.cells.last().unwrap()), (a, b));
                        }
                        Err(crate::SearchError::Damaged(_)) => caught += 1,
                        Err(_) => {}
                    }
                }
            }
        }
        assert!(caught > 100, "{caught} edits caught");
    }
}
