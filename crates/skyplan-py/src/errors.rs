//! The facade's failure kinds as Python exceptions.
//!
//! The classes live in `skyplan/_errors.py` (so that `InvalidStart`, `InvalidGoal` and
//! `BadInput` can also be `ValueError`s); this module raises them by name.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyType;
use skyplan_plan::{FailureKind, PlanFailure};

/// The exception class of a failure kind (`bad_request` is `BadInput`, `internal` the base
/// class `PlanError`).
fn class_name(kind: FailureKind) -> &'static str {
    match kind {
        FailureKind::InvalidStart => "InvalidStart",
        FailureKind::InvalidGoal => "InvalidGoal",
        FailureKind::NoPath => "NoPath",
        FailureKind::Timeout => "Timeout",
        FailureKind::NoCorridor => "NoPath",
        FailureKind::BadRequest => "BadInput",
        FailureKind::Internal => "PlanError",
    }
}

/// A failure as the Python exception of its kind, carrying the facade's message.
pub(crate) fn to_py(failure: PlanFailure) -> PyErr {
    Python::attach(|py| {
        let class = py
            .import("skyplan._errors")
            .and_then(|m| m.getattr(class_name(failure.kind)))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
        match class {
            Ok(ty) => PyErr::from_type(ty, failure.message),
            // Only if the package's Python half is missing (the bare extension imported alone).
            Err(_) => PyRuntimeError::new_err(format!("{}: {}", failure.kind, failure.message)),
        }
    })
}

/// `BadInput` with a message.
pub(crate) fn bad_input(message: impl Into<String>) -> PyErr {
    to_py(PlanFailure::bad_request(message))
}

/// An exception of `kind` with a message.
pub(crate) fn fail(kind: FailureKind, message: impl Into<String>) -> PyErr {
    to_py(PlanFailure::new(kind, message))
}
