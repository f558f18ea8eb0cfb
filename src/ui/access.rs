//! Who may use the web view: checked on every HTTP request (the page, `/state.json`,
//! `/hello.json` and the WebSocket) before any handler runs.
//!
//! - **Host** (DNS rebinding): a page on `attacker.example` whose name the attacker re-points
//!   at 127.0.0.1 reaches this server as its own origin, so comparing `Origin` with `Host` is
//!   not enough: the `Host` must name this server. Accepted: a loopback literal (127.0.0.0/8,
//!   `[::1]`), `localhost`, or the bound address (with or without its port); on a wildcard
//!   bind (`0.0.0.0`, `[::]`) any IP literal, since a rebinding page always carries a *name*
//!   of its own. Anything else is answered 421 (Misdirected Request).
//! - **Origin**, when present (every WebSocket request from a browser, every `fetch` that is
//!   not a plain GET), must be the same host and port as `Host`: 403 otherwise.
//! - **Token**: a server bound to a non-loopback address can be reached by other machines,
//!   and the view injects faults into the emulator. Such a server requires `?token=…` (random,
//!   printed in the URL at start) on every request: 403 without it. Loopback stays tokenless.

use std::io::Read as _;
use std::net::{IpAddr, SocketAddr};

use axum::extract::{Request, State};
use axum::http::{header, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use super::same_origin;

/// Bytes of randomness in a token (hex-encoded: 32 characters).
const TOKEN_BYTES: usize = 16;

/// The access policy of one server.
#[derive(Debug, Clone)]
pub struct Access {
    bound: SocketAddr,
    token: Option<String>,
}

impl Access {
    /// The policy of a server bound to `bound`, requiring `token` on every request if given.
    pub fn new(bound: SocketAddr, token: Option<String>) -> Self {
        Self { bound, token }
    }

    /// Whether a `Host` header (or the authority of an absolute request target) names this
    /// server.
    pub fn host_allowed(&self, host: &str) -> bool {
        let Some((name, port)) = split_host(host) else {
            return false;
        };
        if name.eq_ignore_ascii_case("localhost") {
            return true;
        }
        let Ok(ip) = name.parse::<IpAddr>() else {
            // A name other than localhost: what a DNS-rebinding page sends.
            return false;
        };
        let ip = ip.to_canonical();
        if ip.is_loopback() {
            return true;
        }
        let port_ok = port.is_none_or(|p| p == self.bound.port());
        let bound = self.bound.ip().to_canonical();
        port_ok && (bound.is_unspecified() || ip == bound)
    }

    /// Check one request; `Err` is the response to send instead.
    fn check(&self, request: &Request) -> Result<(), (StatusCode, &'static str)> {
        let headers = request.headers();
        let host = headers.get(header::HOST).and_then(|v| v.to_str().ok());
        let authority = request.uri().authority().map(|a| a.as_str());
        let names_us = match (host, authority) {
            (None, None) => false,
            (host, authority) => [host, authority]
                .into_iter()
                .flatten()
                .all(|h| self.host_allowed(h)),
        };
        if !names_us {
            return Err((
                StatusCode::MISDIRECTED_REQUEST,
                "this server answers only to its own address (localhost, a loopback or the bound address)",
            ));
        }
        let origin = headers.get(header::ORIGIN).map(|v| v.to_str().ok());
        if let Some(origin) = origin {
            if !(origin.is_some() && same_origin(origin, host.or(authority))) {
                return Err((StatusCode::FORBIDDEN, "cross-origin request refused"));
            }
        }
        if let Some(token) = &self.token {
            let given = request
                .uri()
                .query()
                .unwrap_or("")
                .split('&')
                .find_map(|pair| pair.strip_prefix("token="));
            if !given.is_some_and(|g| constant_time_eq(g.as_bytes(), token.as_bytes())) {
                return Err((
                    StatusCode::FORBIDDEN,
                    "token required: open the URL printed when the emulator started",
                ));
            }
        }
        Ok(())
    }
}

/// The middleware: every request passes [`Access::check`] or gets its refusal.
pub async fn guard(
    State(access): State<std::sync::Arc<Access>>,
    request: Request,
    next: Next,
) -> Response {
    match access.check(&request) {
        Ok(()) => next.run(request).await,
        Err((status, why)) => {
            tracing::debug!(
                %status,
                host = ?request.headers().get(header::HOST),
                origin = ?request.headers().get(header::ORIGIN),
                path = request.uri().path(),
                "web view refused a request"
            );
            (status, why).into_response()
        }
    }
}

/// `host[:port]` or `[v6][:port]` into the name and the port. `None` if malformed.
fn split_host(host: &str) -> Option<(&str, Option<u16>)> {
    let (name, port) = if let Some(rest) = host.strip_prefix('[') {
        let (v6, after) = rest.split_once(']')?;
        let port = match after {
            "" => None,
            p => Some(p.strip_prefix(':')?),
        };
        (v6, port)
    } else {
        match host.split_once(':') {
            Some((name, port)) => (name, Some(port)),
            None => (host, None),
        }
    };
    let port = match port {
        Some(p) => Some(p.parse::<u16>().ok()?),
        None => None,
    };
    (!name.is_empty()).then_some((name, port))
}

/// Compare without stopping at the first difference (the token must not leak by timing).
fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// A fresh random token from the operating system (`/dev/urandom`), hex-encoded.
pub fn new_token() -> std::io::Result<String> {
    let mut bytes = [0u8; TOKEN_BYTES];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut bytes)?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn access(bound: &str, token: Option<&str>) -> Access {
        Access::new(bound.parse().unwrap(), token.map(str::to_owned))
    }

    fn request(host: Option<&str>, origin: Option<&str>, uri: &str) -> Request {
        let mut builder = Request::builder().uri(uri);
        if let Some(host) = host {
            builder = builder.header(header::HOST, host);
        }
        if let Some(origin) = origin {
            builder = builder.header(header::ORIGIN, origin);
        }
        builder.body(axum::body::Body::empty()).unwrap()
    }

    #[test]
    fn only_names_of_this_server_are_accepted_as_host() {
        let local = access("127.0.0.1:8000", None);
        for ok in [
            "127.0.0.1:8000",
            "127.0.0.1",
            "127.1.2.3:8000",
            "localhost:8000",
            "LOCALHOST",
            "[::1]:8000",
            "[::1]",
        ] {
            assert!(local.host_allowed(ok), "{ok}");
        }
        for bad in [
            "attacker.example:8000",
            "attacker.example",
            "127.0.0.1.nip.io:8000",
            "localhost.attacker.example",
            "192.168.1.5:8000",
            "",
            ":8000",
            "[::1",
            "127.0.0.1:notaport",
        ] {
            assert!(!local.host_allowed(bad), "{bad}");
        }
        let lan = access("192.168.1.5:8000", Some("t"));
        assert!(lan.host_allowed("192.168.1.5:8000"));
        assert!(lan.host_allowed("192.168.1.5"));
        assert!(!lan.host_allowed("192.168.1.5:9000"));
        assert!(!lan.host_allowed("192.168.1.6:8000"));
        assert!(!lan.host_allowed("robot-pc.local:8000"));
        let any = access("0.0.0.0:8000", Some("t"));
        assert!(any.host_allowed("10.0.0.7:8000"));
        assert!(any.host_allowed("localhost:8000"));
        assert!(!any.host_allowed("attacker.example:8000"));
    }

    #[test]
    fn a_rebinding_page_is_refused_with_421_and_a_foreign_origin_with_403() {
        let local = access("127.0.0.1:8000", None);
        let forged = Some("attacker.example:8000");
        for uri in ["/", "/state.json", "/ws"] {
            let refused = local
                .check(&request(forged, Some("http://attacker.example:8000"), uri))
                .unwrap_err();
            assert_eq!(refused.0, StatusCode::MISDIRECTED_REQUEST, "{uri}");
        }
        assert!(local.check(&request(None, None, "/")).is_err());
        assert!(local
            .check(&request(None, None, "http://attacker.example/state.json"))
            .is_err());
        let host = Some("127.0.0.1:8000");
        assert!(local.check(&request(host, None, "/state.json")).is_ok());
        assert!(local
            .check(&request(host, Some("http://127.0.0.1:8000"), "/ws"))
            .is_ok());
        for origin in ["http://attacker.example", "null", "http://localhost:8000"] {
            let refused = local
                .check(&request(host, Some(origin), "/ws"))
                .unwrap_err();
            assert_eq!(refused.0, StatusCode::FORBIDDEN, "{origin}");
        }
    }

    #[test]
    fn a_token_is_required_on_every_request_when_set() {
        let lan = access("192.168.1.5:8000", Some("s3cret"));
        let host = Some("192.168.1.5:8000");
        for uri in [
            "/",
            "/ws",
            "/state.json?x=1",
            "/?token=",
            "/?token=s3cre",
            "/?token=s3cretX",
        ] {
            let refused = lan.check(&request(host, None, uri)).unwrap_err();
            assert_eq!(refused.0, StatusCode::FORBIDDEN, "{uri}");
        }
        for uri in [
            "/?token=s3cret",
            "/ws?token=s3cret",
            "/state.json?a=b&token=s3cret",
        ] {
            assert!(lan.check(&request(host, None, uri)).is_ok(), "{uri}");
        }
    }

    #[test]
    fn tokens_are_random_and_long() {
        let a = new_token().unwrap();
        let b = new_token().unwrap();
        assert_eq!(a.len(), 2 * TOKEN_BYTES);
        assert!(a.bytes().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
    }
}
