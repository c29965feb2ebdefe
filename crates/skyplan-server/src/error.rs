//! [`ApiError`]: every error response, and the one place where failure kinds become HTTP
//! statuses.

use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use skyplan_plan::{FailureKind, PlanFailure};

/// What went wrong, as the `kind` of an error body. The planning API's kinds
/// (`invalid_start`, `invalid_goal`, `no_path`, `timeout`, `bad_request`, `internal`) keep their
/// names; the server adds its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// A failure of the planning API.
    Plan(FailureKind),
    /// The request body is larger than the limit (413).
    TooLarge,
    /// The request body is not declared `application/json` (415). Browsers cannot send JSON to
    /// another origin without asking first, so other pages cannot make this server plan.
    NotJson,
    /// Every planning worker (or event stream slot) is busy (503).
    Busy,
    /// The request's time budget ran out while it was planned (504).
    OverBudget,
    /// The request waited in the queue until it could no longer finish within its budget (504).
    QueueTimeout,
    /// No such path (404).
    NotFound,
    /// The path exists, the method does not (405).
    MethodNotAllowed,
    /// No departure of the window is free of the stored intents of equal or higher priority
    /// (409); the body names them (`conflicts`).
    Conflict,
    /// The airspace store could not be opened or failed (503).
    StoreUnavailable,
}

impl ErrorKind {
    /// The snake-case name in the error body.
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::Plan(k) => k.name(),
            ErrorKind::TooLarge => "too_large",
            ErrorKind::NotJson => "not_json",
            ErrorKind::Busy => "busy",
            ErrorKind::OverBudget => "over_budget",
            ErrorKind::QueueTimeout => "queue_timeout",
            ErrorKind::NotFound => "not_found",
            ErrorKind::MethodNotAllowed => "method_not_allowed",
            ErrorKind::Conflict => "conflict",
            ErrorKind::StoreUnavailable => "store_unavailable",
        }
    }

    /// The HTTP status: the only mapping from kinds to statuses in the server.
    ///
    /// | kind | status |
    /// |---|---|
    /// | `bad_request` (malformed JSON, unknown field, value out of range) | 400 |
    /// | `invalid_start`, `invalid_goal`, `no_path`, `timeout` (valid request, no route) | 422 |
    /// | `internal` | 500 |
    /// | `too_large` | 413 |
    /// | `not_json` | 415 |
    /// | `conflict` | 409 |
    /// | `busy`, `store_unavailable` | 503 |
    /// | `over_budget`, `queue_timeout` | 504 |
    pub fn status(self) -> StatusCode {
        match self {
            ErrorKind::Plan(FailureKind::BadRequest) => StatusCode::BAD_REQUEST,
            ErrorKind::Plan(
                FailureKind::InvalidStart
                | FailureKind::InvalidGoal
                | FailureKind::NoPath
                | FailureKind::Timeout
                | FailureKind::NoCorridor,
            ) => StatusCode::UNPROCESSABLE_ENTITY,
            ErrorKind::Plan(FailureKind::Internal) => StatusCode::INTERNAL_SERVER_ERROR,
            ErrorKind::TooLarge => StatusCode::PAYLOAD_TOO_LARGE,
            ErrorKind::NotJson => StatusCode::UNSUPPORTED_MEDIA_TYPE,
            ErrorKind::Busy | ErrorKind::StoreUnavailable => StatusCode::SERVICE_UNAVAILABLE,
            ErrorKind::Conflict => StatusCode::CONFLICT,
            ErrorKind::OverBudget | ErrorKind::QueueTimeout => StatusCode::GATEWAY_TIMEOUT,
            ErrorKind::NotFound => StatusCode::NOT_FOUND,
            ErrorKind::MethodNotAllowed => StatusCode::METHOD_NOT_ALLOWED,
        }
    }
}

/// An error response: `{"status": "error", "kind": "…", "message": "…"}` with the kind's status.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct ApiError {
    /// What kind of error.
    pub kind: ErrorKind,
    /// What is wrong, for people.
    pub message: String,
    /// Seconds after which a retry may succeed, sent as `Retry-After` with a 503 (1 if unset).
    pub retry_after_s: Option<u64>,
    /// The intents in the way (`conflict`), sent as `conflicts`.
    pub conflicts: Option<Vec<skyplan_airspace::IntentRef>>,
}

impl ApiError {
    /// An error of `kind`.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            message: message.into(),
            retry_after_s: None,
            conflicts: None,
        }
    }

    /// The same error naming the intents in the way.
    pub fn with_conflicts(mut self, conflicts: Vec<skyplan_airspace::IntentRef>) -> Self {
        self.conflicts = Some(conflicts);
        self
    }

    /// The same error with a `Retry-After` of `seconds` (sent with a 503).
    pub fn with_retry_after(mut self, seconds: u64) -> Self {
        self.retry_after_s = Some(seconds);
        self
    }

    /// A bad request (400).
    pub fn bad_request(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::Plan(FailureKind::BadRequest), message)
    }

    /// An internal error (500): a bug.
    pub fn internal(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::Plan(FailureKind::Internal), message)
    }

    /// The JSON body.
    pub fn body(&self) -> serde_json::Value {
        let mut body = serde_json::json!({
            "status": "error",
            "kind": self.kind.name(),
            "message": self.message,
        });
        if let Some(c) = &self.conflicts {
            body["conflicts"] = serde_json::json!(c);
        }
        body
    }
}

impl From<PlanFailure> for ApiError {
    fn from(f: PlanFailure) -> Self {
        Self::new(ErrorKind::Plan(f.kind), f.message)
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let mut response = (self.kind.status(), axum::Json(self.body())).into_response();
        if self.kind == ErrorKind::Busy {
            response.headers_mut().insert(
                axum::http::header::RETRY_AFTER,
                axum::http::HeaderValue::from(self.retry_after_s.unwrap_or(1)),
            );
        }
        response
    }
}
