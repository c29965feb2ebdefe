//! Exit codes: scripts tell bad input from "no path" from success. The one place where the
//! planning API's failure kinds become exit codes.

use skyplan_plan::{FailureKind, PlanFailure};

/// What kind of failure ended the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Files could not be written, a check failed, or another runtime error.
    Runtime,
    /// The input (arguments, config, map, positions) is invalid.
    BadInput,
    /// The input is valid but there is no path.
    NoPath,
}

impl Kind {
    /// The process exit code: 1 runtime, 2 bad input (as clap's usage errors), 3 no path.
    pub fn code(self) -> u8 {
        match self {
            Kind::Runtime => 1,
            Kind::BadInput => 2,
            Kind::NoPath => 3,
        }
    }
}

/// An error with its exit code.
#[derive(Debug)]
pub struct Failure {
    pub kind: Kind,
    pub error: anyhow::Error,
    /// The planning API's kind, when the failure came from it (for `--json`).
    pub plan_kind: Option<FailureKind>,
}

pub type Result<T> = std::result::Result<T, Failure>;

/// Attaches an exit kind to any error.
pub trait Classify<T> {
    fn or_exit(self, kind: Kind) -> Result<T>;
}

impl<T, E: Into<anyhow::Error>> Classify<T> for std::result::Result<T, E> {
    fn or_exit(self, kind: Kind) -> Result<T> {
        self.map_err(|e| Failure {
            kind,
            error: e.into(),
            plan_kind: None,
        })
    }
}

impl From<PlanFailure> for Failure {
    fn from(f: PlanFailure) -> Self {
        let kind = match f.kind {
            FailureKind::InvalidStart | FailureKind::InvalidGoal | FailureKind::BadRequest => {
                Kind::BadInput
            }
            FailureKind::NoPath | FailureKind::Timeout | FailureKind::NoCorridor => Kind::NoPath,
            FailureKind::Internal => Kind::Runtime,
        };
        Failure {
            kind,
            plan_kind: Some(f.kind),
            error: anyhow::anyhow!(skyplan_plan::cli::in_cli_words(&f.message)),
        }
    }
}

/// With `--json`, scripts get one JSON object on stdout for failures too, in the HTTP API's
/// shape: `{"status": "error", "kind": "invalid_goal" | "no_path" | "bad_request" | …, "message":
/// "…"}` (the planning failure's kind; `bad_request` for other bad input, `runtime` for a
/// runtime error such as an unwritable file). Returns the result as it was.
pub fn print_json_failure<T>(json: bool, result: Result<T>) -> Result<T> {
    if let (true, Err(f)) = (json, &result) {
        let kind = match (f.plan_kind, f.kind) {
            (Some(k), _) => serde_json::json!(k),
            (None, Kind::BadInput) => serde_json::json!("bad_request"),
            (None, Kind::NoPath) => serde_json::json!("no_path"),
            (None, Kind::Runtime) => serde_json::json!("runtime"),
        };
        println!(
            "{}",
            serde_json::json!({ "status": "error", "kind": kind, "message": format!("{:#}", f.error) })
        );
    }
    result
}

impl Failure {
    /// A failure of `kind` from a message.
    pub fn new(kind: Kind, message: impl std::fmt::Display) -> Self {
        Failure {
            kind,
            error: anyhow::anyhow!("{message}"),
            plan_kind: None,
        }
    }
}

/// A bad-input failure from a message.
pub fn bad_input(message: impl std::fmt::Display) -> Failure {
    Failure::new(Kind::BadInput, message)
}

/// A runtime failure from a message.
pub fn runtime(message: impl std::fmt::Display) -> Failure {
    Failure::new(Kind::Runtime, message)
}

impl From<skyplan_flyer::runner::RunError> for Failure {
    fn from(e: skyplan_flyer::runner::RunError) -> Self {
        use skyplan_flyer::runner::RunError;
        match e {
            RunError::BadInput(m) => bad_input(m),
            RunError::Plan(f) => f.into(),
            // Transparent over the link's errors: their causes stay in the chain.
            other => Failure {
                kind: Kind::Runtime,
                error: other.into(),
                plan_kind: None,
            },
        }
    }
}
