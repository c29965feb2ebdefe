//! The 2D grid of a colliders map at a flight altitude (the FCND `create_grid`, made exact).

use crate::{Grid2, GridError, GridFrame, check_size};
use skyplan_map::colliders::CollidersMap;

/// Parameters of a grid at altitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridSpec {
    /// Flight altitude above home, metres.
    pub alt_m: f64,
    /// Safety margin added around every obstacle (horizontally and vertically), metres.
    pub safety_m: f64,
    /// Cell edge length, metres.
    pub cell_m: f64,
}

impl Default for GridSpec {
    fn default() -> Self {
        Self {
            alt_m: 5.0,
            safety_m: 5.0,
            cell_m: 1.0,
        }
    }
}

impl Grid2 {
    /// The occupancy grid of a colliders map at `spec.alt_m`.
    ///
    /// The origin is `floor(min(north − half_north))`, `floor(min(east − half_east))` (obstacles
    /// without margin, as FCND), the size `ceil((max(north + half_north) − origin) / cell_m)`.
    /// An obstacle counts if its vertical extent grown by the margin contains the altitude
    /// (`top + margin > alt` and `bottom − margin < alt`); it then blocks every cell whose interior
    /// meets the box grown horizontally by the margin (a zero-width box blocks the cell holding it).
    ///
    /// ```
    /// use skyplan_cspace::{Grid2, GridSpec};
    /// let text = "lat0 37.79, lon0 -122.39\n5,5,10,2,2,10\n0,0,2,1,1,2\n12,12,1,1,1,1\n";
    /// let map = skyplan_map::colliders::parse_colliders(text).unwrap();
    /// let spec = GridSpec { alt_m: 10.0, safety_m: 1.0, cell_m: 1.0 };
    /// let grid = Grid2::from_colliders(&map, spec)?;
    /// assert_eq!((grid.rows(), grid.cols()), (14, 14));
    /// assert_eq!(grid.frame().origin_north_m, -1.0);
    /// // Only the tall box counts at 10 m: (2 + 1) * 2 = 6 cells across.
    /// assert_eq!(grid.blocked_count(), 36);
    /// # Ok::<(), skyplan_cspace::GridError>(())
    /// ```
    pub fn from_colliders(map: &CollidersMap, spec: GridSpec) -> Result<Self, GridError> {
        let GridSpec {
            alt_m,
            safety_m,
            cell_m,
        } = spec;
        check_spec(spec)?;
        let fold = |f: fn(f64, f64) -> f64,
                    init: f64,
                    g: &dyn Fn(&skyplan_map::colliders::ObstacleBox) -> f64| {
            map.boxes.iter().map(g).fold(init, f)
        };
        let north_min = fold(f64::min, f64::INFINITY, &|b| b.north_m - b.half_north_m);
        let east_min = fold(f64::min, f64::INFINITY, &|b| b.east_m - b.half_east_m);
        let north_max = fold(f64::max, f64::NEG_INFINITY, &|b| b.north_m + b.half_north_m);
        let east_max = fold(f64::max, f64::NEG_INFINITY, &|b| b.east_m + b.half_east_m);
        let mut grid = Grid2::empty_over([north_min, east_min], [north_max, east_max], cell_m)?;
        let GridFrame {
            origin_north_m: north_min,
            origin_east_m: east_min,
            ..
        } = grid.frame;
        let (rows, cols) = (grid.rows, grid.cols);
        // Half-open cell range [first, last] whose interiors meet [lo, hi] (in cells).
        let span = |lo: f64, hi: f64, n: u32| -> Option<(usize, usize)> {
            let first = lo.floor();
            let last = (hi.ceil() - 1.0).max(first);
            let (first, last) = (first.max(0.0), last.min(f64::from(n) - 1.0));
            (first <= last).then_some((first as usize, last as usize))
        };
        for b in &map.boxes {
            if !b.meets_altitude(alt_m, safety_m) {
                continue;
            }
            let (lo, hi) = b.grown(safety_m);
            let north_lo = (lo[0] - north_min) / cell_m;
            let north_hi = (hi[0] - north_min) / cell_m;
            let east_lo = (lo[1] - east_min) / cell_m;
            let east_hi = (hi[1] - east_min) / cell_m;
            let (Some((r0, r1)), Some((c0, c1))) =
                (span(north_lo, north_hi, rows), span(east_lo, east_hi, cols))
            else {
                continue;
            };
            for r in r0..=r1 {
                let start = r * cols as usize;
                grid.blocked[start + c0..=start + c1].fill(true);
            }
        }
        grid.forget_count();
        Ok(grid)
    }

    /// The free grid laid out over the extent `[lo, hi]` (`[north, east]`, metres) as every map
    /// kind's grid is: origin `floor(lo)`, size `ceil((hi − origin) / cell_m)` (at least 1 × 1),
    /// refused when larger than [`crate::MAX_CELLS`]. `cell_m` must have passed [`check_spec`].
    pub(crate) fn empty_over(lo: [f64; 2], hi: [f64; 2], cell_m: f64) -> Result<Self, GridError> {
        let north_min = lo[0].floor();
        let east_min = lo[1].floor();
        let rows_f = ((hi[0] - north_min) / cell_m).ceil().max(1.0);
        let cols_f = ((hi[1] - east_min) / cell_m).ceil().max(1.0);
        if !(rows_f.is_finite() && cols_f.is_finite()) || rows_f * cols_f > crate::MAX_CELLS as f64
        {
            return Err(GridError::TooLarge {
                rows: rows_f as u64,
                cols: cols_f as u64,
            });
        }
        let (rows, cols) = (rows_f as u32, cols_f as u32);
        check_size(u64::from(rows), u64::from(cols))?;
        Grid2::new(
            rows,
            cols,
            vec![false; rows as usize * cols as usize],
            GridFrame {
                origin_north_m: north_min,
                origin_east_m: east_min,
                cell_m,
            },
        )
    }
}

/// Refuses a non-finite altitude, a negative or non-finite margin, a cell size ≤ 0.
pub(crate) fn check_spec(spec: GridSpec) -> Result<(), GridError> {
    let GridSpec {
        alt_m,
        safety_m,
        cell_m,
    } = spec;
    if !alt_m.is_finite() {
        return Err(GridError::BadParameter {
            name: "alt_m",
            value: alt_m,
            expected: "a finite altitude",
        });
    }
    if !(safety_m.is_finite() && safety_m >= 0.0) {
        return Err(GridError::BadParameter {
            name: "safety_m",
            value: safety_m,
            expected: "a finite margin ≥ 0",
        });
    }
    if !(cell_m.is_finite() && cell_m > 0.0) {
        return Err(GridError::BadParameter {
            name: "cell_m",
            value: cell_m,
            expected: "a finite cell size > 0",
        });
    }
    Ok(())
}
