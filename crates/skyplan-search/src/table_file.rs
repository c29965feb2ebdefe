//! The JPS+ table on disk: a versioned header, the checksum of the grid it was built for, the
//! table, and a checksum of the table.
//!
//! Layout (little-endian), version 3:
//!
//! | bytes | field |
//! |---|---|
//! | 16 | magic `SKYPLAN-JPSPLUS\n` |
//! | 4 | version (3) |
//! | 4 | corner rule: 1 = octile, no corner cutting; 2 = octile with corner cutting |
//! | 4, 4 | grid rows, columns |
//! | 8 | [`grid_checksum`] of the grid |
//! | 3 × 8 | the grid's altitude, margin and cell size in metres as the caller gave them
//! (`NaN` for a fixed grid): how to rebuild the grid |
//! | 4 | escape length in cells (1 ..= [`crate::ESCAPE_CELLS`]) |
//! | 4 | bytes per cell (8) |
//! | 8 | checksum of the corner rule, the escape length and the table bytes |
//! | 4 | landmarks `k` (0 ..= [`crate::landmarks::MAX_LANDMARKS`]) |
//! | 4 | landmark units per cell ([`crate::landmarks::UNITS_PER_CELL`]) |
//! | rows × cols × 8 | per cell, per direction ([`crate::jps`]'s order), the one-byte code of [`crate::JpsPlusTable`] |
//! | k × 8 | when `k > 0`: each landmark's row and column (u32) |
//! | rows × cols × k × 4 | when `k > 0`: per cell, each landmark's distance in fixed point ([`crate::Landmarks`]) |
//! | 8 | when `k > 0`: checksum of the landmark cells and distances |
//!
//! Version 2 was the same without the landmark fields and section; it is refused (rebuild).
//!
//! Tables are written and read as streams ([`JpsPlusTable::write_to`],
//! [`JpsPlusTable::read_from`]): the writer sends the table's own memory, the reader reads
//! straight into the new table's buffer in 1 MiB chunks and checks each chunk as it arrives, so
//! loading needs the table's memory once, not the file's bytes as well. The library opens no
//! files: callers hand it any [`std::io::Read`] / [`std::io::Write`].
//!
//! Loading checks all of it against the grid it is given, and every code against the grid's
//! borders, so a damaged or foreign file is an error, never a wrong path or a panic. Landmark
//! distances are checked to bound distances on the grid ([`crate::Landmarks::check`]), so they
//! can never make a path longer.

use crate::jps_plus::{ESCAPE_CELLS, Entry, decode};
use crate::landmarks::{Landmarks, MAX_LANDMARKS, UNITS_PER_CELL};
use crate::{JpsPlusTable, MoveModel};
use skyplan_cspace::Cell;
use skyplan_cspace::Grid2;
use std::io::{self, Read, Write};
use std::sync::Arc;

/// The first 16 bytes of a table file.
pub const MAGIC: &[u8; 16] = b"SKYPLAN-JPSPLUS\n";
/// The version this build writes and reads.
pub const VERSION: u32 = 3;
/// Bytes before the table.
pub const HEADER_BYTES: usize = 16 + 4 + 4 + 4 + 4 + 8 + 24 + 4 + 4 + 8 + 4 + 4;
/// Bytes per cell in the table.
const CELL_BYTES: u32 = 8;
/// Cells per streamed chunk (1 MiB).
const CHUNK_CELLS: usize = 1 << 17;

/// Why a table file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TableFileError {
    /// Not a JPS+ table file.
    #[error("not a skyplan JPS+ table (expected the header `SKYPLAN-JPSPLUS`)")]
    NotATable,
    /// Written by another version of the format.
    #[error(
        "JPS+ table format version {found}; this skyplan reads version {expected} (rebuild the table)"
    )]
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
    /// A code no table holds.
    #[error("JPS+ table entry at row {row}, column {col} holds an impossible code (damaged table)")]
    Code {
        /// Row of the entry.
        row: u32,
        /// Column of the entry.
        col: u32,
    },
    /// The landmark section does not bound distances on the grid.
    #[error("JPS+ table landmarks: {0}")]
    Landmarks(String),
    /// The reader or writer failed.
    #[error("JPS+ table input/output: {0}")]
    Io(String),
}

impl From<io::Error> for TableFileError {
    fn from(e: io::Error) -> Self {
        TableFileError::Io(e.to_string())
    }
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
    /// Escape length of the table, cells.
    pub escape_cells: u8,
    /// Checksum of the corner rule, the escape length and the table bytes.
    pub table_checksum: u64,
    /// Landmarks stored after the table.
    pub landmarks: u32,
}

impl TableHeader {
    /// Bytes of the whole file this header describes.
    pub fn file_bytes(&self) -> u64 {
        let cells = u64::from(self.rows) * u64::from(self.cols);
        (HEADER_BYTES as u64)
            .saturating_add(cells * u64::from(CELL_BYTES))
            .saturating_add(landmark_bytes(cells, self.landmarks))
    }
}

/// Bytes of a landmark section: `k` cells, `k` values per grid cell and a checksum (none
/// without landmarks).
fn landmark_bytes(cells: u64, k: u32) -> u64 {
    if k == 0 {
        0
    } else {
        (4 * u64::from(k))
            .saturating_mul(cells + 2)
            .saturating_add(8)
    }
}

/// The checksum of a landmark section, fed as it streams.
struct LandmarkSum(Hasher);

impl LandmarkSum {
    fn new(cells: &[Cell]) -> Self {
        let mut h = Hasher::new();
        h.word(cells.len() as u64);
        for c in cells {
            h.word(u64::from(c.row) << 32 | u64::from(c.col));
        }
        Self(h)
    }
    fn values(&mut self, values: &[u32]) {
        for pair in values.chunks(2) {
            let hi = pair.get(1).map_or(u64::MAX, |&v| u64::from(v));
            self.0.word(hi << 32 | u64::from(pair[0]));
        }
    }
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
pub(crate) struct Hasher(u64);

impl Hasher {
    pub(crate) fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    #[inline]
    pub(crate) fn word(&mut self, w: u64) {
        self.0 = (self.0 ^ w)
            .wrapping_mul(0x0000_0100_0000_01b3)
            .rotate_left(29);
    }
    pub(crate) fn finish(&self) -> u64 {
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

/// The table checksum, fed cell by cell while streaming.
struct TableSum {
    h: Hasher,
    cells: u64,
}

impl TableSum {
    fn new(model: MoveModel, escape: u8) -> Self {
        let mut h = Hasher::new();
        h.word(u64::from(model_code(model)) << 32 | u64::from(escape));
        Self { h, cells: 0 }
    }
    #[inline]
    fn cells(&mut self, cells: &[[u8; 8]]) {
        for &c in cells {
            self.h.word(u64::from_le_bytes(c));
        }
        self.cells += cells.len() as u64;
    }
    fn finish(mut self) -> u64 {
        self.h.word(self.cells);
        self.h.finish()
    }
}

fn model_code(model: MoveModel) -> u32 {
    match model {
        MoveModel::OctileCornerCutting => 2,
        MoveModel::Octile | MoveModel::FourConnected => 1,
    }
}

/// Reads the header at the start of a table file's bytes.
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
    let escape_cells = match u8::try_from(u32_at(64)) {
        Ok(e) if (1..=ESCAPE_CELLS).contains(&e) => e,
        _ => {
            return Err(TableFileError::Header(format!(
                "escape length {} cells (expected 1 to {ESCAPE_CELLS})",
                u32_at(64)
            )));
        }
    };
    let cell_bytes = u32_at(68);
    if cell_bytes != CELL_BYTES {
        return Err(TableFileError::Header(format!(
            "{cell_bytes} bytes per cell (expected {CELL_BYTES})"
        )));
    }
    let landmarks = u32_at(80);
    if landmarks as usize > MAX_LANDMARKS {
        return Err(TableFileError::Header(format!(
            "{landmarks} landmarks (expected at most {MAX_LANDMARKS})"
        )));
    }
    if u32_at(84) != UNITS_PER_CELL {
        return Err(TableFileError::Header(format!(
            "landmark units of 1/{} cell (expected 1/{UNITS_PER_CELL})",
            u32_at(84)
        )));
    }
    Ok(TableHeader {
        model,
        rows,
        cols,
        grid_checksum: u64_at(32),
        spec,
        escape_cells,
        table_checksum: u64_at(72),
        landmarks,
    })
}

/// Reads exactly the header from the start of a table stream (the table follows).
pub fn read_header_from(input: &mut impl Read) -> Result<TableHeader, TableFileError> {
    let mut bytes = [0u8; HEADER_BYTES];
    let got = read_full(input, &mut bytes)?;
    read_header(&bytes[..got])
}

/// Reads until `buf` is full or the input ends; the bytes read.
fn read_full(input: &mut impl Read, buf: &mut [u8]) -> Result<usize, TableFileError> {
    let mut got = 0;
    while got < buf.len() {
        match input.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
    Ok(got)
}

impl JpsPlusTable {
    fn header_bytes(
        &self,
        spec: [f64; 3],
        table_checksum: u64,
        landmarks: Option<&Landmarks>,
    ) -> [u8; HEADER_BYTES] {
        let grid = self.grid();
        let mut out = [0u8; HEADER_BYTES];
        let mut at = 0;
        let mut put = |b: &[u8]| {
            out[at..at + b.len()].copy_from_slice(b);
            at += b.len();
        };
        put(MAGIC);
        put(&VERSION.to_le_bytes());
        put(&model_code(self.model()).to_le_bytes());
        put(&grid.rows().to_le_bytes());
        put(&grid.cols().to_le_bytes());
        put(&grid_checksum(grid).to_le_bytes());
        for v in spec {
            put(&v.to_bits().to_le_bytes());
        }
        put(&u32::from(self.escape).to_le_bytes());
        put(&CELL_BYTES.to_le_bytes());
        put(&table_checksum.to_le_bytes());
        put(&(landmarks.map_or(0, |l| l.cells().len()) as u32).to_le_bytes());
        put(&UNITS_PER_CELL.to_le_bytes());
        out
    }

    /// Streams the landmark section of `landmarks` (if any) to `out`: the cells, the values,
    /// and their checksum, computed as they go.
    fn write_landmarks(landmarks: Option<&Landmarks>, out: &mut impl Write) -> io::Result<()> {
        let Some(l) = landmarks else {
            return Ok(());
        };
        for c in l.cells() {
            out.write_all(&c.row.to_le_bytes())?;
            out.write_all(&c.col.to_le_bytes())?;
        }
        let mut sum = LandmarkSum::new(l.cells());
        let mut bytes = Vec::with_capacity(4 * CHUNK_CELLS);
        for chunk in l.units().chunks(CHUNK_CELLS) {
            sum.values(chunk);
            bytes.clear();
            for v in chunk {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            out.write_all(&bytes)?;
        }
        out.write_all(&sum.0.finish().to_le_bytes())
    }

    fn checksum(&self) -> u64 {
        let mut sum = TableSum::new(self.model(), self.escape);
        sum.cells(&self.table);
        sum.finish()
    }

    /// Bytes of the table as a file ([`HEADER_BYTES`] + 8 per cell, and 4 per cell and
    /// landmark when it has landmarks).
    pub fn file_bytes(&self) -> u64 {
        let cells = self.table.len() as u64;
        let k = self.landmarks().map_or(0, |l| l.cells().len() as u32);
        HEADER_BYTES as u64 + cells * u64::from(CELL_BYTES) + landmark_bytes(cells, k)
    }

    /// Writes the table as a file (module [`crate::table_file`]) to `out`, straight from the
    /// table's memory (no copy); `spec` is stored for the reader: the grid's altitude, margin
    /// and cell size in metres (`NaN` for a fixed grid).
    pub fn write_to(&self, mut out: impl Write, spec: [f64; 3]) -> io::Result<()> {
        // Read once: another holder of the table may add landmarks while it is written.
        let landmarks = self.landmarks();
        out.write_all(&self.header_bytes(spec, self.checksum(), landmarks))?;
        for chunk in self.table.chunks(CHUNK_CELLS) {
            out.write_all(chunk.as_flattened())?;
        }
        Self::write_landmarks(landmarks, &mut out)?;
        out.flush()
    }

    /// The table as file bytes in memory ([`JpsPlusTable::write_to`] into a `Vec`).
    pub fn to_bytes(&self, spec: [f64; 3]) -> Vec<u8> {
        let mut out = Vec::with_capacity(usize::try_from(self.file_bytes()).unwrap_or(0));
        let landmarks = self.landmarks();
        out.extend_from_slice(&self.header_bytes(spec, self.checksum(), landmarks));
        out.extend_from_slice(self.table.as_flattened());
        // Writing to a vector cannot fail.
        let _ = Self::write_landmarks(landmarks, &mut out);
        out
    }

    /// Loads a table file's bytes for `grid` ([`JpsPlusTable::read_from`]).
    pub fn from_bytes(bytes: &[u8], grid: Arc<Grid2>) -> Result<Self, TableFileError> {
        Self::read_from(bytes, grid)
    }

    /// Reads a table file from `input` for `grid`: refused unless the file is whole,
    /// undamaged, of this version, and built for exactly this grid. The table is read straight
    /// into its own buffer, checked chunk by chunk (peak memory: the table).
    pub fn read_from(mut input: impl Read, grid: Arc<Grid2>) -> Result<Self, TableFileError> {
        let header = read_header_from(&mut input)?;
        Self::read_after_header(&header, input, grid)
    }

    /// [`JpsPlusTable::read_from`] for a caller that already read the header with
    /// [`read_header_from`] (to choose the grid from it): `input` is positioned at the table.
    pub fn read_after_header(
        header: &TableHeader,
        mut input: impl Read,
        grid: Arc<Grid2>,
    ) -> Result<Self, TableFileError> {
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
        let expected = header.file_bytes();
        let (rows, cols) = (i64::from(grid.rows()), i64::from(grid.cols()));
        let escape = header.escape_cells;
        let reach = reach_table(escape);
        let mut table = vec![[0u8; 8]; grid.len()];
        let mut table_sum = TableSum::new(header.model, escape);
        // The first bad entry, reported only if the checksum holds (damage is a checksum error).
        let mut first_bad: Option<TableFileError> = None;
        let mut done = 0usize;
        for chunk in table.chunks_mut(CHUNK_CELLS) {
            let bytes = chunk.as_flattened_mut();
            let got = read_full(&mut input, bytes)?;
            if got < bytes.len() {
                return Err(TableFileError::Length {
                    expected,
                    found: (HEADER_BYTES + done * CELL_BYTES as usize + got) as u64,
                });
            }
            table_sum.cells(chunk);
            if first_bad.is_none() {
                first_bad = check_codes(chunk, done, rows, cols, &reach);
            }
            done += chunk.len();
        }
        let landmarks = read_landmarks(header, &mut input, grid.len(), done)?;
        let extra = io::copy(&mut input, &mut io::sink())?;
        if extra > 0 {
            return Err(TableFileError::Length {
                expected,
                found: expected + extra,
            });
        }
        if table_sum.finish() != header.table_checksum {
            return Err(TableFileError::Checksum);
        }
        if let Some(e) = first_bad {
            return Err(e);
        }
        let me = Self::from_parts(Arc::clone(&grid), header.model, escape, table);
        if let Some((cells, units)) = landmarks {
            let l = Landmarks::from_parts(&grid, header.model, cells, units)
                .map_err(|e| TableFileError::Landmarks(e.to_string()))?;
            let _ = me.landmarks.set(l);
        }
        Ok(me)
    }
}

/// Reads the landmark section the header announces (after `cells` table cells): the landmark
/// cells and values, their checksum checked.
#[allow(clippy::type_complexity)]
fn read_landmarks(
    header: &TableHeader,
    input: &mut impl Read,
    cells: usize,
    table_cells: usize,
) -> Result<Option<(Vec<Cell>, Vec<u32>)>, TableFileError> {
    let k = header.landmarks as usize;
    if k == 0 {
        return Ok(None);
    }
    let expected = header.file_bytes();
    let mut at = (HEADER_BYTES + table_cells * CELL_BYTES as usize) as u64;
    let short = |at: u64| TableFileError::Length {
        expected,
        found: at,
    };
    let mut head = vec![0u8; 8 * k];
    let got = read_full(input, &mut head)?;
    if got < head.len() {
        return Err(short(at + got as u64));
    }
    at += head.len() as u64;
    let word = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let landmarks: Vec<Cell> = head
        .chunks(8)
        .map(|b| Cell::new(word(&b[..4]), word(&b[4..])))
        .collect();
    let mut sum = LandmarkSum::new(&landmarks);
    // Grown chunk by chunk as the values arrive: a header announcing more than the file holds
    // costs no memory.
    let values = cells * k;
    let mut units: Vec<u32> = Vec::new();
    let mut bytes = vec![0u8; 4 * CHUNK_CELLS];
    while units.len() < values {
        let n = CHUNK_CELLS.min(values - units.len());
        let want = &mut bytes[..4 * n];
        let got = read_full(input, want)?;
        if got < want.len() {
            return Err(short(at + got as u64));
        }
        at += got as u64;
        let from = units.len();
        units.extend(want.chunks(4).map(word));
        sum.values(&units[from..]);
    }
    let mut tail = [0u8; 8];
    let got = read_full(input, &mut tail)?;
    if got < 8 {
        return Err(short(at + got as u64));
    }
    if u64::from_le_bytes(tail) != sum.0.finish() {
        return Err(TableFileError::Checksum);
    }
    Ok(Some((landmarks, units)))
}

/// Reach of an impossible code: more than any grid has room for.
const IMPOSSIBLE: i64 = i64::MAX;

/// How many cells each code lets a scan examine, for a table of escape length `escape`
/// ([`IMPOSSIBLE`] for a code no table holds).
fn reach_table(escape: u8) -> [i64; 256] {
    let mut reach = [IMPOSSIBLE; 256];
    for (code, slot) in reach.iter_mut().enumerate() {
        *slot = match decode(code as u8, escape) {
            Some(Entry::Wall(w) | Entry::Jump(w)) => i64::from(w),
            Some(Entry::Escape) => i64::from(escape),
            None => IMPOSSIBLE,
        };
    }
    reach
}

/// The first entry of `cells` (cell `first` on) whose code is impossible or whose scan
/// reaches past the grid's border.
fn check_codes(
    cells: &[[u8; 8]],
    first: usize,
    rows: i64,
    cols: i64,
    reach: &[i64; 256],
) -> Option<TableFileError> {
    let (mut r, mut c) = (first as i64 / cols, first as i64 % cols);
    for entry in cells {
        // Room to the border in each direction of DIRS (straight, then diagonal).
        let (down, up, right, left) = (rows - 1 - r, r, cols - 1 - c, c);
        let room = [
            down,
            up,
            right,
            left,
            down.min(right),
            down.min(left),
            up.min(right),
            up.min(left),
        ];
        let mut bad = false;
        for (k, &code) in entry.iter().enumerate() {
            bad |= reach[usize::from(code)] > room[k];
        }
        if bad {
            let (row, col) = (r as u32, c as u32);
            return Some(
                if entry
                    .iter()
                    .any(|&code| reach[usize::from(code)] == IMPOSSIBLE)
                {
                    TableFileError::Code { row, col }
                } else {
                    TableFileError::OffGrid { row, col }
                },
            );
        }
        c += 1;
        if c == cols {
            c = 0;
            r += 1;
        }
    }
    None
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

    /// A reader that hands out at most `piece` bytes per call.
    struct Trickle<'a> {
        bytes: &'a [u8],
        piece: usize,
    }

    impl std::io::Read for Trickle<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = self.piece.min(buf.len()).min(self.bytes.len());
            buf[..n].copy_from_slice(&self.bytes[..n]);
            self.bytes = &self.bytes[n..];
            Ok(n)
        }
    }

    /// A reader that fails after `ok` bytes.
    struct Failing {
        bytes: Vec<u8>,
        ok: usize,
    }

    impl std::io::Read for Failing {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.ok == 0 {
                return Err(std::io::Error::other("disk on fire"));
            }
            let n = self.ok.min(buf.len()).min(self.bytes.len());
            buf[..n].copy_from_slice(&self.bytes[..n]);
            self.bytes.drain(..n);
            self.ok -= n;
            Ok(n)
        }
    }

    /// Re-seals a crafted file: the table checksum recomputed over its (changed) bytes.
    fn reseal(file: &mut [u8]) {
        let header = read_header(file).expect("header");
        let mut sum = TableSum::new(header.model, header.escape_cells);
        let n = (header.rows * header.cols) as usize;
        let cells: Vec<[u8; 8]> = file[HEADER_BYTES..HEADER_BYTES + 8 * n]
            .chunks_exact(8)
            .map(|c| c.try_into().expect("8 bytes"))
            .collect();
        sum.cells(&cells);
        file[72..80].copy_from_slice(&sum.finish().to_le_bytes());
        if header.landmarks > 0 {
            // The landmark section's checksum, over its (changed) cells and values.
            let at = HEADER_BYTES + 8 * n;
            let k = header.landmarks as usize;
            let word = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            let marks: Vec<Cell> = file[at..at + 8 * k]
                .chunks(8)
                .map(|b| Cell::new(word(&b[..4]), word(&b[4..])))
                .collect();
            let values: Vec<u32> = file[at + 8 * k..at + 8 * k + 4 * n * k]
                .chunks(4)
                .map(word)
                .collect();
            let mut sum = LandmarkSum::new(&marks);
            for chunk in values.chunks(CHUNK_CELLS) {
                sum.values(chunk);
            }
            let end = at + 8 * k + 4 * n * k;
            file[end..end + 8].copy_from_slice(&sum.0.finish().to_le_bytes());
        }
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
            escape in 1u8..5, piece in 1usize..100,
        ) {
            let g = grid(rows, cols, cells[..(rows * cols) as usize].to_vec());
            for model in [MoveModel::Octile, MoveModel::OctileCornerCutting] {
                let built = JpsPlusTable::build_with_escape(Arc::clone(&g), model, escape);
                if escape % 2 == 0 {
                    built.add_landmarks(usize::from(escape));
                }
                let spec = [5.0, 5.0, 1.0];
                let bytes = built.to_bytes(spec);
                let mut streamed = Vec::new();
                built.write_to(&mut streamed, spec).expect("writes to memory");
                prop_assert_eq!(&streamed, &bytes);
                prop_assert_eq!(bytes.len() as u64, built.file_bytes());
                let header = read_header(&bytes).expect("header");
                prop_assert_eq!(header.spec, spec);
                prop_assert_eq!(header.model, model);
                prop_assert_eq!(header.escape_cells, escape);
                // Read in pieces of any size: the same table.
                let loaded = JpsPlusTable::read_from(Trickle { bytes: &bytes, piece }, Arc::clone(&g))
                    .expect("loads");
                prop_assert_eq!(&loaded.table, &built.table);
                prop_assert_eq!(loaded.landmarks(), built.landmarks());
                let mut plus = JpsPlus::new(&g, model);
                let mut search = GridSearch::new();
                for &(a, b, c, d) in &ends {
                    let (s, t) = (Cell::new(a % rows, b % cols), Cell::new(c % rows, d % cols));
                    let got = loaded.search(&mut search, s, t);
                    prop_assert_eq!(&got, &built.search(&mut GridSearch::new(), s, t));
                    if built.landmarks().is_none() {
                        prop_assert_eq!(&got, &plus.search(s, t));
                    }
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
            let table = JpsPlusTable::build(Arc::clone(&g), MoveModel::Octile);
            table.add_landmarks(2);
            let good = table.to_bytes([f64::NAN; 3]);
            let mut bad = good.clone();
            let i = at % bad.len();
            bad[i] ^= value | 1;
            let result = JpsPlusTable::from_bytes(&bad, Arc::clone(&g));
            if i >= HEADER_BYTES || (64..68).contains(&i) {
                // The table, or the escape length its codes are read with.
                prop_assert!(matches!(
                    result.err(),
                    Some(TableFileError::Checksum | TableFileError::Header(_))
                ));
            }
            if i >= HEADER_BYTES {
                // A table byte, a landmark cell or distance, or a checksum.
                prop_assert_eq!(
                    JpsPlusTable::from_bytes(&bad, Arc::clone(&g)).err(),
                    Some(TableFileError::Checksum)
                );
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
        // Version 1 (32 bytes per cell) and 2 (no landmarks) files are refused by version.
        for old in [1, 2] {
            let mut v = good.clone();
            v[16] = old;
            assert_eq!(
                JpsPlusTable::from_bytes(&v, Arc::clone(&g)).err(),
                Some(TableFileError::Version {
                    found: u32::from(old),
                    expected: 3
                })
            );
        }
        let mut escape = good.clone();
        escape[64] = 200;
        assert!(matches!(
            JpsPlusTable::from_bytes(&escape, Arc::clone(&g)).err(),
            Some(TableFileError::Header(m)) if m.contains("escape length 200")
        ));
        let mut longer = good.clone();
        longer.extend_from_slice(b"tail");
        assert_eq!(
            JpsPlusTable::from_bytes(&longer, Arc::clone(&g)).err(),
            Some(TableFileError::Length {
                expected: good.len() as u64,
                found: good.len() as u64 + 4
            })
        );
        assert_eq!(
            JpsPlusTable::from_bytes(&good[..good.len() - 3], Arc::clone(&g)).err(),
            Some(TableFileError::Length {
                expected: good.len() as u64,
                found: good.len() as u64 - 3
            })
        );
        let failing = Failing {
            bytes: good.clone(),
            ok: HEADER_BYTES + 5,
        };
        assert!(matches!(
            JpsPlusTable::read_from(failing, Arc::clone(&g)).err(),
            Some(TableFileError::Io(m)) if m.contains("disk on fire")
        ));
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
        // (Cell (0, 0), direction south: an escape of 126 cells on a 5-row grid.)
        let mut crafted = good.clone();
        crafted[HEADER_BYTES] = crate::jps_plus::ESCAPE_TO_WALL;
        reseal(&mut crafted);
        assert_eq!(
            JpsPlusTable::from_bytes(&crafted, Arc::clone(&g)).err(),
            Some(TableFileError::OffGrid { row: 0, col: 0 })
        );
        // An impossible code (a jump longer than the escape length) at cell (0, 1).
        let mut crafted = good.clone();
        crafted[HEADER_BYTES + 8 + 2] = 254;
        reseal(&mut crafted);
        assert_eq!(
            JpsPlusTable::from_bytes(&crafted, Arc::clone(&g)).err(),
            Some(TableFileError::Code { row: 0, col: 1 })
        );
    }

    #[test]
    fn landmark_sections_are_checked() {
        let g = city_block();
        let table = JpsPlusTable::build(Arc::clone(&g), MoveModel::Octile);
        table.add_landmarks(3);
        let good = table.to_bytes([f64::NAN; 3]);
        assert_eq!(read_header(&good).expect("header").landmarks, 3);
        let loaded = JpsPlusTable::from_bytes(&good, Arc::clone(&g)).expect("loads");
        assert_eq!(loaded.landmarks(), table.landmarks());
        let values = HEADER_BYTES + 8 * g.len() + 8 * 3;
        // A changed distance is damage (checksum) ...
        let mut bad = good.clone();
        bad[values + 4 * 5] ^= 0x40;
        assert_eq!(
            JpsPlusTable::from_bytes(&bad, Arc::clone(&g)).err(),
            Some(TableFileError::Checksum)
        );
        // ... and with the checksum re-sealed, a distance that no longer bounds distances
        // (cell (0, 1) raised by 3 cells for landmark 0) is refused by the check.
        let mut crafted = good.clone();
        let at = values + 4 * 3; // cell 1, landmark 0
        let raised = u32::from_le_bytes(crafted[at..at + 4].try_into().expect("4 bytes"))
            + 3 * UNITS_PER_CELL;
        crafted[at..at + 4].copy_from_slice(&raised.to_le_bytes());
        reseal(&mut crafted);
        let e = JpsPlusTable::from_bytes(&crafted, Arc::clone(&g)).expect_err("refused");
        assert!(
            matches!(&e, TableFileError::Landmarks(m) if m.contains("landmark 0 at row 0")),
            "{e}"
        );
        // A landmark on a blocked cell (row 1, column 1), re-sealed.
        let mut crafted = good.clone();
        let at = HEADER_BYTES + 8 * g.len();
        crafted[at..at + 8].copy_from_slice(&[1, 0, 0, 0, 1, 0, 0, 0]);
        reseal(&mut crafted);
        let e = JpsPlusTable::from_bytes(&crafted, Arc::clone(&g)).expect_err("refused");
        assert!(e.to_string().contains("not a free cell"), "{e}");
        // Too many landmarks in the header.
        let mut many = good.clone();
        many[80] = 200;
        assert!(matches!(
            JpsPlusTable::from_bytes(&many, Arc::clone(&g)).err(),
            Some(TableFileError::Header(m)) if m.contains("200 landmarks")
        ));
        // Cut inside the landmark section.
        assert!(matches!(
            JpsPlusTable::from_bytes(&good[..values + 10], g).err(),
            Some(TableFileError::Length { found, .. }) if found == values as u64 + 10
        ));
    }
}
