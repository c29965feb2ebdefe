//! Exit codes: scripts tell bad input from "no path" from success.

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
        })
    }
}

/// With `--json`, scripts get one JSON object on stdout for failures too:
/// `{"status": "bad_input" | "no_path" | "error", "error": "…"}`.
pub fn print_json_failure<T>(result: &Result<T>) {
    if let Err(f) = result {
        let status = match f.kind {
            Kind::NoPath => "no_path",
            Kind::BadInput => "bad_input",
            Kind::Runtime => "error",
        };
        println!(
            "{}",
            serde_json::json!({ "status": status, "error": format!("{:#}", f.error) })
        );
    }
}

/// A bad-input failure from a message.
pub fn bad_input(message: impl std::fmt::Display) -> Failure {
    Failure {
        kind: Kind::BadInput,
        error: anyhow::anyhow!("{message}"),
    }
}
