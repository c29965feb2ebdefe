//! Navigation functions for skyplan: the wavefront and cost-map traditions of grid planning.
//!
//! * [`distance_field`]: a field of distances *to the goal* over every free cell, by BFS
//!   ([`FieldMetric::Steps`], the classic wavefront) or by Dijkstra with octile lengths
//!   ([`FieldMetric::Length`]), under a [`MoveModel`] (4-connected, or 8-connected with or without
//!   corner cutting). [`DistanceField::descend`] follows its gradient from any start to the goal.
//! * [`distance_transform`]: the exact Euclidean distance transform (Felzenszwalb–Huttenlocher,
//!   linear time) and [`Costmap::inflate`]: Nav2-style inflation (lethal, inscribed, then
//!   `252·exp(−k·(d − r_inscribed))` up to the inflation radius).
//! * [`cost_search`] and [`cost_to_go`]: A\*/Dijkstra and the cost-to-go field minimising
//!   length + weight · cost on a [`Costmap`]; [`navigate`] moves step by step down that field
//!   through a list of targets, which may change mid-ride.
//! * [`show`]: the workspace, the distance matrix and the path as aligned text.
//!
//! Rows count north (row 0 is the southern edge), columns east, as everywhere in skyplan; all
//! distances here are in cells unless a name says `_m`.
//!
//! ```
//! use skyplan_cspace::{Cell, Grid2};
//! use skyplan_navfn::{distance_field, FieldMetric};
//! use skyplan_search::MoveModel;
//! // A U-shaped wall: the path has to go around it.
//! let grid = Grid2::from_ascii(".....\n.#.#.\n.#.#.\n.###.\n.....")?;
//! let field = distance_field(&grid, Cell::new(2, 2), MoveModel::FourConnected, FieldMetric::Steps)?;
//! let path = field.descend(Cell::new(4, 2))?;
//! assert_eq!(path.cells.first(), Some(&Cell::new(4, 2)));
//! assert_eq!(path.cells.last(), Some(&Cell::new(2, 2)));
//! assert_eq!(path.straight_moves, 10); // up around the wall and back down into the U
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod cost_search;
mod edt;
mod field;
mod inflation;
mod moves;
mod navigate;
pub mod show;

pub use cost_search::{CostPath, CostToGo, cost_search, cost_to_go};
pub use edt::distance_transform;
pub use field::{Descent, DistanceField, FieldMetric, distance_field};
pub use inflation::{Costmap, INSCRIBED, Inflation, LETHAL, MAX_NON_OBSTACLE};
pub use navigate::{NavLeg, NavRequest, NavRun, TargetChange, navigate};

pub use skyplan_search::MoveModel;

use skyplan_cspace::{Cell, OutsideGrid};

/// Which end of a query an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endpoint {
    /// The source (start, where the vehicle is).
    Source,
    /// The destination (goal, target).
    Destination,
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Endpoint::Source => "source",
            Endpoint::Destination => "destination",
        })
    }
}

/// Why a field, a descent or a search has no answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NavError {
    /// An endpoint lies outside the grid.
    #[error("the {which} {outside}")]
    Outside {
        /// Which endpoint.
        which: Endpoint,
        /// The cell and the grid's size.
        outside: OutsideGrid,
    },
    /// An endpoint is on an obstacle (or, on a cost map, within the inscribed radius of one).
    #[error("the {which} (row {}, col {}) is at an obstacle", .cell.row, .cell.col)]
    AtObstacle {
        /// Which endpoint.
        which: Endpoint,
        /// The cell.
        cell: Cell,
    },
    /// The destination cannot be reached from the source.
    #[error(
        "path could not be found: the destination (row {}, col {}) is unreachable from the source (row {}, col {})",
        .destination_cell.row, .destination_cell.col, .source_cell.row, .source_cell.col
    )]
    Unreachable {
        /// The source cell.
        source_cell: Cell,
        /// The destination cell.
        destination_cell: Cell,
    },
    /// Parameters out of range.
    #[error("{name} = {value}: expected {expected}")]
    BadParameter {
        /// Parameter name, with its unit.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
    /// Two inputs of different sizes.
    #[error("size mismatch: {what}")]
    SizeMismatch {
        /// What does not match.
        what: &'static str,
    },
}
