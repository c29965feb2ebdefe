//! The subgoal graph on disk: its contraction hierarchy, in the hierarchy file's layout
//! ([`crate::ch_file`]) under its own magic, `SKYPLAN-SUBGOAL\n`, version 1. The hierarchy is
//! what takes long to build (seconds on rooms whose doors let every corner see many others);
//! the subgoals, the graph's edges and the cells' roots come again from the grid on loading, in
//! tens of milliseconds, and the hub labels from the hierarchy.
//!
//! Loading ([`SubgoalGraph::read_from`]) checks what the hierarchy file's loading checks, with
//! the graph's nodes and edges in place of the grid's cells and moves: the ranks are a
//! permutation of the grid's subgoals, and every original edge joins two subgoals that reach
//! each other directly, at their octile distance. A damaged or foreign file is a
//! [`SubgoalFileError`], never a wrong path or a panic.

use crate::ch_file::{ChFileError, Nodes};
use crate::subgoal::{Floods, KEEP_ALL};
use crate::{ContractionHierarchy, MoveModel, SubgoalError, SubgoalGraph};
use skyplan_cspace::Grid2;
use std::io::{Read, Write};
use std::sync::Arc;

/// The first 16 bytes of a subgoal graph file.
pub const MAGIC: &[u8; 16] = b"SKYPLAN-SUBGOAL\n";

/// Why a subgoal graph file cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SubgoalFileError {
    /// Not a subgoal graph file.
    #[error("not a saved skyplan subgoal graph (expected the header `SKYPLAN-SUBGOAL`)")]
    NotASubgoalGraph,
    /// Its hierarchy is refused (version, length, checksum, grid, structure, input/output).
    #[error("subgoal graph file: {0}")]
    Hierarchy(ChFileError),
    /// The grid gives no subgoal graph (too large).
    #[error("subgoal graph file: {0}")]
    Graph(SubgoalError),
}

impl SubgoalGraph {
    /// Bytes of its file.
    pub fn file_bytes(&self) -> u64 {
        self.hierarchy().file_bytes()
    }

    /// Writes the graph as a file (module docs) to `out`.
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_search::{MoveModel, SubgoalGraph, SubgoalQuery};
    /// use std::sync::Arc;
    /// let grid = Arc::new(Grid2::from_ascii("......\n.####.\n......\n###...")?);
    /// let built = SubgoalGraph::build(Arc::clone(&grid), MoveModel::Octile)?;
    /// let mut bytes = Vec::new();
    /// built.write_to(&mut bytes)?;
    /// assert_eq!(bytes.len() as u64, built.file_bytes());
    /// let loaded = SubgoalGraph::read_from(&bytes[..], grid)?;
    /// let mut q = SubgoalQuery::new();
    /// let (a, b) = (Cell::new(0, 2), Cell::new(3, 3));
    /// assert_eq!(loaded.search(&mut q, a, b)?.cells, built.search(&mut q, a, b)?.cells);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn write_to(&self, out: impl Write) -> Result<(), SubgoalFileError> {
        self.hierarchy()
            .write_with(out, MAGIC)
            .map_err(SubgoalFileError::Hierarchy)
    }

    /// Reads a file written by [`SubgoalGraph::write_to`] for `grid` (8-connected, no corner
    /// cutting); refused with a [`SubgoalFileError`] if it is not one, another version,
    /// truncated, damaged, or built for another grid.
    pub fn read_from(input: impl Read, grid: Arc<Grid2>) -> Result<Self, SubgoalFileError> {
        let model = MoveModel::Octile;
        let mut head = [0u8; 16];
        let mut input = input;
        let got = crate::ch_file::read_up_to(&mut input, &mut head)
            .map_err(|e| SubgoalFileError::Hierarchy(e.into()))?;
        if got < 16 || &head != MAGIC {
            return Err(SubgoalFileError::NotASubgoalGraph);
        }
        let mut floods = Floods::run(&grid, None, KEEP_ALL).map_err(SubgoalFileError::Graph)?;
        // Sorted for the look-ups below (the graph needs only their number).
        floods.pairs.sort_unstable();
        let pairs = &floods.pairs;
        let node_cells = &floods.node_cells;
        let cols = grid.cols() as usize;
        let node_of = |cell: skyplan_cspace::Cell| {
            let i = cell.row as usize * cols + cell.col as usize;
            node_cells.binary_search(&(i as u32)).ok().map(|k| k as u32)
        };
        let original = |p, q| {
            let (a, b) = (node_of(p)?, node_of(q)?);
            let (u, v) = (a.min(b), a.max(b));
            let at = pairs.partition_point(|&(x, y, _)| (x, y) < (u, v));
            pairs
                .get(at)
                .filter(|&&(x, y, _)| (x, y) == (u, v))
                .map(|&(_, _, cost)| cost)
        };
        let nodes = Nodes {
            count: node_cells.len(),
            what: "subgoals",
            is_node: &|i| node_cells.binary_search(&(i as u32)).is_ok(),
            original: &original,
            neighbours: "subgoals that reach each other directly",
        };
        let parts =
            ContractionHierarchy::read_parts((&head[..]).chain(input), &grid, model, MAGIC, &nodes)
                .map_err(SubgoalFileError::Hierarchy)?;
        let ch = parts.into_hierarchy(Arc::clone(&grid), model);
        SubgoalGraph::assemble(grid, floods, ch, None, KEEP_ALL).map_err(SubgoalFileError::Graph)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SubgoalQuery;
    use crate::oracle::dijkstra_exact;
    use skyplan_cspace::Cell;

    fn grid() -> Arc<Grid2> {
        Arc::new(
            Grid2::from_ascii(
                "............\n.###..##..#.\n...#......#.\n.#...####...\n......#.....\n.##.....##..",
            )
            .unwrap(),
        )
    }

    fn saved() -> (SubgoalGraph, Vec<u8>) {
        let graph = SubgoalGraph::build(grid(), MoveModel::Octile).unwrap();
        let mut bytes = Vec::new();
        graph.write_to(&mut bytes).unwrap();
        (graph, bytes)
    }

    /// A corridor with two blocks far apart: four subgoals whose hops are much longer than the
    /// graph has nodes, so its shortcuts cost more than a path through every node once (a
    /// bound the file's check once took from the node count).
    #[test]
    fn a_graph_of_few_subgoals_and_long_hops_loads() {
        let row = |blocked: &[usize]| -> String {
            (0..60)
                .map(|c| if blocked.contains(&c) { '#' } else { '.' })
                .collect()
        };
        let text = [row(&[]), row(&[5, 54]), row(&[]), row(&[30]), row(&[])].join("\n");
        let grid = Arc::new(Grid2::from_ascii(&text).unwrap());
        let graph = SubgoalGraph::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
        assert!(
            graph
                .hierarchy()
                .edges
                .iter()
                .any(|e| e.mid != crate::contraction::NONE)
        );
        let mut bytes = Vec::new();
        graph.write_to(&mut bytes).unwrap();
        let loaded = SubgoalGraph::read_from(&bytes[..], Arc::clone(&grid)).unwrap();
        let (a, b) = (Cell::new(2, 0), Cell::new(2, 59));
        let mut q = SubgoalQuery::new();
        assert_eq!(
            loaded.search(&mut q, a, b).unwrap().cells,
            graph.search(&mut q, a, b).unwrap().cells
        );
    }

    #[test]
    fn a_saved_graph_loads_and_answers_every_query_as_built() {
        let (built, bytes) = saved();
        assert!(built.subgoals() > 10);
        let loaded = SubgoalGraph::read_from(&bytes[..], grid()).unwrap();
        assert_eq!(
            (loaded.subgoals(), loaded.edges(), loaded.label_entries()),
            (built.subgoals(), built.edges(), built.label_entries())
        );
        let g = grid();
        let free: Vec<Cell> = (0..g.len())
            .map(|i| g.cell(i))
            .filter(|&c| !g.is_blocked(c))
            .collect();
        let mut q = SubgoalQuery::new();
        for &a in &free {
            for &b in &free {
                let (x, y) = (
                    built.search(&mut q, a, b).unwrap(),
                    loaded.search(&mut q, a, b).unwrap(),
                );
                assert_eq!(x.cells, y.cells);
                let truth = dijkstra_exact(&g, a, b, MoveModel::Octile).unwrap();
                assert_eq!(
                    (y.straight_moves, y.diagonal_moves),
                    (truth.straight, truth.diagonal)
                );
            }
        }
    }

    /// Every single flipped bit anywhere in the file is refused (magic, version, move model,
    /// grid size and checksum, counts, body checksum, body), never a panic or a wrong graph.
    #[test]
    fn every_flipped_bit_is_refused() {
        let (_, bytes) = saved();
        for at in 0..bytes.len() {
            for bit in [0x01u8, 0x80] {
                let mut damaged = bytes.clone();
                damaged[at] ^= bit;
                assert!(
                    SubgoalGraph::read_from(&damaged[..], grid()).is_err(),
                    "byte {at} bit {bit:#x}"
                );
            }
        }
    }

    #[test]
    fn damaged_foreign_and_other_files_are_refused_by_name() {
        let (graph, bytes) = saved();
        let read = |b: &[u8]| SubgoalGraph::read_from(b, grid()).unwrap_err();
        // A hierarchy file of the same grid is not a subgoal graph, nor is nothing.
        let ch = ContractionHierarchy::build(grid(), MoveModel::Octile).unwrap();
        let mut other = Vec::new();
        ch.write_to(&mut other).unwrap();
        assert_eq!(read(&other), SubgoalFileError::NotASubgoalGraph);
        assert_eq!(read(b""), SubgoalFileError::NotASubgoalGraph);
        // A flipped byte, a truncated file.
        let mut damaged = bytes.clone();
        let at = bytes.len() - 9;
        damaged[at] ^= 0x10;
        assert_eq!(
            read(&damaged),
            SubgoalFileError::Hierarchy(ChFileError::Checksum)
        );
        assert!(matches!(
            read(&bytes[..bytes.len() - 1]),
            SubgoalFileError::Hierarchy(ChFileError::Length { .. })
        ));
        // Another grid.
        let open = Arc::new(Grid2::from_ascii("......\n......").unwrap());
        let e = SubgoalGraph::read_from(&bytes[..], open).unwrap_err();
        assert!(
            matches!(e, SubgoalFileError::Hierarchy(ChFileError::OtherGrid(_))),
            "{e}"
        );
        assert!(e.to_string().starts_with("subgoal graph file: "), "{e}");
        // A consistent checksum over a hierarchy whose original edge joins two subgoals that
        // do not see each other: the edges of the file are rewritten to join the first and the
        // last subgoal, and the body resealed.
        let n = graph.subgoals();
        let h = graph.hierarchy();
        let (m, e) = (h.arcs.len(), h.edges.len());
        let header = crate::ch_file::HEADER_BYTES;
        let mut body = bytes[header..].to_vec();
        let edges_at = 4 * n + 4 * (n + 1) + 16 * m;
        let k = (h
            .edges
            .iter()
            .position(|x| x.mid == crate::contraction::NONE))
        .unwrap();
        // A rank whose subgoal does not reach edge k's first end's directly.
        let floods = Floods::run(&grid(), None, KEEP_ALL).unwrap();
        let node = |r: u32| floods.node_cells.binary_search(&h.cell_of(r)).unwrap() as u32;
        let a = node(h.edges[k].a);
        let far = (0..n as u32)
            .find(|&r| {
                let b = node(r);
                b != a && !(floods.pairs.iter()).any(|&(x, y, _)| (x, y) == (a.min(b), a.max(b)))
            })
            .unwrap();
        body[edges_at + 20 * k + 4..edges_at + 20 * k + 8].copy_from_slice(&far.to_le_bytes());
        assert!(e > k);
        let mut resealed = bytes[..header].to_vec();
        resealed[52..60].copy_from_slice(&crate::ch_file::body_sum(&body).to_le_bytes());
        resealed.extend_from_slice(&body);
        let err = read(&resealed);
        assert_eq!(
            err.to_string(),
            format!(
                "subgoal graph file: contraction hierarchy is damaged: edge {k} joins cells that are not subgoals that reach each other directly"
            )
        );
    }
}
