//! # skyplan for Python
//!
//! The extension module `skyplan._skyplan` behind `import skyplan` (the package's Python half,
//! `python/skyplan/`, re-exports it and holds the exception classes and the type stubs).
//!
//! * [`fcnd`]: drop-ins for FCND's `planning_utils.py` — `create_grid` (FCND's own rules, bit
//!   for bit), `a_star` (exactly optimal through [`skyplan_plan::CellSearch`]), `prune_path`,
//!   `bresenham_prune`.
//! * [`weighted`]: `astar_path` with pyastar2d's contract (weights ≥ 1, `inf` walls), its
//!   heuristics (`heuristic_override`) and its paths, ties included.
//! * [`planner`]: `planners()` (the registry's rows), `Planner` (a world loaded once, sessions
//!   of the planning API) and `Plan`.
//! * [`airspace`]: `Airspace` — a shared airspace store; flights reserved as operational
//!   intents one at a time (`reserve`, the departure shifted or the route re-planned in space
//!   and time) or as a fleet (`fleet`), as `POST /api/intents` and `skyplan fleet` do.
//! * [`arrays`]: numpy arrays and Python values in, checked; every failure a Python exception.
//!
//! Everything planning-related goes through the planning API crate `skyplan-plan`; the GIL is
//! released while Rust computes (`Python::detach`), so Python threads plan in parallel.

use pyo3::prelude::*;

mod airspace;
mod arrays;
mod errors;
mod fcnd;
mod planner;
mod weighted;

/// skyplan's compiled core; import `skyplan`, not this module.
#[pymodule]
fn _skyplan(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(fcnd::create_grid, m)?)?;
    m.add_function(wrap_pyfunction!(fcnd::a_star, m)?)?;
    m.add_function(wrap_pyfunction!(fcnd::prune_path, m)?)?;
    m.add_function(wrap_pyfunction!(fcnd::bresenham_prune, m)?)?;
    m.add_function(wrap_pyfunction!(weighted::astar_path, m)?)?;
    m.add_function(wrap_pyfunction!(planner::planners, m)?)?;
    m.add_class::<planner::Planner>()?;
    m.add_class::<planner::Plan>()?;
    m.add_class::<airspace::Airspace>()?;
    Ok(())
}
