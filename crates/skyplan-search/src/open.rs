//! [`OpenList`] and its [`OpenEntry`]: the open list of the binary-heap A\* and Dijkstra
//! searches over float costs (graph, roadmap, lattice and cost-map searches; the grid planners
//! here use their own packed queue).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

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

/// A binary-heap open list with lazy deletion over nodes `0..n`, for A\* and Dijkstra over
/// float costs: an entry is pushed each time a node's cost improves, and [`OpenList::pop`]
/// passes over the entries of nodes already closed, closes the node it returns and counts it as
/// an expansion.
///
/// ```
/// use skyplan_search::{OpenEntry, OpenList};
/// let mut open = OpenList::new(3);
/// open.push(OpenEntry { f: 4.0, g: 4.0, node: 1 });
/// open.push(OpenEntry { f: 2.0, g: 2.0, node: 1 }); // a better route to node 1
/// open.push(OpenEntry { f: 3.0, g: 3.0, node: 2 });
/// assert_eq!(open.pop().map(|e| (e.node, e.g)), Some((1, 2.0)));
/// assert!(open.is_closed(1));
/// assert_eq!(open.pop().map(|e| e.node), Some(2));
/// assert_eq!(open.pop(), None); // node 1's stale entry is passed over
/// assert_eq!(open.expansions(), 2);
/// ```
#[derive(Debug, Clone, Default)]
pub struct OpenList {
    heap: BinaryHeap<OpenEntry>,
    closed: Vec<bool>,
    expansions: u64,
}

impl OpenList {
    /// An empty open list over nodes `0..nodes`, none closed.
    pub fn new(nodes: usize) -> Self {
        Self {
            heap: BinaryHeap::new(),
            closed: vec![false; nodes],
            expansions: 0,
        }
    }

    /// Queues `entry`; its node may be queued already, with a worse cost.
    pub fn push(&mut self, entry: OpenEntry) {
        self.heap.push(entry);
    }

    /// The best queued entry whose node is not closed yet, its node now closed (one expansion);
    /// `None` when no such entry is left.
    pub fn pop(&mut self) -> Option<OpenEntry> {
        while let Some(entry) = self.heap.pop() {
            let closed = &mut self.closed[entry.node as usize];
            if !*closed {
                *closed = true;
                self.expansions += 1;
                return Some(entry);
            }
        }
        None
    }

    /// True if `node` has been popped: its cost is final.
    pub fn is_closed(&self, node: u32) -> bool {
        self.closed[node as usize]
    }

    /// Nodes popped so far.
    pub fn expansions(&self) -> u64 {
        self.expansions
    }
}
