//! The world as the vehicle knows it: the map's grid at one altitude plus cells learned from
//! range readings.

use skyplan_cspace::{Cell, Grid2};
use skyplan_flight::sensing::{ObstacleReading, SectorRange};
use std::collections::BTreeSet;
use std::sync::Arc;

/// The known grid at one altitude (the map's obstacles grown by the margin) and what range
/// readings taught: every hit marks its cell, and every cell within the margin of it is occupied;
/// rays clear earlier hits they pass through. The map's own obstacles never clear.
///
/// ```
/// use skyplan_cspace::{Cell, Grid2, GridFrame};
/// use skyplan_flight::sensing::{ObstacleReading, SectorRange};
/// use skyplan_replan::WorldModel;
/// use std::sync::Arc;
/// let grid = Grid2::new(40, 40, vec![false; 1600], GridFrame::default())?;
/// let mut world = WorldModel::new(Arc::new(grid), 1.0);
/// let mut ranges = vec![SectorRange::Clear; 4];
/// ranges[0] = SectorRange::Obstacle(10.0); // 10 m north of the vehicle at (5.5, 5.5)
/// let reading = ObstacleReading {
///     time_s: 0.0, position_ned: [5.5, 5.5, -5.0], velocity_ned_m_s: [0.0; 3], first_bearing_rad: 0.0,
///     increment_rad: std::f64::consts::FRAC_PI_2, min_range_m: 0.2, max_range_m: 20.0, ranges,
/// };
/// let changed = world.apply(&reading);
/// assert_eq!(changed.len(), 9); // the hit's cell and its 8 neighbours (a 1 m margin)
/// assert!(world.grid().is_blocked(Cell::new(15, 5)));
/// # Ok::<(), skyplan_cspace::GridError>(())
/// ```
#[derive(Debug, Clone)]
pub struct WorldModel {
    known: Arc<Grid2>,
    combined: Grid2,
    /// How many hit cells cover each cell (within the margin).
    cover: Vec<u16>,
    /// Cells holding a sensor hit.
    is_hit: Vec<bool>,
    /// The same cells, for a quick look at what lies near the vehicle.
    hit_list: BTreeSet<usize>,
    learned: usize,
    margin_cells: i64,
}

impl WorldModel {
    /// A model over the known grid; learned hits are grown by `margin_m` (rounded up to cells).
    pub fn new(known: Arc<Grid2>, margin_m: f64) -> Self {
        let cell_m = known.frame().cell_m;
        let margin_cells = if margin_m.is_finite() && margin_m > 0.0 {
            (margin_m / cell_m - 1e-9).ceil().max(0.0) as i64
        } else {
            0
        };
        Self {
            combined: (*known).clone(),
            cover: vec![0; known.len()],
            is_hit: vec![false; known.len()],
            hit_list: BTreeSet::new(),
            learned: 0,
            known,
            margin_cells,
        }
    }

    /// The map's grid (known obstacles grown by the margin).
    pub fn known(&self) -> &Arc<Grid2> {
        &self.known
    }

    /// Known and learned obstacles together.
    pub fn grid(&self) -> &Grid2 {
        &self.combined
    }

    /// The margin in cells around every learned hit.
    pub fn margin_cells(&self) -> i64 {
        self.margin_cells
    }

    /// True if `cell` is occupied because of something learned (not the map).
    pub fn is_learned(&self, cell: Cell) -> bool {
        self.known.contains(cell) && self.cover[self.known.index(cell)] > 0
    }

    /// Cells occupied because of what was learned (hits grown by the margin), row-major order.
    pub fn learned_cells(&self) -> Vec<Cell> {
        (0..self.cover.len())
            .filter(|&i| self.cover[i] > 0)
            .map(|i| self.known.cell(i))
            .collect()
    }

    /// The learned cells alone (grown by the margin) as a grid in the map's frame: what the
    /// map does not know, for a check that has the map's obstacles otherwise (a trajectory
    /// replanned in flight keeps out of both).
    pub fn learned_grid(&self) -> Grid2 {
        let blocked: Vec<bool> = self.cover.iter().map(|&c| c > 0).collect();
        Grid2::new(
            self.known.rows(),
            self.known.cols(),
            blocked,
            self.known.frame(),
        )
        .unwrap_or_else(|_| (*self.known).clone())
    }

    /// How many cells are occupied because of what was learned.
    pub fn learned_count(&self) -> usize {
        self.learned
    }

    /// The cells that hold a sensor hit.
    pub fn hit_cells(&self) -> Vec<Cell> {
        self.hit_list.iter().map(|&i| self.known.cell(i)).collect()
    }

    /// The centres of the learned cells, north/east metres (for logs and pictures).
    pub fn learned_points_ne(&self) -> Vec<[f64; 2]> {
        self.learned_cells()
            .into_iter()
            .map(|c| {
                let (n, e) = self.known.center_ne(c);
                [n, e]
            })
            .collect()
    }

    /// Learns from one reading; returns the cells whose occupancy changed (`true`: now blocked),
    /// in the form [`crate::DStarLite::update_cells`] takes.
    ///
    /// Rays first clear earlier hits they pass through (up to one cell before their own hit, or
    /// to the maximum range when clear), then every hit outside the map's obstacles is added.
    /// Hits in cells the map already blocks teach nothing new and are ignored.
    pub fn apply(&mut self, reading: &ObstacleReading) -> Vec<(Cell, bool)> {
        let mut touched: Vec<(usize, bool)> = Vec::new();
        let cell_m = self.known.frame().cell_m;
        let [pn, pe, _] = reading.position_ned;
        if !(pn.is_finite() && pe.is_finite()) {
            return Vec::new();
        }
        let mut new_hits = BTreeSet::new();
        // Rays only clear hits within their reach: skip the walks when none is near.
        let reach_m = reading.max_range_m.max(0.0) + 2.0 * cell_m;
        let any_near = self.hit_list.iter().any(|&i| {
            let (n, e) = self.known.center_ne(self.known.cell(i));
            (n - pn).abs() <= reach_m && (e - pe).abs() <= reach_m
        });
        let mut clear = BTreeSet::new();
        for (i, r) in reading.ranges.iter().enumerate() {
            let b = reading.bearing_rad(i);
            let (free_m, hit) = match *r {
                SectorRange::Obstacle(d) if d.is_finite() && d >= 0.0 => (d - cell_m, Some(d)),
                SectorRange::Clear if reading.max_range_m.is_finite() => {
                    (reading.max_range_m, None)
                }
                _ => continue,
            };
            if !b.is_finite() {
                continue;
            }
            let (dn, de) = (b.cos(), b.sin());
            // Walk the free part of the ray in quarter cells; a hit cell is cleared when the ray
            // passes through the inner half of it.
            let steps = if !any_near {
                0 // nothing learned within reach: nothing to clear
            } else {
                (free_m.max(0.0) / (cell_m * 0.25)).floor() as usize
            };
            for k in 0..=steps {
                let t = k as f64 * cell_m * 0.25;
                let (n, e) = (pn + t * dn, pe + t * de);
                if let Some(c) = self.known.cell_at_ne(n, e) {
                    let idx = self.known.index(c);
                    if self.is_hit[idx] {
                        let (cn, ce) = self.known.center_ne(c);
                        if (cn - n).abs() <= cell_m * 0.25 && (ce - e).abs() <= cell_m * 0.25 {
                            clear.insert(idx);
                        }
                    }
                }
            }
            if let Some(d) = hit
                && let Some(c) = self.known.cell_at_ne(pn + d * dn, pe + d * de)
                && !self.known.is_blocked(c)
            {
                new_hits.insert(self.known.index(c));
            }
        }
        for idx in clear {
            if !new_hits.contains(&idx) && self.is_hit[idx] {
                self.is_hit[idx] = false;
                self.hit_list.remove(&idx);
                self.cover_around(idx, false, &mut touched);
            }
        }
        for idx in new_hits {
            if !self.is_hit[idx] {
                self.is_hit[idx] = true;
                self.hit_list.insert(idx);
                self.cover_around(idx, true, &mut touched);
            }
        }
        // A cell may have been touched more than once: report its final state if it changed.
        touched.sort_unstable_by_key(|t| t.0);
        touched.dedup_by_key(|t| t.0);
        let mut changed = Vec::new();
        for (idx, was_blocked) in touched {
            let cell = self.known.cell(idx);
            let now = self.known.is_blocked(cell) || self.cover[idx] > 0;
            self.combined.set_blocked(cell, now);
            if now != was_blocked {
                changed.push((cell, now));
            }
        }
        changed
    }

    /// Adds or removes one hit cell's cover; records each touched cell's state before the first
    /// touch.
    fn cover_around(&mut self, hit: usize, add: bool, touched: &mut Vec<(usize, bool)>) {
        let c = self.known.cell(hit);
        let m = self.margin_cells;
        let (r0, c0) = (i64::from(c.row), i64::from(c.col));
        for r in r0 - m..=r0 + m {
            for cc in c0 - m..=c0 + m {
                let Some(cell) = self.known.checked_cell(r, cc) else {
                    continue;
                };
                let idx = self.known.index(cell);
                touched.push((idx, self.combined.is_blocked(cell)));
                let slot = &mut self.cover[idx];
                let was = *slot > 0;
                *slot = if add {
                    slot.saturating_add(1)
                } else {
                    slot.saturating_sub(1)
                };
                match (was, *slot > 0) {
                    (false, true) => self.learned += 1,
                    (true, false) => self.learned -= 1,
                    _ => {}
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use skyplan_cspace::GridFrame;
    use std::f64::consts::FRAC_PI_2;

    /// 40 × 40 cells of 1 m from (0, 0); the cells in `blocked` are the map's.
    fn model(blocked: &[Cell], margin_m: f64) -> WorldModel {
        let mut grid = Grid2::new(40, 40, vec![false; 1600], GridFrame::default()).unwrap();
        for &c in blocked {
            grid.set_blocked(c, true);
        }
        WorldModel::new(Arc::new(grid), margin_m)
    }

    /// Four sectors (N, E, S, W) from `at`.
    fn reading(at: [f64; 2], ranges: [SectorRange; 4]) -> ObstacleReading {
        ObstacleReading {
            time_s: 0.0,
            position_ned: [at[0], at[1], -5.0],
            velocity_ned_m_s: [0.0; 3],
            first_bearing_rad: 0.0,
            increment_rad: FRAC_PI_2,
            min_range_m: 0.2,
            max_range_m: 20.0,
            ranges: ranges.to_vec(),
        }
    }

    use SectorRange::{Clear, Obstacle, Unknown};

    #[test]
    fn a_hit_blocks_its_cell_grown_by_the_margin() {
        let mut w = model(&[], 2.0);
        // 10 m east of (5.5, 5.5): the hit is at (5.5, 15.5), cell (5, 15).
        let changed = w.apply(&reading(
            [5.5, 5.5],
            [Unknown, Obstacle(10.0), Unknown, Unknown],
        ));
        assert_eq!(changed.len(), 25);
        assert!(changed.iter().all(|&(_, b)| b));
        for r in 0..40 {
            for c in 0..40 {
                let inside = (3..=7).contains(&r) && (13..=17).contains(&c);
                assert_eq!(w.grid().is_blocked(Cell::new(r, c)), inside, "({r}, {c})");
                assert_eq!(w.is_learned(Cell::new(r, c)), inside);
            }
        }
        assert_eq!(w.hit_cells(), vec![Cell::new(5, 15)]);
        assert_eq!(w.learned_count(), 25);
        assert_eq!(w.learned_points_ne()[0], [3.5, 13.5]);
        // The same reading again changes nothing.
        assert!(
            w.apply(&reading(
                [5.5, 5.5],
                [Unknown, Obstacle(10.0), Unknown, Unknown]
            ))
            .is_empty()
        );
    }

    #[test]
    fn a_clear_ray_clears_what_was_learned_but_never_the_map() {
        let map_cell = Cell::new(5, 20);
        let mut w = model(&[map_cell], 1.0);
        w.apply(&reading(
            [5.5, 5.5],
            [Unknown, Obstacle(10.0), Unknown, Unknown],
        ));
        assert_eq!(w.learned_count(), 9);
        // Now the sensor sees nothing east within 20 m: the ray passes the old hit and the map's
        // cell at (5, 20).
        let changed = w.apply(&reading([5.5, 5.5], [Unknown, Clear, Unknown, Unknown]));
        assert_eq!(changed.len(), 9);
        assert!(changed.iter().all(|&(_, b)| !b));
        assert_eq!(w.learned_count(), 0);
        assert!(w.grid().is_blocked(map_cell), "the map's obstacle stays");
        assert_eq!(w.grid().blocked_count(), 1);
    }

    #[test]
    fn hits_on_the_maps_obstacles_teach_nothing_and_overlaps_are_counted() {
        let mut w = model(&[Cell::new(5, 15)], 1.0);
        assert!(
            w.apply(&reading(
                [5.5, 5.5],
                [Unknown, Obstacle(10.0), Unknown, Unknown]
            ))
            .is_empty()
        );
        // Two hits two cells apart share a column of their margins.
        let changed = w.apply(&reading(
            [20.5, 5.5],
            [Unknown, Obstacle(10.0), Unknown, Unknown],
        ));
        assert_eq!(changed.len(), 9);
        let changed = w.apply(&reading(
            [22.5, 5.5],
            [Unknown, Obstacle(10.0), Unknown, Unknown],
        ));
        assert_eq!(changed.len(), 6, "the shared row was already blocked");
        assert_eq!(w.learned_count(), 15);
        // A ray from the west through the first hit (row 20) clears it, up to one cell short of
        // a hit at 20 m: the second hit's cover keeps the shared row.
        let changed = w.apply(&reading(
            [20.5, 0.5],
            [Unknown, Obstacle(20.0), Unknown, Unknown],
        ));
        // The old hit (20, 15) is cleared; a new one at (20, 20) is added.
        assert!(w.hit_cells().contains(&Cell::new(20, 20)));
        assert!(!w.hit_cells().contains(&Cell::new(20, 15)));
        assert!(
            w.grid().is_blocked(Cell::new(21, 15)),
            "still covered by the hit at (22, 15)"
        );
        assert!(!w.grid().is_blocked(Cell::new(20, 14)));
        assert!(changed.contains(&(Cell::new(19, 14), false)));
    }
}
