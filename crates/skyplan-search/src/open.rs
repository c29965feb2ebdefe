//! [`OpenEntry`]: the open-list entry of the binary-heap A\* and Dijkstra searches over float
//! costs (graph, roadmap and cost-map searches; the grid planners here use their own packed
//! queue).

use std::cmp::Ordering;

/// An entry of a [`BinaryHeap`](std::collections::BinaryHeap) open list, ordered so the heap
/// pops the smallest `f` first; on equal `f` the larger `g` (the deeper node), then the smaller
/// node index. Costs compare by [`f64::total_cmp`], so the order is total (costs are expected to
/// be non-negative and not NaN).
///
/// ```
/// use skyplan_search::OpenEntry;
/// use std::collections::BinaryHeap;
/// let mut heap = BinaryHeap::from([
///     OpenEntry { f: 3.0, g: 1.0, node: 0 },
///     OpenEntry { f: 2.0, g: 0.5, node: 1 },
///     OpenEntry { f: 2.0, g: 1.5, node: 2 },
///     OpenEntry { f: 2.0, g: 1.5, node: 3 },
/// ]);
/// let order: Vec<u32> = std::iter::from_fn(|| heap.pop().map(|e| e.node)).collect();
/// assert_eq!(order, [2, 3, 1, 0]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenEntry {
    /// The priority: the cost so far plus the heuristic (the cost so far alone for Dijkstra).
    pub f: f64,
    /// The cost so far.
    pub g: f64,
    /// The node: a cell or vertex index.
    pub node: u32,
}

impl Eq for OpenEntry {}

impl Ord for OpenEntry {
    fn cmp(&self, other: &Self) -> Ordering {
        // Reversed on f and node (BinaryHeap is a max-heap), straight on g (larger g first).
        other
            .f
            .total_cmp(&self.f)
            .then_with(|| self.g.total_cmp(&other.g))
            .then_with(|| other.node.cmp(&self.node))
    }
}

impl PartialOrd for OpenEntry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
