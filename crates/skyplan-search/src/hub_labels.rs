//! Hub labels over a contraction hierarchy (Abraham, Delling, Goldberg and Werneck,
//! "Hierarchical Hub Labelings for Shortest Paths", ESA 2012): a query reads two short lists
//! instead of searching.
//!
//! * Every node `v` keeps a **label**: nodes `h` (its hubs) with the distance of a shortest
//!   upward path `v → h` in the hierarchy. The labels are made from the top rank down: `v`'s
//!   candidates are itself and, for each upward arc `v → w`, the hubs of `w`'s label with the
//!   arc's cost added; a candidate `(h, d)` is then **pruned** when another candidate `x` and
//!   `h`'s own label show a path `v → x → h` shorter than `d` (its distance is not the shortest,
//!   so no shortest path peaks there).
//! * For any two nodes the hierarchy has a shortest path that climbs to its highest node and
//!   descends; its halves are shortest paths, so the peak is in both labels with the exact
//!   distances, and `min over common hubs (d(s, h) + d(t, h))` is the distance.
//! * Each entry also keeps the upward arc its path starts with, so the path to a hub is walked
//!   label by label (`v → w`, then `w`'s entry for the same hub) and its shortcuts unpacked.
//!
//! The hierarchy must be complete (no core): [`HubLabels::build`] declines otherwise, and when
//! the labels would hold more than a given number of entries.

use crate::contraction::{ChQuery, ContractionHierarchy, NONE};

/// One hub of a label while the labels are made: the distance to it and the edge of the upward
/// arc the path starts with (`NONE` for the node itself).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct HubEntry {
    dist: u64,
    hub: u32,
    via: u32,
}

/// Every rank's label, by rank, each sorted by hub; the hubs, distances and first arcs in
/// three arrays, so that a query reads 12 bytes an entry, not 16 (the arcs are for climbing).
#[derive(Debug)]
pub(crate) struct HubLabels {
    /// `hubs[first[r]..first[r + 1]]` (and the same span of the others) is rank `r`'s label.
    pub(crate) first: Vec<u32>,
    pub(crate) hubs: Vec<u32>,
    pub(crate) dists: Vec<u64>,
    pub(crate) vias: Vec<u32>,
}

/// Why no labels were made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LabelRefusal {
    /// The hierarchy has a core (nodes whose "upward" arcs lead down).
    Core,
    /// More entries than allowed.
    TooLarge,
    /// The deadline passed.
    Deadline,
}

/// Where a query's best path peaks, and through which roots.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LabelMeet {
    /// The path's cost, roots' initial costs included.
    pub(crate) cost: u64,
    /// The peak (a rank).
    pub(crate) hub: u32,
    /// Indices of the source and target roots the path starts and ends at.
    pub(crate) source: usize,
    pub(crate) target: usize,
}

/// A query's reusable buffer: the best distance to each hub from the sources.
#[derive(Debug, Default)]
pub(crate) struct LabelQuery {
    /// Per rank: distance, stamp, source root index.
    best: Vec<(u64, u32, u32)>,
    now: u32,
}

impl HubLabels {
    /// Labels of every rank of `ch`, or why not (module docs); at most `max_entries` entries.
    pub(crate) fn build(
        ch: &ContractionHierarchy,
        max_entries: usize,
        deadline: Option<std::time::Instant>,
    ) -> Result<Self, LabelRefusal> {
        let n = ch.cell_of_rank.len();
        let arcs_of = |r: usize| &ch.arcs[ch.first_out[r] as usize..ch.first_out[r + 1] as usize];
        if (0..n).any(|r| arcs_of(r).iter().any(|a| a.head as usize <= r)) {
            return Err(LabelRefusal::Core);
        }
        let mut labels: Vec<Vec<HubEntry>> = vec![Vec::new(); n];
        // Per rank: candidate distance, via edge, stamp.
        let mut cand: Vec<(u64, u32, u32)> = vec![(0, NONE, 0); n];
        let mut touched: Vec<u32> = Vec::new();
        let mut total = 0usize;
        for r in (0..n).rev() {
            if r % 256 == 0
                && let Some(d) = deadline
                && std::time::Instant::now() >= d
            {
                return Err(LabelRefusal::Deadline);
            }
            let now = (n - r) as u32;
            touched.clear();
            cand[r] = (0, NONE, now);
            touched.push(r as u32);
            for a in arcs_of(r) {
                for e in &labels[a.head as usize] {
                    let d = a.cost.saturating_add(e.dist);
                    let c = &mut cand[e.hub as usize];
                    if c.2 != now {
                        *c = (d, a.edge, now);
                        touched.push(e.hub);
                    } else if d < c.0 {
                        *c = (d, a.edge, now);
                    }
                }
            }
            touched.sort_unstable();
            let mut label = Vec::with_capacity(touched.len());
            for &h in &touched {
                let (d, via, _) = cand[h as usize];
                // Pruned when a path through another candidate hub x is shorter: every
                // candidate distance is the length of a real upward path.
                let shorter = h as usize != r
                    && labels[h as usize].iter().any(|x| {
                        let c = cand[x.hub as usize];
                        x.hub != h && c.2 == now && c.0.saturating_add(x.dist) < d
                    });
                if !shorter {
                    label.push(HubEntry {
                        dist: d,
                        hub: h,
                        via,
                    });
                }
            }
            total += label.len();
            if total > max_entries || total > u32::MAX as usize {
                return Err(LabelRefusal::TooLarge);
            }
            labels[r] = label;
        }
        let mut first = Vec::with_capacity(n + 1);
        let (mut hubs, mut dists, mut vias) = (
            Vec::with_capacity(total),
            Vec::with_capacity(total),
            Vec::with_capacity(total),
        );
        for label in labels {
            first.push(hubs.len() as u32);
            for e in label {
                hubs.push(e.hub);
                dists.push(e.dist);
                vias.push(e.via);
            }
        }
        first.push(hubs.len() as u32);
        Ok(Self {
            first,
            hubs,
            dists,
            vias,
        })
    }

    /// The span of rank `r`'s label in the arrays.
    #[inline]
    fn span(&self, r: u32) -> std::ops::Range<usize> {
        self.first[r as usize] as usize..self.first[r as usize + 1] as usize
    }

    /// Rank `r`'s label: its hubs and the distances to them.
    #[inline]
    pub(crate) fn label(&self, r: u32) -> (&[u32], &[u64]) {
        let span = self.span(r);
        (&self.hubs[span.clone()], &self.dists[span])
    }

    /// Entries in all.
    pub(crate) fn entries(&self) -> usize {
        self.hubs.len()
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.first.len() * 4 + self.hubs.len() * (4 + 8 + 4)
    }

    /// The cheapest path from any source to any target (ranks with initial costs, as if a
    /// super-source and a super-target were joined to them), and the entries read.
    pub(crate) fn meet(
        &self,
        q: &mut LabelQuery,
        sources: &[(u32, u64)],
        targets: &[(u32, u64)],
    ) -> (Option<LabelMeet>, u64) {
        let n = self.first.len() - 1;
        if q.best.len() != n {
            q.best = vec![(0, 0, 0); n];
            q.now = 0;
        }
        if q.now == u32::MAX {
            q.best.iter_mut().for_each(|b| b.1 = 0);
            q.now = 0;
        }
        q.now += 1;
        let now = q.now;
        let mut read = 0u64;
        for (i, &(root, d0)) in sources.iter().enumerate() {
            let (hubs, dists) = self.label(root);
            read += hubs.len() as u64;
            for (&hub, &dist) in hubs.iter().zip(dists) {
                let d = d0.saturating_add(dist);
                let b = &mut q.best[hub as usize];
                if b.1 != now || d < b.0 {
                    *b = (d, now, i as u32);
                }
            }
        }
        let mut meet: Option<LabelMeet> = None;
        for (j, &(root, d0)) in targets.iter().enumerate() {
            let (hubs, dists) = self.label(root);
            read += hubs.len() as u64;
            for (&hub, &dist) in hubs.iter().zip(dists) {
                let b = q.best[hub as usize];
                if b.1 == now {
                    let cost = b.0.saturating_add(d0).saturating_add(dist);
                    if meet.is_none_or(|m| cost < m.cost) {
                        meet = Some(LabelMeet {
                            cost,
                            hub,
                            source: b.2 as usize,
                            target: j,
                        });
                    }
                }
            }
        }
        (meet, read)
    }

    /// The distance between ranks `a` and `b` (a merge of their labels, sorted by hub), or
    /// `None` when they are not connected.
    pub(crate) fn distance(&self, a: u32, b: u32) -> Option<u64> {
        let ((xh, xd), (yh, yd)) = (self.label(a), self.label(b));
        let (mut i, mut j) = (0, 0);
        let mut best: Option<u64> = None;
        while i < xh.len() && j < yh.len() {
            match xh[i].cmp(&yh[j]) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    let d = xd[i].saturating_add(yd[j]);
                    best = Some(best.map_or(d, |b| b.min(d)));
                    i += 1;
                    j += 1;
                }
            }
        }
        best
    }

    /// Appends the ranks of the upward path from `from` to its hub `hub` (without `from`),
    /// shortcuts unpacked; `None` if `hub` is not in the labels on the way (never for a hub a
    /// [`Self::meet`] returned).
    pub(crate) fn climb(
        &self,
        ch: &ContractionHierarchy,
        q: &mut ChQuery,
        from: u32,
        hub: u32,
        out: &mut Vec<u32>,
    ) -> Option<()> {
        let mut v = from;
        while v != hub {
            let span = self.span(v);
            let at = self.hubs[span.clone()].binary_search(&hub).ok()?;
            let via = self.vias[span.start + at];
            if via == NONE {
                return None;
            }
            v = ch.unpack_ranks(q, v, via, out);
        }
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contraction::{DIAGONAL, STRAIGHT};
    use crate::oracle::dijkstra_exact;
    use crate::{MoveModel, check_path};
    use proptest::prelude::*;
    use skyplan_cspace::{Cell, Grid2, GridFrame};
    use std::sync::Arc;

    fn grid_strategy() -> impl Strategy<Value = Grid2> {
        (1u32..16, 1u32..16, 0.0f64..0.4).prop_flat_map(|(rows, cols, density)| {
            proptest::collection::vec(proptest::bool::weighted(density), (rows * cols) as usize)
                .prop_map(move |b| Grid2::new(rows, cols, b, GridFrame::default()).unwrap())
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(if std::env::var_os("CI").is_some() { 400 } else { 120 }))]

        /// Labels of a grid's own hierarchy (every free cell a node), every pair of free cells:
        /// the cost is the exact Dijkstra oracle's, and the path walked through the labels to
        /// the meeting hub, shortcuts unpacked, is a valid path of that many moves.
        #[test]
        fn labels_give_the_oracle_distances_and_paths(grid in grid_strategy(), model in prop_oneof![Just(MoveModel::Octile), Just(MoveModel::FourConnected)]) {
            let grid = Arc::new(grid);
            let ch = ContractionHierarchy::build(Arc::clone(&grid), model).unwrap();
            let labels = HubLabels::build(&ch, usize::MAX, None).unwrap();
            let (mut lq, mut cq) = (LabelQuery::default(), ChQuery::default());
            let free: Vec<Cell> = (0..grid.len()).map(|i| grid.cell(i)).filter(|&c| !grid.is_blocked(c)).collect();
            for &s in &free {
                for &t in &free {
                    let (rs, rt) = (ch.rank_of(grid.index(s)), ch.rank_of(grid.index(t)));
                    let (meet, _) = labels.meet(&mut lq, &[(rs, 0)], &[(rt, 0)]);
                    let want = dijkstra_exact(&grid, s, t, model);
                    prop_assert_eq!(meet.map(|m| m.cost), want.map(|c| c.straight * STRAIGHT + c.diagonal * DIAGONAL), "{:?} → {:?}", s, t);
                    prop_assert_eq!(labels.distance(rs, rt), meet.map(|m| m.cost));
                    let Some(m) = meet else { continue };
                    let mut up = vec![rs];
                    let mut down = vec![rt];
                    prop_assert!(labels.climb(&ch, &mut cq, rs, m.hub, &mut up).is_some());
                    prop_assert!(labels.climb(&ch, &mut cq, rt, m.hub, &mut down).is_some());
                    down.pop();
                    up.extend(down.iter().rev());
                    let cells: Vec<Cell> = up.iter().map(|&r| grid.cell(ch.cell_of(r) as usize)).collect();
                    prop_assert_eq!((cells.first(), cells.last()), (Some(&s), Some(&t)));
                    prop_assert_eq!(check_path(&grid, &cells, model), Ok(()));
                    let diagonal = cells.windows(2).filter(|w| w[0].row != w[1].row && w[0].col != w[1].col).count() as u64;
                    let want = want.unwrap();
                    prop_assert_eq!((cells.len() as u64 - 1 - diagonal, diagonal), (want.straight, want.diagonal));
                }
            }
        }
    }

    #[test]
    fn several_roots_meet_at_the_cheapest_pair() {
        // A corridor 0 – 1 – … – 9: roots with initial costs, as the subgoal graph gives them.
        let grid = Arc::new(Grid2::from_ascii("..........").unwrap());
        let ch = ContractionHierarchy::build(Arc::clone(&grid), MoveModel::Octile).unwrap();
        let labels = HubLabels::build(&ch, usize::MAX, None).unwrap();
        let rank = |c: u32| ch.rank_of(c as usize);
        let mut q = LabelQuery::default();
        // From 2 (cost 5) or 4 (cost 1), to 8 (cost 1) or 9 (cost 0): 4 → 8 costs 1 + 4 + 1.
        let sources = [(rank(2), 5 * STRAIGHT), (rank(4), STRAIGHT)];
        let targets = [(rank(8), STRAIGHT), (rank(9), 0)];
        let (meet, read) = labels.meet(&mut q, &sources, &targets);
        let m = meet.unwrap();
        assert_eq!((m.cost, m.source, m.target), (6 * STRAIGHT, 1, 0));
        assert!(read >= 4);
        // A blocked cell splits the corridor: no meeting.
        let split = Arc::new(Grid2::from_ascii("....#.....").unwrap());
        let ch = ContractionHierarchy::build(Arc::clone(&split), MoveModel::Octile).unwrap();
        let labels = HubLabels::build(&ch, usize::MAX, None).unwrap();
        let (a, b) = (ch.rank_of(0), ch.rank_of(9));
        assert_eq!(labels.meet(&mut q, &[(a, 0)], &[(b, 0)]).0, None);
        // Too many entries: refused.
        assert_eq!(
            HubLabels::build(&ch, 3, None).err(),
            Some(LabelRefusal::TooLarge)
        );
        let past = std::time::Instant::now();
        assert_eq!(
            HubLabels::build(&ch, usize::MAX, Some(past)).err(),
            Some(LabelRefusal::Deadline)
        );
        // A hierarchy with a core (searched in every direction) has no labels.
        let core = ContractionHierarchy::build_with_core(grid, MoveModel::Octile, 0);
        assert_eq!(
            HubLabels::build(&core, usize::MAX, None).err(),
            Some(LabelRefusal::Core)
        );
    }
}
