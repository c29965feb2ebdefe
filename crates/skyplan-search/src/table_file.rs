//! The JPS+ table on disk: a versioned header, the checksum of the grid it was built for, the
//! table, and a checksum of the table.
//!
//! Layout (little-endian), version 1:
//!
//! | bytes | field |
//! |---|---|
//! | 16 | magic `SKYPLAN-JPSPLUS\n` |
//! | 4 | version (1) |
//! | 4 | corner rule: 1 = octile, no corner cutting; 2 = octile with corner cutting |
//! | 4, 4 | grid rows, columns |
//! | 8 | [`grid_checksum`] of the grid |
//! | 3 × 8 | the grid's altitude, margin and cell size in metres as the caller gave them
//! (`NaN` for a fixed grid): how to rebuild the grid |
//! | 8 | checksum of the table bytes |
//! | rows × cols × 8 × 4 | per cell, per direction ([`crate::jps`]'s order), the jump value (i32) |
//!
//! Loading checks all of it against the grid it is given, and every jump value against the
//! grid's borders, so a damaged or foreign file is an error, never a wrong path or a panic.
//! The free-neighbour masks are not stored: they are recomputed from the grid.

use crate::jps::DIRS;
use crate::{JpsPlusTable, MoveModel};
use skyplan_cspace::Grid2;
use std::sync::Arc;

/// The first 16 bytes of a table file.
pub const MAGIC: &[u8; 16] = b"SKYPLAN-JPSPLUS\n";
/// The version this build writes and reads.
pub const VERSION: u32 = 1;
const HEADER_BYTES: usize = 16 + 4 + 4 + 8 + 8 + 24 + 8;

/// Why a table file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TableFileError {
    /// Not a JPS+ table file.
    #[error("not a skyplan JPS+ table (expected the header `SKYPLAN-JPSPLUS`)")]
    NotATable,
    /// Written by another version of the format.
    #[error("JPS+ table format version {found}; this skyplan reads version {expected}")]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        expected: u32,
    },
    /// The file is shorter or longer than its header says.
    #[error("JPS+ table is {found} bytes; its header says {expected} (truncated or damaged)")]
    Length {
        /// Bytes expected from the header.
        expected: u64,
        /// Bytes found.
        found: u64,
    },
    /// A header field has an impossible value.
    #[error("JPS+ table header: {0}")]
    Header(String),
    /// The table bytes do not match their checksum.
    #[error("JPS+ table is damaged (its checksum does not match its contents)")]
    Checksum,
    /// The table was built for another grid.
    #[error(
        "JPS+ table was built for a {file_rows} × {file_cols} grid with checksum {file_sum:016x}; \
         this grid is {rows} × {cols} with checksum {sum:016x} (another map, altitude, margin or cell size)"
    )]
    OtherGrid {
        /// Rows in the file.
        file_rows: u32,
        /// Columns in the file.
        file_cols: u32,
        /// Grid checksum in the file.
        file_sum: u64,
        /// Rows of the grid given.
        rows: u32,
        /// Columns of the grid given.
        cols: u32,
        /// Checksum of the grid given.
        sum: u64,
    },
    /// A jump value points past the grid's border.
    #[error("JPS+ table entry at row {row}, column {col} points off the grid (damaged table)")]
    OffGrid {
        /// Row of the entry.
        row: u32,
        /// Column of the entry.
        col: u32,
    },
}

/// What a table file's header says (read without the grid).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableHeader {
    /// The corner rule.
    pub model: MoveModel,
    /// Grid rows.
    pub rows: u32,
    /// Grid columns.
    pub cols: u32,
    /// [`grid_checksum`] of the grid.
    pub grid_checksum: u64,
    /// Altitude, margin and cell size (metres) the caller gave when saving (`NaN` if none).
    pub spec: [f64; 3],
}

/// A 64-bit checksum of a grid's size and occupancy (not cryptographic: it tells grids apart).
pub fn grid_checksum(grid: &Grid2) -> u64 {
    let mut h = Hasher::new();
    h.word(u64::from(grid.rows()) << 32 | u64::from(grid.cols()));
    for chunk in grid.blocked_cells().chunks(64) {
        let bits = chunk
            .iter()
            .enumerate()
            .fold(0u64, |w, (k, &b)| w | (u64::from(b) << k));
        h.word(bits);
    }
    h.finish()
}

/// Word-at-a-time multiply–rotate mixing (a 64-bit FNV-style hash over words).
struct Hasher(u64);

impl Hasher {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    #[inline]
    fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w)
            .wrapping_mul(0x0000_0100_0000_01b3)
            .rotate_left(29);
    }
    fn finish(&self) -> u64 {
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

fn payload_checksum(payload: &[u8]) -> u64 {
    let mut h = Hasher::new();
    let mut words = payload.chunks_exact(8);
    for w in &mut words {
        h.word(u64::from_le_bytes(w.try_into().unwrap_or_default()));
    }
    let mut tail = [0u8; 8];
    tail[..words.remainder().len()].copy_from_slice(words.remainder());
    h.word(u64::from_le_bytes(tail));
    h.word(payload.len() as u64);
    h.finish()
}

fn model_code(model: MoveModel) -> u32 {
    match model {
        MoveModel::OctileCornerCutting => 2,
        MoveModel::Octile | MoveModel::FourConnected => 1,
    }
}

/// Reads the header of a table file.
pub fn read_header(bytes: &[u8]) -> Result<TableHeader, TableFileError> {
    if bytes.len() < 16 || &bytes[..16] != MAGIC {
        return Err(TableFileError::NotATable);
    }
    if bytes.len() < HEADER_BYTES {
        return Err(TableFileError::Length {
            expected: HEADER_BYTES as u64,
            found: bytes.len() as u64,
        });
    }
    let u32_at =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let u64_at = |at: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&bytes[at..at + 8]);
        u64::from_le_bytes(b)
    };
    let version = u32_at(16);
    if version != VERSION {
        return Err(TableFileError::Version {
            found: version,
            expected: VERSION,
        });
    }
    let model = match u32_at(20) {
        1 => MoveModel::Octile,
        2 => MoveModel::OctileCornerCutting,
        other => {
            return Err(TableFileError::Header(format!(
                "corner rule {other} (expected 1 = octile or 2 = octile with corner cutting)"
            )));
        }
    };
    let (rows, cols) = (u32_at(24), u32_at(28));
    let spec = [
        f64::from_bits(u64_at(40)),
        f64::from_bits(u64_at(48)),
        f64::from_bits(u64_at(56)),
    ];
    Ok(TableHeader {
        model,
        rows,
        cols,
        grid_checksum: u64_at(32),
        spec,
    })
}

impl JpsPlusTable {
    /// The table as a file (module [`crate::table_file`]); `spec` is stored for the reader:
    /// the grid's altitude, margin and cell size in metres (`NaN` for a fixed grid).
    pub fn to_bytes(&self, spec: [f64; 3]) -> Vec<u8> {
        let grid = self.grid();
        let mut out = Vec::with_capacity(HEADER_BYTES + self.table.len() * 32);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&model_code(self.model()).to_le_bytes());
        out.extend_from_slice(&grid.rows().to_le_bytes());
        out.extend_from_slice(&grid.cols().to_le_bytes());
        out.extend_from_slice(&grid_checksum(grid).to_le_bytes());
        for v in spec {
            out.extend_from_slice(&v.to_bits().to_le_bytes());
        }
        out.extend_from_slice(&[0; 8]); // the table checksum, written below
        for entry in &self.table {
            for v in entry {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        let sum = payload_checksum(&out[HEADER_BYTES..]);
        out[HEADER_BYTES - 8..HEADER_BYTES].copy_from_slice(&sum.to_le_bytes());
        out
    }

    /// Loads a table file for `grid`: refused unless the file is whole, undamaged, of this
    /// version, and built for exactly this grid.
    pub fn from_bytes(bytes: &[u8], grid: Arc<Grid2>) -> Result<Self, TableFileError> {
        let header = read_header(bytes)?;
        let sum = grid_checksum(&grid);
        if (header.rows, header.cols, header.grid_checksum) != (grid.rows(), grid.cols(), sum) {
            return Err(TableFileError::OtherGrid {
                file_rows: header.rows,
                file_cols: header.cols,
                file_sum: header.grid_checksum,
                rows: grid.rows(),
                cols: grid.cols(),
                sum,
            });
        }
        let cells = grid.len();
        let expected = HEADER_BYTES as u64 + cells as u64 * 32;
        if bytes.len() as u64 != expected {
            return Err(TableFileError::Length {
                expected,
                found: bytes.len() as u64,
            });
        }
        let payload = &bytes[HEADER_BYTES..];
        let mut stored = [0u8; 8];
        stored.copy_from_slice(&bytes[HEADER_BYTES - 8..HEADER_BYTES]);
        if payload_checksum(payload) != u64::from_le_bytes(stored) {
            return Err(TableFileError::Checksum);
        }
        let (rows, cols) = (i64::from(grid.rows()), i64::from(grid.cols()));
        let mut table = Vec::with_capacity(cells);
        for (i, chunk) in payload.chunks_exact(32).enumerate() {
            let (r, c) = (i as i64 / cols, i as i64 % cols);
            let mut entry = [0i32; 8];
            for (k, v) in entry.iter_mut().enumerate() {
                let at = 4 * k;
                *v = i32::from_le_bytes([chunk[at], chunk[at + 1], chunk[at + 2], chunk[at + 3]]);
                // A scan reaches |v| cells along DIRS[k]: all of them must be on the grid.
                let (dr, dc) = DIRS[k];
                let reach = i64::from(v.unsigned_abs());
                let (er, ec) = (r + reach * dr, c + reach * dc);
                if er < 0 || er >= rows || ec < 0 || ec >= cols {
                    return Err(TableFileError::OffGrid {
                        row: r as u32,
                        col: c as u32,
                    });
                }
            }
            table.push(entry);
        }
        Ok(Self::from_parts(grid, header.model, table))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::oracle::dijkstra_exact;
    use crate::{GridSearch, JpsPlus};
    use proptest::prelude::*;
    use skyplan_cspace::{Cell, GridFrame};

    fn grid(rows: u32, cols: u32, blocked: Vec<bool>) -> Arc<Grid2> {
        Arc::new(Grid2::new(rows, cols, blocked, GridFrame::default()).expect("size"))
    }

    fn city_block() -> Arc<Grid2> {
        let g = Grid2::from_ascii("........\n.##..#..\n.##..#..\n........\n...###..")
            .expect("ascii grid");
        Arc::new(g)
    }

    proptest! {
        /// A saved and reloaded table answers exactly like the table it was saved from (path
        /// for path) and like the exact oracle (cost), for both corner rules.
        #[test]
        fn reloaded_tables_answer_like_built_ones(
            rows in 1u32..20, cols in 1u32..20,
            cells in proptest::collection::vec(proptest::bool::weighted(0.3), 400),
            ends in proptest::collection::vec((0u32..20, 0u32..20, 0u32..20, 0u32..20), 1..5),
        ) {
            let g = grid(rows, cols, cells[..(rows * cols) as usize].to_vec());
            for model in [MoveModel::Octile, MoveModel::OctileCornerCutting] {
                let built = JpsPlusTable::build(Arc::clone(&g), model);
                let spec = [5.0, 5.0, 1.0];
                let bytes = built.to_bytes(spec);
                let header = read_header(&bytes).expect("header");
                prop_assert_eq!(header.spec, spec);
                prop_assert_eq!(header.model, model);
                let loaded = JpsPlusTable::from_bytes(&bytes, Arc::clone(&g)).expect("loads");
                let mut plus = JpsPlus::new(&g, model);
                let mut search = GridSearch::new();
                for &(a, b, c, d) in &ends {
                    let (s, t) = (Cell::new(a % rows, b % cols), Cell::new(c % rows, d % cols));
                    let got = loaded.search(&mut search, s, t);
                    prop_assert_eq!(&got, &plus.search(s, t));
                    let truth = dijkstra_exact(&g, s, t, model);
                    prop_assert_eq!(got.ok().map(|p| p.cost_cells()), truth.map(|c| c.to_f64()));
                }
            }
        }

        /// Any bytes, and any one-byte change or cut of a real file, load as an error or as a
        /// table — never a panic; a changed table byte is always caught.
        #[test]
        fn damaged_files_are_refused_without_panics(
            noise in proptest::collection::vec(any::<u8>(), 0..200),
            at in any::<usize>(), value in any::<u8>(), cut in any::<usize>(),
        ) {
            let g = city_block();
            let _ = JpsPlusTable::from_bytes(&noise, Arc::clone(&g));
            let good = JpsPlusTable::build(Arc::clone(&g), MoveModel::Octile).to_bytes([f64::NAN; 3]);
            let mut bad = good.clone();
            let i = at % bad.len();
            bad[i] ^= value | 1;
            let result = JpsPlusTable::from_bytes(&bad, Arc::clone(&g));
            if i >= HEADER_BYTES {
                prop_assert_eq!(result.err(), Some(TableFileError::Checksum));
            }
            let short = &good[..cut % good.len()];
            prop_assert!(JpsPlusTable::from_bytes(short, Arc::clone(&g)).is_err());
        }
    }

    #[test]
    fn each_refusal_says_why() {
        let g = city_block();
        let good = JpsPlusTable::build(Arc::clone(&g), MoveModel::Octile).to_bytes([f64::NAN; 3]);
        assert!(JpsPlusTable::from_bytes(&good, Arc::clone(&g)).is_ok());
        assert_eq!(
            JpsPlusTable::from_bytes(b"P5 not a table", Arc::clone(&g)).err(),
            Some(TableFileError::NotATable)
        );
        let mut v2 = good.clone();
        v2[16] = 2;
        assert_eq!(
            JpsPlusTable::from_bytes(&v2, Arc::clone(&g)).err(),
            Some(TableFileError::Version {
                found: 2,
                expected: 1
            })
        );
        // One more blocked cell: another grid.
        let mut cells = g.blocked_cells().to_vec();
        cells[0] = true;
        let other = grid(g.rows(), g.cols(), cells);
        let err = JpsPlusTable::from_bytes(&good, other).err();
        assert!(matches!(
            err,
            Some(TableFileError::OtherGrid {
                file_rows: 5,
                rows: 5,
                ..
            })
        ));
        assert!(err.is_some_and(|e| e.to_string().contains("another map")));
        // A jump past the border with a valid checksum (a crafted file) is still refused.
        let mut crafted = good.clone();
        crafted[HEADER_BYTES..HEADER_BYTES + 4].copy_from_slice(&1000i32.to_le_bytes());
        let sum = payload_checksum(&crafted[HEADER_BYTES..]);
        crafted[HEADER_BYTES - 8..HEADER_BYTES].copy_from_slice(&sum.to_le_bytes());
        assert_eq!(
            JpsPlusTable::from_bytes(&crafted, g).err(),
            Some(TableFileError::OffGrid { row: 0, col: 0 })
        );
    }
}
