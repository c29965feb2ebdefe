//! Nearest-neighbour index over a growing point set: kiddo's mutable k-d tree, with a linear
//! overflow list for the rare point kiddo cannot place (a full bucket of equal coordinates).
//!
//! ```
//! use skyplan_sampling::nearest::NearIndex;
//! let mut index = NearIndex::default();
//! for p in [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 3.0, 4.0]] {
//!     index.add(p);
//! }
//! assert_eq!(index.nearest([9.0, 0.0, 0.0]), Some(1));
//! assert_eq!(index.nearest_n([0.0, 0.0, 1.0], 2), vec![0, 2]);
//! ```

use crate::Neu;
use kiddo::{MutableKdTree, SquaredEuclidean};
use std::num::NonZeroUsize;

/// Points numbered in insertion order, with nearest and k-nearest queries (exact, Euclidean).
#[derive(Default)]
pub struct NearIndex {
    tree: MutableKdTree<f64, 3>,
    points: Vec<Neu>,
    overflow: Vec<u32>,
}

impl std::fmt::Debug for NearIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NearIndex")
            .field("points", &self.points.len())
            .field("overflow", &self.overflow.len())
            .finish()
    }
}

fn d2(a: Neu, b: Neu) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

impl NearIndex {
    /// Adds a point; returns its number.
    pub fn add(&mut self, p: Neu) -> u32 {
        let id = self.points.len() as u32;
        self.points.push(p);
        if self.tree.add(&p, id).is_err() {
            self.overflow.push(id);
        }
        id
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The nearest point's number (ties: any), or `None` if empty.
    pub fn nearest(&self, q: Neu) -> Option<u32> {
        let mut best: Option<(f64, u32)> = None;
        if self.tree.size() > 0 {
            let r = self
                .tree
                .query(&q)
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute();
            best = Some((r.distance, r.item));
        }
        for &k in &self.overflow {
            let d = d2(self.points[k as usize], q);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, k));
            }
        }
        best.map(|(_, k)| k)
    }

    /// The numbers of the `k` nearest points, nearest first.
    pub fn nearest_n(&self, q: Neu, k: usize) -> Vec<u32> {
        let Some(k_nz) = NonZeroUsize::new(k) else {
            return Vec::new();
        };
        let mut found: Vec<(f64, u32)> = Vec::new();
        if self.tree.size() > 0 {
            found = self
                .tree
                .query(&q)
                .nearest_n::<SquaredEuclidean<f64>>(k_nz)
                .execute()
                .into_iter()
                .map(|r| (r.distance, r.item))
                .collect();
        }
        if !self.overflow.is_empty() {
            found.extend(
                self.overflow
                    .iter()
                    .map(|&i| (d2(self.points[i as usize], q), i)),
            );
            found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            found.truncate(k);
        }
        found.into_iter().map(|(_, i)| i).collect()
    }
}
