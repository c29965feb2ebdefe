//! A\* over a weighted undirected graph given as adjacency lists, with a binary heap and an
//! admissible heuristic.
//!
//! ```
//! use skyplan_sampling::graph::astar;
//! // 0 —1— 1 —1— 2, and a long direct edge 0 —5— 2.
//! let adjacency = vec![vec![(1, 1.0), (2, 5.0)], vec![(0, 1.0), (2, 1.0)], vec![(1, 1.0), (0, 5.0)]];
//! let (path, cost) = astar(&adjacency, 0, 2, |_| 0.0).unwrap();
//! assert_eq!(path, vec![0, 1, 2]);
//! assert_eq!(cost, 2.0);
//! ```

use skyplan_search::{OpenEntry, OpenList};

/// Shortest path from `start` to `goal` (node lists and cost), or `None` if unreachable.
///
/// `adjacency[v]` lists `(neighbour, edge cost ≥ 0)`; `heuristic(v)` must never overestimate
/// the remaining cost (for points in space: the straight-line distance to the goal).
pub fn astar(
    adjacency: &[Vec<(u32, f64)>],
    start: u32,
    goal: u32,
    heuristic: impl Fn(u32) -> f64,
) -> Option<(Vec<u32>, f64)> {
    let n = adjacency.len();
    if start as usize >= n || goal as usize >= n {
        return None;
    }
    let mut g = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let mut open = OpenList::new(n);
    g[start as usize] = 0.0;
    open.push(OpenEntry {
        f: heuristic(start),
        g: 0.0,
        node: start,
    });
    while let Some(OpenEntry { g: gv, node, .. }) = open.pop() {
        if node == goal {
            let mut path = vec![goal];
            let mut k = goal;
            while k != start {
                k = parent[k as usize];
                path.push(k);
            }
            path.reverse();
            return Some((path, gv));
        }
        for &(w, c) in &adjacency[node as usize] {
            let nw = w as usize;
            let ng = gv + c;
            if !open.is_closed(w) && ng < g[nw] {
                g[nw] = ng;
                parent[nw] = node;
                open.push(OpenEntry {
                    f: ng + heuristic(w),
                    g: ng,
                    node: w,
                });
            }
        }
    }
    None
}
