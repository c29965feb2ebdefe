//! Nav2-style cost maps: obstacles inflated by an exponentially decaying cost.

use crate::NavError;
use crate::edt::distance_transform;
use skyplan_cspace::{Cell, Grid2, GridFrame};

/// Cost of an obstacle cell (Nav2 `LETHAL_OBSTACLE`).
pub const LETHAL: u8 = 254;
/// Cost of a cell whose centre is within the inscribed radius of an obstacle
/// (Nav2 `INSCRIBED_INFLATED_OBSTACLE`): the vehicle's footprint would touch it.
pub const INSCRIBED: u8 = 253;
/// Largest cost of a cell the vehicle may enter (`INSCRIBED − 1`), the scale of the decay.
pub const MAX_NON_OBSTACLE: u8 = 252;

/// Inflation parameters, as Nav2's inflation layer names them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inflation {
    /// Radius of the circle inscribed in the vehicle's footprint, metres.
    pub inscribed_radius_m: f64,
    /// Distance from an obstacle up to which costs are raised, metres.
    pub inflation_radius_m: f64,
    /// Decay rate `k` of `252·exp(−k·(d − r_inscribed))`, per metre.
    pub cost_scaling_factor: f64,
}

impl Default for Inflation {
    /// Nav2's defaults: no inscribed radius, 0.55 m inflation radius, scaling factor 10; for a
    /// drone grid of 1 m cells a wider cushion is usually wanted (see the CLI's defaults).
    fn default() -> Self {
        Self {
            inscribed_radius_m: 0.0,
            inflation_radius_m: 0.55,
            cost_scaling_factor: 10.0,
        }
    }
}

impl Inflation {
    fn validate(&self) -> Result<(), NavError> {
        let bad = |name, value, expected| {
            Err(NavError::BadParameter {
                name,
                value,
                expected,
            })
        };
        if !(self.inscribed_radius_m.is_finite() && self.inscribed_radius_m >= 0.0) {
            return bad(
                "inscribed_radius_m",
                self.inscribed_radius_m,
                "a finite radius ≥ 0",
            );
        }
        if !(self.inflation_radius_m.is_finite() && self.inflation_radius_m >= 0.0) {
            return bad(
                "inflation_radius_m",
                self.inflation_radius_m,
                "a finite radius ≥ 0",
            );
        }
        if !(self.cost_scaling_factor.is_finite() && self.cost_scaling_factor >= 0.0) {
            return bad(
                "cost_scaling_factor",
                self.cost_scaling_factor,
                "a finite factor ≥ 0",
            );
        }
        Ok(())
    }

    /// The cost of a cell whose centre is `distance_m` from the nearest obstacle cell's centre:
    /// [`LETHAL`] at 0, [`INSCRIBED`] up to the inscribed radius, then
    /// `⌊252·exp(−k·(d − r_inscribed))⌋` up to the inflation radius, 0 beyond (as Nav2's
    /// `InflationLayer::computeCost`, which truncates to an integer).
    ///
    /// ```
    /// use skyplan_navfn::Inflation;
    /// let p = Inflation { inscribed_radius_m: 1.0, inflation_radius_m: 3.0, cost_scaling_factor: 3.0 };
    /// assert_eq!(p.cost_at(0.0), 254);
    /// assert_eq!(p.cost_at(1.0), 253);
    /// assert_eq!(p.cost_at(2.0), 12);   // 252·e⁻³ = 12.55
    /// assert_eq!(p.cost_at(3.5), 0);
    /// ```
    pub fn cost_at(&self, distance_m: f64) -> u8 {
        if distance_m <= 0.0 {
            LETHAL
        } else if distance_m <= self.inscribed_radius_m {
            INSCRIBED
        } else if distance_m <= self.inflation_radius_m {
            let factor = (-self.cost_scaling_factor * (distance_m - self.inscribed_radius_m)).exp();
            (f64::from(MAX_NON_OBSTACLE) * factor) as u8
        } else {
            0
        }
    }
}

/// A cost grid over a [`Grid2`]: one cost in `0..=254` per cell, and each cell's clearance.
#[derive(Debug, Clone, PartialEq)]
pub struct Costmap {
    rows: u32,
    cols: u32,
    frame: GridFrame,
    costs: Vec<u8>,
    clearance_cells: Vec<f64>,
}

impl Costmap {
    /// Inflates the obstacles of `grid`: an exact Euclidean distance transform, then
    /// [`Inflation::cost_at`] of every cell's distance in metres (cells × `cell_m`).
    ///
    /// ```
    /// use skyplan_cspace::{Cell, Grid2};
    /// use skyplan_navfn::{Costmap, Inflation, LETHAL, INSCRIBED};
    /// let grid = Grid2::from_ascii("#....")?;
    /// let p = Inflation { inscribed_radius_m: 1.0, inflation_radius_m: 3.0, cost_scaling_factor: 3.0 };
    /// let costmap = Costmap::inflate(&grid, p)?;
    /// assert_eq!(costmap.costs(), &[LETHAL, INSCRIBED, 12, 0, 0]); // 252·e⁻⁶ = 0.62 → 0
    /// assert_eq!(costmap.clearance_m(Cell::new(0, 4)), Some(4.0));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn inflate(grid: &Grid2, params: Inflation) -> Result<Self, NavError> {
        params.validate()?;
        let clearance_cells = distance_transform(grid);
        let cell_m = grid.frame().cell_m;
        let costs = clearance_cells
            .iter()
            .map(|&d| params.cost_at(d * cell_m))
            .collect();
        Ok(Self {
            rows: grid.rows(),
            cols: grid.cols(),
            frame: grid.frame(),
            costs,
            clearance_cells,
        })
    }

    /// Number of rows.
    pub fn rows(&self) -> u32 {
        self.rows
    }
    /// Number of columns.
    pub fn cols(&self) -> u32 {
        self.cols
    }
    /// Placement in the local frame.
    pub fn frame(&self) -> GridFrame {
        self.frame
    }
    /// Row-major costs.
    pub fn costs(&self) -> &[u8] {
        &self.costs
    }
    /// The cost of a cell (`None` off the grid).
    pub fn cost(&self, cell: Cell) -> Option<u8> {
        self.index(cell).map(|i| self.costs[i])
    }
    /// Row-major distances in cells from each cell centre to the nearest obstacle cell centre.
    pub fn clearance_cells(&self) -> &[f64] {
        &self.clearance_cells
    }
    /// A cell's clearance in metres (`f64::INFINITY` without obstacles; `None` off the grid).
    pub fn clearance_m(&self, cell: Cell) -> Option<f64> {
        self.index(cell)
            .map(|i| self.clearance_cells[i] * self.frame.cell_m)
    }
    fn index(&self, cell: Cell) -> Option<usize> {
        (cell.row < self.rows && cell.col < self.cols)
            .then(|| cell.row as usize * self.cols as usize + cell.col as usize)
    }
    /// The grid a vehicle may move in: cells of cost ≥ [`INSCRIBED`] are blocked.
    pub fn passable_grid(&self) -> Grid2 {
        let blocked = self.costs.iter().map(|&c| c >= INSCRIBED).collect();
        // Same size as the grid it was inflated from, so this cannot fail.
        Grid2::new(self.rows, self.cols, blocked, self.frame)
            .unwrap_or_else(|_| unreachable!("a costmap has the size of a valid grid"))
    }
    /// Costs scaled to `0..=255` for display: `cost · 255 / 254`.
    pub fn normalised(&self) -> Vec<u8> {
        self.costs
            .iter()
            .map(|&c| (u16::from(c) * 255 / u16::from(LETHAL)) as u8)
            .collect()
    }
}
