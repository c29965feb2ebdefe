//! The contraction hierarchy on disk, like the JPS+ table ([`crate::table_file`]): a versioned
//! header, the checksum of the grid it was built for, the hierarchy's arrays, and a checksum of
//! them.
//!
//! Layout (little-endian), version 1:
//!
//! | bytes | field |
//! |---|---|
//! | 16 | magic `SKYPLAN-CH-FILE\n` |
//! | 4 | version (1) |
//! | 4 | move model: 1 = octile, 2 = octile with corner cutting, 3 = 4-connected |
//! | 4, 4 | grid rows, columns |
//! | 8 | [`grid_checksum`] of the grid |
//! | 4, 4, 4 | nodes `n` (free cells), arcs `m` (upward edges), edges `e` (every edge made) |
//! | 8 | checksum of the body |
//! | body | cell of every rank (`n` × u32), first arc of every rank (`n + 1` × u32), arc heads (`m` × u32), arc costs (`m` × u64), arc edge ids (`m` × u32), edges (`e` × 5 × u32: ends, middle, halves) |
//!
//! Loading ([`ContractionHierarchy::read_from`]) checks the header against the grid it is
//! given, the checksum, and then the structure itself: ranks are a permutation of the free
//! cells, arcs are in range and join the edge they name, every original edge joins two
//! neighbouring free cells under the move model at the move's cost, every shortcut is made of
//! two earlier edges through its middle at their summed cost. A damaged or foreign file is a
//! [`ChFileError`] naming what is wrong, never a wrong path or a panic. The library opens no
//! files: callers hand it any [`Read`] / [`Write`].

use crate::contraction::{DIAGONAL, Edge, NONE, STRAIGHT, UpArc};
use crate::table_file::{Hasher, grid_checksum};
use crate::{ContractionHierarchy, MoveModel};
use skyplan_cspace::{Cell, Grid2};
use std::io::{self, Read, Write};
use std::sync::Arc;

/// The first 16 bytes of a hierarchy file.
pub const MAGIC: &[u8; 16] = b"SKYPLAN-CH-FILE\n";
/// The version this build writes and reads.
pub const VERSION: u32 = 1;
/// Bytes before the body.
pub const HEADER_BYTES: usize = 16 + 4 + 4 + 4 + 4 + 8 + 4 + 4 + 4 + 8;

/// Why a hierarchy file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChFileError {
    /// Not a hierarchy file.
    #[error("not a skyplan contraction hierarchy (expected the header `SKYPLAN-CH-FILE`)")]
    NotAHierarchy,
    /// Written by another version of the format.
    #[error(
        "contraction hierarchy format version {found}; this skyplan reads version {expected} (rebuild it)"
    )]
    Version {
        /// The file's version.
        found: u32,
        /// The version this build reads.
        expected: u32,
    },
    /// The file is shorter or longer than its header says.
    #[error(
        "contraction hierarchy is {found} bytes; its header says {expected} (truncated or damaged)"
    )]
    Length {
        /// Bytes expected from the header.
        expected: u64,
        /// Bytes found (at least; reading stops one byte past the expected length).
        found: u64,
    },
    /// The body does not match its checksum.
    #[error("contraction hierarchy is damaged (its checksum does not match its contents)")]
    Checksum,
    /// Built for another grid or move model.
    #[error("contraction hierarchy was built for {0}")]
    OtherGrid(GridMismatch),
    /// The structure is inconsistent although the checksum matches.
    #[error("contraction hierarchy is damaged: {0}")]
    Damaged(String),
    /// The reader or writer failed.
    #[error("contraction hierarchy input/output: {0}")]
    Io(String),
}

impl From<io::Error> for ChFileError {
    fn from(e: io::Error) -> Self {
        ChFileError::Io(e.to_string())
    }
}

/// What a preprocessing file was built for, against the grid and move model given: the
/// `OtherGrid` of [`ChFileError`] and of the first-move table's file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GridMismatch {
    /// Rows in the file.
    pub file_rows: u32,
    /// Columns in the file.
    pub file_cols: u32,
    /// Grid checksum in the file.
    pub file_sum: u64,
    /// The file's move model, in words.
    pub file_model: &'static str,
    /// Rows of the grid given.
    pub rows: u32,
    /// Columns of the grid given.
    pub cols: u32,
    /// Checksum of the grid given.
    pub sum: u64,
    /// The move model asked for, in words.
    pub model: &'static str,
}

impl std::fmt::Display for GridMismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "a {} × {} grid with checksum {:016x} ({}); this grid is {} × {} with checksum {:016x} ({}) \
             (another map, altitude, margin, cell size or move model)",
            self.file_rows,
            self.file_cols,
            self.file_sum,
            self.file_model,
            self.rows,
            self.cols,
            self.sum,
            self.model
        )
    }
}

/// Why the common start of a preprocessing file — magic (16 bytes), version, move model, grid
/// rows and columns (4 bytes each), grid checksum (8) — does not fit, before each format's own
/// fields.
pub(crate) enum HeadError {
    /// Another magic: not this kind of file.
    Foreign,
    /// Shorter than its header.
    Short { expected: u64, found: u64 },
    /// Another version.
    Version(u32),
    /// Another grid or move model.
    OtherGrid(GridMismatch),
    /// The reader failed.
    Io(io::Error),
}

/// Reads the `N`-byte header of a preprocessing file with `magic` and `version` built for `grid`
/// under `model`, checking the common start ([`HeadError`]).
pub(crate) fn read_head<const N: usize>(
    input: &mut impl Read,
    magic: &[u8; 16],
    version: u32,
    grid: &Grid2,
    model: MoveModel,
) -> Result<[u8; N], HeadError> {
    let mut header = [0u8; N];
    let got = read_up_to(input, &mut header).map_err(HeadError::Io)?;
    if got < magic.len() || header[..16] != magic[..] {
        return Err(HeadError::Foreign);
    }
    if got < N {
        return Err(HeadError::Short {
            expected: N as u64,
            found: got as u64,
        });
    }
    if u32_at(&header, 16) != version {
        return Err(HeadError::Version(u32_at(&header, 16)));
    }
    let (file_model, rows, cols) = (
        u32_at(&header, 20),
        u32_at(&header, 24),
        u32_at(&header, 28),
    );
    let (file_sum, sum) = (u64_at(&header, 32), grid_checksum(grid));
    if file_model != model_code(model)
        || rows != grid.rows()
        || cols != grid.cols()
        || file_sum != sum
    {
        return Err(HeadError::OtherGrid(GridMismatch {
            file_rows: rows,
            file_cols: cols,
            file_sum,
            file_model: model_words(file_model),
            rows: grid.rows(),
            cols: grid.cols(),
            sum,
            model: model_words(model_code(model)),
        }));
    }
    Ok(header)
}

/// The little-endian `u32` at byte `at`.
pub(crate) fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// The little-endian `u64` at byte `at`.
pub(crate) fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from(u32_at(b, at)) | u64::from(u32_at(b, at + 4)) << 32
}

/// The common start of a preprocessing file: magic, version, move model, grid size and checksum.
pub(crate) fn write_head(
    out: &mut Vec<u8>,
    magic: &[u8; 16],
    version: u32,
    grid: &Grid2,
    model: MoveModel,
) {
    out.extend_from_slice(magic);
    for w in [version, model_code(model), grid.rows(), grid.cols()] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&grid_checksum(grid).to_le_bytes());
}

pub(crate) fn model_code(model: MoveModel) -> u32 {
    match model {
        MoveModel::Octile => 1,
        MoveModel::OctileCornerCutting => 2,
        MoveModel::FourConnected => 3,
    }
}

pub(crate) fn model_words(code: u32) -> &'static str {
    match code {
        1 => "octile",
        2 => "octile with corner cutting",
        3 => "4-connected",
        _ => "an unknown move model",
    }
}

pub(crate) fn body_sum(body: &[u8]) -> u64 {
    let mut h = Hasher::new();
    h.word(body.len() as u64);
    let mut chunks = body.chunks_exact(8);
    for c in &mut chunks {
        let mut w = [0u8; 8];
        w.copy_from_slice(c);
        h.word(u64::from_le_bytes(w));
    }
    let mut tail = [0u8; 8];
    tail[..chunks.remainder().len()].copy_from_slice(chunks.remainder());
    h.word(u64::from_le_bytes(tail));
    h.finish()
}

impl ContractionHierarchy {
    /// Bytes of its file.
    pub fn file_bytes(&self) -> u64 {
        let (n, m, e) = (
            self.cell_of_rank.len() as u64,
            self.arcs.len() as u64,
            self.edges.len() as u64,
        );
        HEADER_BYTES as u64 + 4 * n + 4 * (n + 1) + 16 * m + 20 * e
    }

    /// Writes the hierarchy as a file (see the module docs) to `out`.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{ChQuery, ContractionHierarchy, MoveModel};
    /// let grid = Arc::new(Grid2::from_ascii("......\n.####.\n......")?);
    /// let built = ContractionHierarchy::build(Arc::clone(&grid), MoveModel::Octile)?;
    /// let mut bytes = Vec::new();
    /// built.write_to(&mut bytes)?;
    /// assert_eq!(bytes.len() as u64, built.file_bytes());
    /// let loaded = ContractionHierarchy::read_from(&bytes[..], grid, MoveModel::Octile)?;
    /// let mut q = ChQuery::default();
    /// let (a, b) = (Cell::new(0, 0), Cell::new(2, 5));
    /// assert_eq!(loaded.search(&mut q, a, b)?.cells, built.search(&mut q, a, b)?.cells);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn write_to(&self, out: impl Write) -> Result<(), ChFileError> {
        self.write_with(out, MAGIC)
    }

    /// [`Self::write_to`] with another magic (the subgoal graph's file holds its hierarchy).
    pub(crate) fn write_with(
        &self,
        mut out: impl Write,
        magic: &[u8; 16],
    ) -> Result<(), ChFileError> {
        let body = self.body();
        let mut header = Vec::with_capacity(HEADER_BYTES);
        write_head(&mut header, magic, VERSION, &self.grid, self.model);
        for w in [self.cell_of_rank.len(), self.arcs.len(), self.edges.len()] {
            header.extend_from_slice(&(w as u32).to_le_bytes());
        }
        header.extend_from_slice(&body_sum(&body).to_le_bytes());
        out.write_all(&header)?;
        out.write_all(&body)?;
        out.flush()?;
        Ok(())
    }

    fn body(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(self.file_bytes() as usize - HEADER_BYTES);
        let u32s = |b: &mut Vec<u8>, v: &[u32]| {
            for x in v {
                b.extend_from_slice(&x.to_le_bytes());
            }
        };
        u32s(&mut b, &self.cell_of_rank);
        u32s(&mut b, &self.first_out);
        for a in &self.arcs {
            b.extend_from_slice(&a.head.to_le_bytes());
        }
        for a in &self.arcs {
            b.extend_from_slice(&a.cost.to_le_bytes());
        }
        for a in &self.arcs {
            b.extend_from_slice(&a.edge.to_le_bytes());
        }
        for e in &self.edges {
            u32s(&mut b, &[e.a, e.b, e.mid, e.first, e.second]);
        }
        b
    }

    /// Reads a hierarchy file written by [`ContractionHierarchy::write_to`] for `grid` under
    /// `model`; refused with a [`ChFileError`] if it is not one, another version, truncated,
    /// damaged, or built for another grid or move model.
    pub fn read_from(
        input: impl Read,
        grid: Arc<Grid2>,
        model: MoveModel,
    ) -> Result<Self, ChFileError> {
        let free = grid.len() - grid.blocked_count();
        let nodes = Nodes {
            count: free,
            what: "free cells",
            is_node: &|i| !grid.blocked_cells()[i],
            original: &|p, q| {
                let (dr, dc) = (
                    i64::from(q.row) - i64::from(p.row),
                    i64::from(q.col) - i64::from(p.col),
                );
                let diagonal = dr != 0 && dc != 0;
                let legal = dr.abs() <= 1
                    && dc.abs() <= 1
                    && (!diagonal || (model.has_diagonals() && model.corner_ok(&grid, p, dr, dc)));
                legal.then_some(if diagonal { DIAGONAL } else { STRAIGHT })
            },
            neighbours: "neighbours under the move model",
        };
        let parts = Self::read_parts(input, &grid, model, MAGIC, &nodes)?;
        Ok(parts.into_hierarchy(grid, model))
    }

    /// Reads a hierarchy file with `magic` for `grid` under `model` whose nodes are `nodes`'.
    pub(crate) fn read_parts(
        mut input: impl Read,
        grid: &Grid2,
        model: MoveModel,
        magic: &[u8; 16],
        nodes: &Nodes<'_>,
    ) -> Result<Parts, ChFileError> {
        let header = read_head::<HEADER_BYTES>(&mut input, magic, VERSION, grid, model).map_err(
            |e| match e {
                HeadError::Foreign => ChFileError::NotAHierarchy,
                HeadError::Short { expected, found } => ChFileError::Length { expected, found },
                HeadError::Version(found) => ChFileError::Version {
                    found,
                    expected: VERSION,
                },
                HeadError::OtherGrid(m) => ChFileError::OtherGrid(m),
                HeadError::Io(e) => e.into(),
            },
        )?;
        let u32_at = |at: usize| u32_at(&header, at);
        let u64_at = |at: usize| u64_at(&header, at);
        let (n, m, e) = (
            u64::from(u32_at(40)),
            u64::from(u32_at(44)),
            u64::from(u32_at(48)),
        );
        let body_checksum = u64_at(52);
        let expected = 4 * n + 4 * (n + 1) + 16 * m + 20 * e;
        // Read at most one byte past the expected length: memory grows only with what is there.
        let mut body = Vec::new();
        (&mut input).take(expected + 1).read_to_end(&mut body)?;
        if body.len() as u64 != expected {
            return Err(ChFileError::Length {
                expected: HEADER_BYTES as u64 + expected,
                found: HEADER_BYTES as u64 + body.len() as u64,
            });
        }
        if body_sum(&body) != body_checksum {
            return Err(ChFileError::Checksum);
        }
        let (n, m, e) = (n as usize, m as usize, e as usize);
        let mut at = 0usize;
        let mut u32s = |count: usize| -> Vec<u32> {
            let v = body[at..at + 4 * count]
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            at += 4 * count;
            v
        };
        let cell_of_rank = u32s(n);
        let first_out = u32s(n + 1);
        let head = u32s(m);
        let cost_words = u32s(2 * m);
        let edge_id = u32s(m);
        let edge_words = u32s(5 * e);
        let cost: Vec<u64> = (cost_words.chunks_exact(2))
            .map(|c| u64::from(c[0]) | u64::from(c[1]) << 32)
            .collect();
        let edges: Vec<Edge> = (edge_words.chunks_exact(5))
            .map(|c| Edge {
                a: c[0],
                b: c[1],
                mid: c[2],
                first: c[3],
                second: c[4],
            })
            .collect();
        let rank_of_cell = check(
            grid,
            nodes,
            &cell_of_rank,
            &first_out,
            &head,
            &cost,
            &edge_id,
            &edges,
        )
        .map_err(ChFileError::Damaged)?;
        Ok(Parts {
            rank_of_cell,
            cell_of_rank,
            first_out,
            arcs: (head.iter().zip(&cost).zip(&edge_id))
                .map(|((&head, &cost), &edge)| UpArc { cost, head, edge })
                .collect(),
            edges,
        })
    }
}

/// What a hierarchy's nodes are, for the checks of its file: how many, which grid cells
/// (`is_node` of a cell index), and the cost of an original edge between two nodes' cells
/// (`None` when the two are not joined; `neighbours` says what they must be, in words).
pub(crate) struct Nodes<'a> {
    pub(crate) count: usize,
    pub(crate) what: &'static str,
    pub(crate) is_node: &'a dyn Fn(usize) -> bool,
    pub(crate) original: &'a dyn Fn(Cell, Cell) -> Option<u64>,
    pub(crate) neighbours: &'static str,
}

/// A hierarchy's arrays read from a file and checked.
pub(crate) struct Parts {
    rank_of_cell: Vec<u32>,
    cell_of_rank: Vec<u32>,
    first_out: Vec<u32>,
    arcs: Vec<UpArc>,
    edges: Vec<Edge>,
}

impl Parts {
    pub(crate) fn into_hierarchy(self, grid: Arc<Grid2>, model: MoveModel) -> ContractionHierarchy {
        ContractionHierarchy {
            grid,
            model,
            rank_of_cell: self.rank_of_cell,
            cell_of_rank: self.cell_of_rank,
            first_out: self.first_out,
            arcs: self.arcs,
            edges: self.edges,
            id: crate::contraction::next_id(),
        }
    }
}

/// Reads until `buf` is full or the input ends; the bytes read.
pub(crate) fn read_up_to(input: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match input.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// The structure's consistency (module docs); the rank of every cell, or what is wrong.
#[allow(clippy::too_many_arguments)]
fn check(
    grid: &Grid2,
    nodes: &Nodes<'_>,
    cell_of_rank: &[u32],
    first_out: &[u32],
    head: &[u32],
    cost: &[u64],
    edge_id: &[u32],
    edges: &[Edge],
) -> Result<Vec<u32>, String> {
    let n = cell_of_rank.len();
    if n != nodes.count {
        return Err(format!(
            "{n} nodes for a grid of {} {}",
            nodes.count, nodes.what
        ));
    }
    let mut rank_of_cell = vec![NONE; grid.len()];
    for (r, &c) in cell_of_rank.iter().enumerate() {
        let i = c as usize;
        if i >= grid.len() || !(nodes.is_node)(i) || rank_of_cell[i] != NONE {
            return Err(format!(
                "rank {r} names cell {c}: off the grid, not one of the {}, or named twice",
                nodes.what
            ));
        }
        rank_of_cell[i] = r as u32;
    }
    if first_out.first() != Some(&0)
        || first_out.windows(2).any(|w| w[0] > w[1])
        || first_out.last().map(|&x| x as usize) != Some(head.len())
    {
        return Err("the arcs' offsets are not increasing from 0 to the arc count".into());
    }
    // Every edge's cost, from its two ends (original moves) or its halves (shortcuts).
    // A shortest path moves through each free cell at most once (the subgoal graph's nodes
    // are fewer than the cells its edges cross).
    let free = (grid.len() - grid.blocked_count()) as u64;
    let max_cost = free.saturating_mul(DIAGONAL);
    let cols = u64::from(grid.cols());
    let cell = |rank: u32| {
        let i = u64::from(cell_of_rank[rank as usize]);
        Cell::new((i / cols) as u32, (i % cols) as u32)
    };
    let joins = |e: &Edge, x: u32, y: u32| (e.a == x && e.b == y) || (e.a == y && e.b == x);
    let mut edge_cost = Vec::with_capacity(edges.len());
    for (k, e) in edges.iter().enumerate() {
        if e.a as usize >= n || e.b as usize >= n || e.a == e.b {
            return Err(format!("edge {k} does not join two nodes"));
        }
        let c = if e.mid == NONE {
            let Some(c) = (nodes.original)(cell(e.a), cell(e.b)) else {
                return Err(format!(
                    "edge {k} joins cells that are not {}",
                    nodes.neighbours
                ));
            };
            c
        } else {
            let (f, s) = (e.first as usize, e.second as usize);
            if e.mid as usize >= n || f >= k || s >= k {
                return Err(format!("shortcut {k} is not made of two earlier edges"));
            }
            if !joins(&edges[f], e.a, e.mid) || !joins(&edges[s], e.mid, e.b) {
                return Err(format!("shortcut {k}'s halves do not meet at its middle"));
            }
            let c: u64 = edge_cost[f] + edge_cost[s];
            if c > max_cost {
                return Err(format!("shortcut {k} costs more than any path of the grid"));
            }
            c
        };
        edge_cost.push(c);
    }
    for u in 0..n {
        for k in first_out[u] as usize..first_out[u + 1] as usize {
            let (v, id) = (head[k], edge_id[k] as usize);
            if v as usize >= n || id >= edges.len() || !joins(&edges[id], u as u32, v) {
                return Err(format!("arc {k} does not follow the edge it names"));
            }
            if cost[k] != edge_cost[id] {
                return Err(format!("arc {k}'s cost is not its edge's"));
            }
        }
    }
    Ok(rank_of_cell)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ChQuery;

    fn grid() -> Arc<Grid2> {
        Arc::new(
            Grid2::from_ascii("..........\n.###..##..\n...#......\n.#...####.\n..........\n")
                .unwrap(),
        )
    }

    fn saved(model: MoveModel) -> (ContractionHierarchy, Vec<u8>) {
        let ch = ContractionHierarchy::build(grid(), model).unwrap();
        let mut bytes = Vec::new();
        ch.write_to(&mut bytes).unwrap();
        (ch, bytes)
    }

    /// The bytes written for a fixed grid are those of the build that first wrote this version
    /// (FNV-1a values taken from it), so files saved then still load, and the in-memory layout
    /// of the arcs never leaks into the file.
    #[test]
    fn files_are_byte_for_byte_those_of_the_first_version_1_writer() {
        let fnv = |b: &[u8]| {
            b.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &x| {
                (h ^ u64::from(x)).wrapping_mul(0x100_0000_01b3)
            })
        };
        let grid = Arc::new(
            Grid2::from_ascii("........\n.##..#..\n.#...#..\n...###..\n........").unwrap(),
        );
        for (model, len, hash) in [
            (MoveModel::Octile, 3164, 0x1768_dd02_6d18_8d30_u64),
            (MoveModel::FourConnected, 2588, 0x9fed_81d3_d13d_59f5),
        ] {
            let ch = ContractionHierarchy::build(Arc::clone(&grid), model).unwrap();
            let mut bytes = Vec::new();
            ch.write_to(&mut bytes).unwrap();
            assert_eq!((bytes.len(), fnv(&bytes)), (len, hash), "{model:?}");
        }
    }

    #[test]
    fn a_saved_hierarchy_loads_and_answers_every_query_as_built() {
        for model in [
            MoveModel::Octile,
            MoveModel::OctileCornerCutting,
            MoveModel::FourConnected,
        ] {
            let (built, bytes) = saved(model);
            let loaded = ContractionHierarchy::read_from(&bytes[..], grid(), model).unwrap();
            let g = grid();
            let free: Vec<Cell> = (0..g.len())
                .map(|i| g.cell(i))
                .filter(|&c| !g.is_blocked(c))
                .collect();
            let mut q = ChQuery::default();
            for &a in &free {
                for &b in &free {
                    let (x, y) = (
                        built.search(&mut q, a, b).unwrap(),
                        loaded.search(&mut q, a, b).unwrap(),
                    );
                    assert_eq!(x.cells, y.cells);
                    let truth = crate::oracle::dijkstra_exact(&g, a, b, model)
                        .unwrap()
                        .to_f64();
                    assert!((y.cost_cells() - truth).abs() < 1e-9);
                }
            }
        }
    }

    #[test]
    fn damaged_truncated_foreign_and_other_files_are_refused_by_name() {
        let (_, bytes) = saved(MoveModel::Octile);
        let read =
            |b: &[u8]| ContractionHierarchy::read_from(b, grid(), MoveModel::Octile).unwrap_err();
        // A flipped body byte: the checksum.
        let mut damaged = bytes.clone();
        let at = HEADER_BYTES + (bytes.len() - HEADER_BYTES) / 2;
        damaged[at] ^= 0x40;
        assert_eq!(read(&damaged), ChFileError::Checksum);
        // Truncated, in the body and in the header; one byte too many.
        assert!(matches!(
            read(&bytes[..bytes.len() - 3]),
            ChFileError::Length { .. }
        ));
        assert!(matches!(
            read(&bytes[..HEADER_BYTES - 4]),
            ChFileError::Length { .. }
        ));
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(read(&longer), ChFileError::Length { .. }));
        // Not a hierarchy (a JPS+ table's magic), another version.
        assert_eq!(
            read(b"SKYPLAN-JPSPLUS\n and more"),
            ChFileError::NotAHierarchy
        );
        assert_eq!(read(b""), ChFileError::NotAHierarchy);
        let mut version = bytes.clone();
        version[16] = 9;
        assert_eq!(
            read(&version),
            ChFileError::Version {
                found: 9,
                expected: VERSION
            }
        );
        // Another grid, another move model.
        let other = Arc::new(
            Grid2::from_ascii("..........\n..........\n..........\n..........\n..........")
                .unwrap(),
        );
        let e = ContractionHierarchy::read_from(&bytes[..], other, MoveModel::Octile).unwrap_err();
        assert!(matches!(e, ChFileError::OtherGrid(_)), "{e}");
        let e = ContractionHierarchy::read_from(&bytes[..], grid(), MoveModel::FourConnected)
            .unwrap_err();
        assert!(
            e.to_string().contains("(octile); this grid is 5 × 10"),
            "{e}"
        );
        // A huge count in the header with a short body: a length error, no huge allocation.
        let mut huge = bytes.clone();
        huge[48..52].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(read(&huge), ChFileError::Length { .. }));
    }

    #[test]
    fn a_consistent_checksum_over_an_inconsistent_structure_is_refused() {
        let (ch, _) = saved(MoveModel::Octile);
        let reseal = |body: Vec<u8>| {
            let mut bytes = Vec::new();
            ch.write_to(&mut bytes).unwrap();
            bytes.truncate(HEADER_BYTES);
            bytes[52..60].copy_from_slice(&body_sum(&body).to_le_bytes());
            bytes.extend_from_slice(&body);
            bytes
        };
        let n = ch.cell_of_rank.len();
        let m = ch.arcs.len();
        // An arc pointing past the nodes.
        let mut body = ch.body();
        let head_at = 4 * n + 4 * (n + 1);
        body[head_at..head_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = ContractionHierarchy::read_from(&reseal(body)[..], grid(), MoveModel::Octile)
            .unwrap_err();
        assert!(matches!(e, ChFileError::Damaged(_)), "{e}");
        // A shortcut naming itself as a half (an endless unpacking), if there is a shortcut.
        let edges_at = head_at + 16 * m;
        {
            let k =
                (ch.edges.iter().position(|e| e.mid != NONE)).expect("the grid makes a shortcut");
            let mut body = ch.body();
            let at = edges_at + 20 * k + 12;
            body[at..at + 4].copy_from_slice(&(k as u32).to_le_bytes());
            let e = ContractionHierarchy::read_from(&reseal(body)[..], grid(), MoveModel::Octile)
                .unwrap_err();
            assert_eq!(
                e,
                ChFileError::Damaged(format!("shortcut {k} is not made of two earlier edges"))
            );
        }
        // Two ranks naming one cell.
        let mut body = ch.body();
        let first = body[0..4].to_vec();
        body[4..8].copy_from_slice(&first);
        let e = ContractionHierarchy::read_from(&reseal(body)[..], grid(), MoveModel::Octile)
            .unwrap_err();
        assert!(e.to_string().contains("named twice"), "{e}");
    }
}
