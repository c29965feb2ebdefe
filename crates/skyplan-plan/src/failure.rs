//! Why no plan was made, with kinds as in OMPL's `PlannerStatus`.

use serde::Serialize;
use std::fmt;

/// The kind of a failure. Front ends map kinds to their own codes in one place (the CLI's exit
/// codes, the server's HTTP statuses, the Python exception classes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// The start is off the map, inside an obstacle or its margin, or not expressible.
    InvalidStart,
    /// The goal is off the map, inside an obstacle or its margin, or not expressible.
    InvalidGoal,
    /// Valid request, but the start and goal are not connected.
    NoPath,
    /// The planner's budget ran out before it found a path.
    Timeout,
    /// A route was found, but no safe corridor for a trajectory around it (too tight for the
    /// margin somewhere; the message says where).
    NoCorridor,
    /// The request (or the map) is invalid: a value out of range, a planner that does not take
    /// this map, a broken roadmap file.
    BadRequest,
    /// A post-condition failed (for example the final re-check): a bug, reported, never flown.
    Internal,
}

impl FailureKind {
    /// The snake-case name used in JSON (`invalid_start`, `no_path`, …).
    pub fn name(self) -> &'static str {
        match self {
            FailureKind::InvalidStart => "invalid_start",
            FailureKind::InvalidGoal => "invalid_goal",
            FailureKind::NoPath => "no_path",
            FailureKind::Timeout => "timeout",
            FailureKind::NoCorridor => "no_corridor",
            FailureKind::BadRequest => "bad_request",
            FailureKind::Internal => "internal",
        }
    }

    /// True for "valid input, no route" (no path, timeout, or no corridor for a trajectory).
    pub fn is_no_route(self) -> bool {
        matches!(
            self,
            FailureKind::NoPath | FailureKind::Timeout | FailureKind::NoCorridor
        )
    }

    /// True for input the user must change (start, goal or request).
    pub fn is_bad_input(self) -> bool {
        matches!(
            self,
            FailureKind::InvalidStart | FailureKind::InvalidGoal | FailureKind::BadRequest
        )
    }
}

impl fmt::Display for FailureKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A failed plan: its kind and the message users see.
///
/// ```
/// use skyplan_plan::{FailureKind, PlanFailure};
/// let f = PlanFailure::new(FailureKind::NoPath, "goal is unreachable");
/// assert_eq!(f.to_string(), "goal is unreachable");
/// assert!(f.kind.is_no_route());
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[error("{message}")]
pub struct PlanFailure {
    /// What kind of failure.
    pub kind: FailureKind,
    /// What is wrong and, where it helps, what to do about it.
    pub message: String,
}

impl PlanFailure {
    /// A failure of `kind` with `message`.
    pub fn new(kind: FailureKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            message: message.into(),
        }
    }

    /// A bad request.
    pub fn bad_request(message: impl Into<String>) -> Self {
        Self::new(FailureKind::BadRequest, message)
    }

    /// An internal error (a failed post-condition).
    pub fn internal(message: impl Into<String>) -> Self {
        Self::new(FailureKind::Internal, message)
    }
}
