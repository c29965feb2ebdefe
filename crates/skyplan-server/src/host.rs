//! DNS-rebinding protection: a server bound to a loopback address answers only requests whose
//! `Host` header names that address or `localhost` (with or without the port). A page on
//! another site whose name was re-pointed at 127.0.0.1 sends its own name as `Host` and gets
//! 403. A server bound to any other address (`--bind 0.0.0.0:8080`) was opened to the network
//! on purpose and checks nothing.

use axum::Router;
use axum::extract::{Request, State};
use axum::http::{StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use std::net::SocketAddr;

/// Whether a request with this `Host` header (`None`: none sent) may be answered by a server
/// bound to `bound`.
///
/// ```
/// use skyplan_server::host_allowed;
/// let bound = "127.0.0.1:8080".parse().unwrap();
/// assert!(host_allowed(Some("127.0.0.1:8080"), bound));
/// assert!(host_allowed(Some("localhost:8080"), bound));
/// assert!(host_allowed(Some("LOCALHOST"), bound));
/// assert!(!host_allowed(Some("attacker.example:8080"), bound));
/// assert!(!host_allowed(Some("localhost:9999"), bound));
/// assert!(!host_allowed(None, bound));
/// assert!(host_allowed(Some("anything"), "0.0.0.0:8080".parse().unwrap()));
/// ```
pub fn host_allowed(host: Option<&str>, bound: SocketAddr) -> bool {
    if !bound.ip().is_loopback() {
        return true;
    }
    let Some(host) = host else {
        return false;
    };
    let host = host.trim().to_ascii_lowercase();
    // Split off the port: "[::1]:8080", "127.0.0.1:8080", "localhost:8080", or no port.
    let (name, port) = match host.rsplit_once(':') {
        Some((n, p)) if !n.is_empty() && (n.ends_with(']') || !n.contains(':')) => (n, Some(p)),
        _ => (host.as_str(), None),
    };
    if port.is_some_and(|p| p.parse::<u16>().ok() != Some(bound.port())) {
        return false;
    }
    let name = name.trim_start_matches('[').trim_end_matches(']');
    name == "localhost"
        || name
            .parse::<std::net::IpAddr>()
            .is_ok_and(|ip| ip == bound.ip())
}

/// `router` with the `Host` check of [`host_allowed`] for a server bound to `bound`.
pub fn with_host_check(router: Router, bound: SocketAddr) -> Router {
    router.layer(axum::middleware::from_fn_with_state(bound, check))
}

async fn check(State(bound): State<SocketAddr>, request: Request, next: Next) -> Response {
    let host = request
        .headers()
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .map(str::to_string);
    if host_allowed(host.as_deref(), bound) {
        return next.run(request).await;
    }
    let message = format!(
        "Host {} is not this server: a server bound to {bound} answers only Host {bound} or localhost:{} (DNS-rebinding protection)",
        host.as_deref().unwrap_or("(none)"),
        bound.port()
    );
    (
        StatusCode::FORBIDDEN,
        axum::Json(
            serde_json::json!({ "status": "error", "kind": "forbidden_host", "message": message }),
        ),
    )
        .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::body::Body;
    use axum::routing::get;
    use tower::ServiceExt;

    async fn status(bound: &str, host: Option<&str>) -> StatusCode {
        let app = with_host_check(
            Router::new().route("/", get(|| async { "ok" })),
            bound.parse().unwrap(),
        );
        let mut req = Request::builder().uri("/");
        if let Some(h) = host {
            req = req.header(header::HOST, h);
        }
        app.oneshot(req.body(Body::empty()).unwrap())
            .await
            .unwrap()
            .status()
    }

    #[tokio::test]
    async fn loopback_servers_answer_only_their_own_host() {
        for ok in ["127.0.0.1:8080", "localhost:8080", "localhost", "127.0.0.1"] {
            assert_eq!(
                status("127.0.0.1:8080", Some(ok)).await,
                StatusCode::OK,
                "{ok}"
            );
        }
        for bad in [
            "evil.example",
            "evil.example:8080",
            "127.0.0.2:8080",
            "localhost:80",
            "localhost.evil.example:8080",
        ] {
            assert_eq!(
                status("127.0.0.1:8080", Some(bad)).await,
                StatusCode::FORBIDDEN,
                "{bad}"
            );
        }
        assert_eq!(status("127.0.0.1:8080", None).await, StatusCode::FORBIDDEN);
        assert_eq!(
            status("[::1]:8080", Some("[::1]:8080")).await,
            StatusCode::OK
        );
        assert_eq!(
            status("[::1]:8080", Some("127.0.0.1:8080")).await,
            StatusCode::FORBIDDEN
        );
        // Bound to every interface on purpose: no check.
        assert_eq!(
            status("0.0.0.0:8080", Some("evil.example")).await,
            StatusCode::OK
        );
    }
}
