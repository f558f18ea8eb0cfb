//! The live web view of `armhil sim <device> --ui ADDR`: one page (built into the binary) and
//! a WebSocket that streams the emulator's state and takes fault commands.
//!
//! Protocol (JSON text messages on `/ws`):
//! - server → page, once: `{"type": "hello", "device", "model", "faults": [...]}`: the arm to
//!   draw (see [`crate::harness::report::html::arm_model`]) and the fault vocabulary of
//!   scenario files (name, parameters, description).
//! - server → page, every [`STATE_PERIOD`]: `{"type": "state", ...}` (device specific).
//! - page → server: `{"type": "inject" | "clear", "fault": NAME, "args": {...}}`, answered by
//!   `{"type": "ack", "ok": bool, "message": TEXT}`.
//!
//! `GET /state.json` returns one state message, `GET /hello.json` the hello (for scripts).
//!
//! Every request passes the access check first (`access.rs`): a `Host` that does not name
//! this server gets 421 (DNS rebinding), an `Origin` other than the `Host` 403 (another site
//! in the same browser), and a server bound to a non-loopback address requires the random
//! token printed at start (`?token=…`) on every request. The listener (`listener.rs`) caps
//! the open connections and closes those that send their request too slowly or sit idle
//! ([`Limits`]).

mod access;
pub mod bus_tap;
pub mod damiao;
mod fault_args;
mod listener;
pub mod piper;
pub mod realman;
pub mod robot;
pub mod robstride;

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::response::{Html, IntoResponse, Json};
use axum::routing::get;
use axum::Router;
use serde::Deserialize;
use serde_json::{json, Value};

use sim::fault_desk::{FaultAction, Faults};

use crate::harness::elide_long_tokens;
use crate::harness::report::html::{live_page, LIVE_JS};
pub use fault_args::page_fault_args;
pub use listener::Limits;

/// How often the page gets a state message (50 Hz: the page draws at its own frame rate and
/// interpolates nothing, so this bounds what it can show).
pub const STATE_PERIOD: Duration = Duration::from_millis(20);

/// A fault command from the page.
#[derive(Debug, Clone, Deserialize)]
pub struct Command {
    /// `inject` or `clear`.
    #[serde(rename = "type")]
    pub action: String,
    /// The fault's name in scenario files.
    pub fault: String,
    /// Its parameters by name.
    #[serde(default)]
    pub args: serde_json::Map<String, Value>,
}

/// What the page shows: one emulator, and its faults through the emulator's own
/// [`Faults`] desk (the same builder, table and messages as scenario files and Python).
#[async_trait::async_trait]
pub trait LiveSource: Send + Sync + 'static {
    /// The message sent once per connection, without its `faults` (the server adds the
    /// emulator's fault table).
    fn hello(&self) -> Value;
    /// The current state message; the server adds the faults applied from the page and not
    /// cleared as `faults`, unless the source set `faults` itself (a stopped robot says so).
    async fn state(&self) -> Value;
    /// The emulator's faults.
    fn faults(&self) -> &dyn Faults;
}

/// The hello of `source`: its own fields and the emulator's fault table.
pub fn hello_message(source: &dyn LiveSource) -> Value {
    let mut hello = source.hello();
    if let Value::Object(fields) = &mut hello {
        fields.insert("faults".into(), json!(source.faults().table()));
    }
    hello
}

/// The state message of `source`, with the faults applied from the page.
pub async fn state_message(source: &dyn LiveSource) -> Value {
    let mut state = source.state().await;
    if let Value::Object(fields) = &mut state {
        fields
            .entry("faults")
            .or_insert_with(|| json!(source.faults().active()));
    }
    state
}

/// Apply a page's fault command through the emulator's desk; `Ok` is the line the page
/// shows, `Err` why it was refused (a pasted huge value elided).
pub async fn apply_command(faults: &dyn Faults, command: &Command) -> Result<String, String> {
    let action = match command.action.as_str() {
        "inject" => FaultAction::Inject,
        "clear" => FaultAction::Clear,
        other => return Err(format!("unknown command `{}`", elide_long_tokens(other))),
    };
    faults
        .apply(action, &command.fault, &page_fault_args(&command.args))
        .await
        .map_err(|e| elide_long_tokens(&e.to_string()))
}

/// Why the server could not start.
#[derive(Debug, thiserror::Error)]
pub enum UiError {
    /// The address could not be bound.
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// No random token could be made for a server reachable from other machines.
    #[error("cannot make an access token for the web view on {addr}: {source}")]
    Token {
        /// The address asked for.
        addr: String,
        /// The OS error.
        source: std::io::Error,
    },
}

/// How to serve the web view.
#[derive(Debug, Clone, Default)]
pub struct UiOptions {
    /// Connection cap and deadlines.
    pub limits: Limits,
    /// Whether every request needs the token: `None` (default) decides by the address, a
    /// token exactly when it is not loopback.
    pub require_token: Option<bool>,
}

/// A running web view; dropping it leaves the server running until the runtime stops.
#[derive(Debug)]
pub struct UiServer {
    addr: SocketAddr,
    token: Option<String>,
    stop: tokio::sync::watch::Sender<bool>,
    task: tokio::task::JoinHandle<()>,
}

impl UiServer {
    /// The address it listens on (the bound port when 0 was asked for).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The token every request must carry (`?token=…`), if the server requires one.
    pub fn token(&self) -> Option<&str> {
        self.token.as_deref()
    }

    /// Whether other machines can reach it (bound to a non-loopback address).
    pub fn is_public(&self) -> bool {
        !self.addr.ip().is_loopback()
    }

    /// The URL to open, token included. For a wildcard bind (`0.0.0.0`, `[::]`) the host
    /// part is `127.0.0.1` (other machines put this machine's address in its place).
    pub fn url(&self) -> String {
        let mut shown = self.addr;
        if shown.ip().is_unspecified() {
            shown.set_ip(std::net::Ipv4Addr::LOCALHOST.into());
        }
        match &self.token {
            Some(token) => format!("http://{shown}/?token={token}"),
            None => format!("http://{shown}/"),
        }
    }

    /// Stop accepting connections and end the open ones.
    pub async fn shutdown(self) {
        let _ = self.stop.send(true);
        let _ = self.task.await;
    }
}

#[derive(Clone)]
struct App {
    source: Arc<dyn LiveSource>,
    page: Arc<String>,
    stop: tokio::sync::watch::Receiver<bool>,
}

/// Serve the page for `source` on `addr` (`HOST:PORT`; a bare port means 127.0.0.1) with
/// the default [`UiOptions`].
pub async fn serve(addr: &str, source: Arc<dyn LiveSource>) -> Result<UiServer, UiError> {
    serve_with(addr, source, UiOptions::default()).await
}

/// Serve the page for `source` on `addr` (`HOST:PORT`; a bare port means 127.0.0.1).
pub async fn serve_with(
    addr: &str,
    source: Arc<dyn LiveSource>,
    options: UiOptions,
) -> Result<UiServer, UiError> {
    let addr = match addr.parse::<u16>() {
        Ok(port) => format!("127.0.0.1:{port}"),
        Err(_) => addr.to_owned(),
    };
    let listener = tokio::net::TcpListener::bind(&addr)
        .await
        .map_err(|source| UiError::Bind {
            addr: addr.clone(),
            source,
        })?;
    let local = listener.local_addr().map_err(|source| UiError::Bind {
        addr: addr.clone(),
        source,
    })?;
    let needs_token = options.require_token.unwrap_or(!local.ip().is_loopback());
    let token = if needs_token {
        Some(access::new_token().map_err(|source| UiError::Token {
            addr: addr.clone(),
            source,
        })?)
    } else {
        None
    };
    let access = Arc::new(access::Access::new(local, token.clone()));
    let (stop, stopped) = tokio::sync::watch::channel(false);
    let app = App {
        source,
        page: Arc::new(live_page("armhil live", LIVE_JS)),
        stop: stopped.clone(),
    };
    let router = Router::new()
        .route("/", get(index))
        .route("/ws", get(ws))
        .route("/state.json", get(state_json))
        .route("/hello.json", get(hello_json))
        .with_state(app)
        // Outermost: no handler (and no 404) answers a request that fails the check.
        .layer(axum::middleware::from_fn_with_state(access, access::guard));
    let listener = listener::LimitedListener::new(listener, options.limits);
    let mut stopped = stopped;
    let task = tokio::spawn(async move {
        let shutdown = async move {
            let _ = stopped.wait_for(|s| *s).await.map(|_| ());
        };
        if let Err(e) = axum::serve(listener, router)
            .with_graceful_shutdown(shutdown)
            .await
        {
            tracing::warn!(error = %e, "web view server stopped");
        }
    });
    Ok(UiServer {
        addr: local,
        token,
        stop,
        task,
    })
}

async fn index(State(app): State<App>) -> impl IntoResponse {
    (
        [(axum::http::header::CACHE_CONTROL, "no-store")],
        Html(app.page.as_str().to_owned()),
    )
}

async fn state_json(State(app): State<App>) -> Json<Value> {
    Json(state_message(app.source.as_ref()).await)
}

async fn hello_json(State(app): State<App>) -> Json<Value> {
    Json(hello_message(app.source.as_ref()))
}

async fn ws(
    State(app): State<App>,
    headers: axum::http::HeaderMap,
    upgrade: WebSocketUpgrade,
) -> axum::response::Response {
    let header =
        |name: axum::http::header::HeaderName| headers.get(name).and_then(|v| v.to_str().ok());
    if !same_origin(
        header(axum::http::header::ORIGIN),
        header(axum::http::header::HOST),
    ) {
        // Another site open in the same browser must not inject faults.
        return (
            axum::http::StatusCode::FORBIDDEN,
            "cross-origin WebSocket refused",
        )
            .into_response();
    }
    upgrade
        .on_upgrade(move |socket| stream(app, socket))
        .into_response()
}

/// Whether a WebSocket request comes from the page this server sent: no `Origin` (a script,
/// not a browser) or an `Origin` whose host and port are the request's `Host`.
pub fn same_origin(origin: Option<&str>, host: Option<&str>) -> bool {
    match (origin, host) {
        (None, _) => true,
        (Some(origin), Some(host)) => origin
            .strip_prefix("http://")
            .or_else(|| origin.strip_prefix("https://"))
            .is_some_and(|rest| rest.eq_ignore_ascii_case(host)),
        (Some(_), None) => false,
    }
}

/// One page: hello, then state every period, commands answered as they come.
async fn stream(app: App, mut socket: WebSocket) {
    let mut stop = app.stop.clone();
    if send(&mut socket, &hello_message(app.source.as_ref()))
        .await
        .is_err()
    {
        return;
    }
    let mut tick = tokio::time::interval(STATE_PERIOD);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    loop {
        tokio::select! {
            _ = tick.tick() => {
                let state = state_message(app.source.as_ref()).await;
                if send(&mut socket, &state).await.is_err() {
                    break;
                }
            }
            message = socket.recv() => match message {
                Some(Ok(Message::Text(text))) => {
                    let reply = answer(app.source.as_ref(), text.as_str()).await;
                    if send(&mut socket, &reply).await.is_err() {
                        break;
                    }
                }
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => break,
                Some(Ok(_)) => {}
            },
            // Any change is the server stopping (it only ever sends `true`).
            _ = stop.changed() => break,
        }
    }
}

/// The reply to one text message (malformed ones get an error reply, never a panic).
pub async fn answer(source: &dyn LiveSource, text: &str) -> Value {
    let result = match serde_json::from_str::<Command>(text) {
        Ok(command) => apply_command(source.faults(), &command).await,
        Err(e) => Err(format!("bad message: {e}")),
    };
    match result {
        Ok(message) => json!({"type": "ack", "ok": true, "message": message}),
        Err(message) => json!({"type": "ack", "ok": false, "message": message}),
    }
}

async fn send(socket: &mut WebSocket, value: &Value) -> Result<(), axum::Error> {
    socket.send(Message::Text(value.to_string().into())).await
}

/// A value as the page shows it: to a thousandth (of a degree, a volt, a second …).
fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_served_page_or_a_script_may_open_the_socket() {
        assert!(same_origin(None, Some("127.0.0.1:8000")));
        assert!(same_origin(
            Some("http://127.0.0.1:8000"),
            Some("127.0.0.1:8000")
        ));
        assert!(!same_origin(
            Some("http://evil.example"),
            Some("127.0.0.1:8000")
        ));
        assert!(!same_origin(
            Some("http://127.0.0.1:9000"),
            Some("127.0.0.1:8000")
        ));
        assert!(!same_origin(Some("null"), Some("127.0.0.1:8000")));
        assert!(!same_origin(Some("http://127.0.0.1:8000"), None));
    }

    struct Echo;

    /// Says what it was asked to do.
    #[derive(Debug)]
    struct EchoFaults;

    #[async_trait::async_trait]
    impl Faults for EchoFaults {
        fn table(&self) -> Vec<sim::fault_desk::FaultInfo> {
            Vec::new()
        }
        async fn apply(
            &self,
            action: FaultAction,
            name: &str,
            _args: &sim::fault_args::FaultArgs,
        ) -> Result<String, sim::fault_desk::FaultCommandError> {
            let verb = match action {
                FaultAction::Inject => "inject",
                FaultAction::Clear => "clear",
            };
            Ok(format!("{verb} {name}"))
        }
        fn active(&self) -> Vec<String> {
            vec!["estop".into()]
        }
    }

    #[async_trait::async_trait]
    impl LiveSource for Echo {
        fn hello(&self) -> Value {
            json!({"type": "hello"})
        }
        async fn state(&self) -> Value {
            json!({"type": "state"})
        }
        fn faults(&self) -> &dyn Faults {
            &EchoFaults
        }
    }

    /// A server for [`Echo`] on a free loopback port.
    async fn server(options: UiOptions) -> UiServer {
        serve_with("127.0.0.1:0", Arc::new(Echo), options)
            .await
            .expect("web view starts")
    }

    /// Send `request` on a new connection and return what came back until the server closed
    /// it or `within` passed.
    async fn exchange(addr: SocketAddr, request: &str, within: Duration) -> String {
        use tokio::io::{AsyncReadExt, AsyncWriteExt};
        let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
        stream.write_all(request.as_bytes()).await.unwrap();
        let mut seen = Vec::new();
        let mut buf = [0u8; 4096];
        let _ = tokio::time::timeout(within, async {
            loop {
                match stream.read(&mut buf).await {
                    Ok(0) | Err(_) => break,
                    Ok(n) => seen.extend_from_slice(&buf[..n]),
                }
                // One response is enough (keep-alive would hold the connection open).
                if seen.windows(4).any(|w| w == b"\r\n\r\n") {
                    break;
                }
            }
        })
        .await;
        String::from_utf8_lossy(&seen).into_owned()
    }

    fn get(path: &str, host: &str, origin: Option<&str>) -> String {
        let origin = origin
            .map(|o| format!("Origin: {o}\r\n"))
            .unwrap_or_default();
        format!("GET {path} HTTP/1.1\r\nHost: {host}\r\n{origin}\r\n")
    }

    fn upgrade(path: &str, host: &str, origin: &str) -> String {
        format!(
            "GET {path} HTTP/1.1\r\nHost: {host}\r\nOrigin: {origin}\r\nConnection: Upgrade\r\n\
             Upgrade: websocket\r\nSec-WebSocket-Version: 13\r\n\
             Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n"
        )
    }

    const WAIT: Duration = Duration::from_secs(5);

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_dns_rebinding_page_gets_421_on_every_path() {
        let ui = server(UiOptions::default()).await;
        let addr = ui.local_addr();
        assert_eq!(ui.token(), None, "loopback stays tokenless");
        let evil = format!("attacker.example:{}", addr.port());
        let evil_origin = format!("http://{evil}");
        for path in ["/", "/state.json", "/hello.json", "/nope"] {
            let reply = exchange(addr, &get(path, &evil, Some(&evil_origin)), WAIT).await;
            assert!(reply.starts_with("HTTP/1.1 421"), "{path}: {reply}");
        }
        let reply = exchange(addr, &upgrade("/ws", &evil, &evil_origin), WAIT).await;
        assert!(reply.starts_with("HTTP/1.1 421"), "ws: {reply}");
        // The same requests naming this server are served (so the test can fail).
        let host = addr.to_string();
        let reply = exchange(addr, &get("/state.json", &host, None), WAIT).await;
        assert!(reply.starts_with("HTTP/1.1 200"), "{reply}");
        let reply = exchange(
            addr,
            &get("/", &format!("localhost:{}", addr.port()), None),
            WAIT,
        )
        .await;
        assert!(reply.starts_with("HTTP/1.1 200"), "{reply}");
        let reply = exchange(
            addr,
            &upgrade("/ws", &host, &format!("http://{host}")),
            WAIT,
        )
        .await;
        assert!(reply.starts_with("HTTP/1.1 101"), "{reply}");
        let reply = exchange(
            addr,
            &upgrade("/ws", &host, "http://attacker.example"),
            WAIT,
        )
        .await;
        assert!(reply.starts_with("HTTP/1.1 403"), "{reply}");
        ui.shutdown().await;
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn with_a_token_every_request_needs_it() {
        let ui = server(UiOptions {
            require_token: Some(true),
            ..UiOptions::default()
        })
        .await;
        let addr = ui.local_addr();
        let host = addr.to_string();
        let token = ui.token().expect("a token").to_owned();
        assert!(ui.url().ends_with(&format!("/?token={token}")));
        for path in ["/", "/state.json", "/hello.json", "/?token=wrong"] {
            let reply = exchange(addr, &get(path, &host, None), WAIT).await;
            assert!(reply.starts_with("HTTP/1.1 403"), "{path}: {reply}");
        }
        let reply = exchange(
            addr,
            &upgrade("/ws", &host, &format!("http://{host}")),
            WAIT,
        )
        .await;
        assert!(reply.starts_with("HTTP/1.1 403"), "{reply}");
        for path in ["/", "/state.json", "/hello.json"] {
            let path = format!("{path}?token={token}");
            let reply = exchange(addr, &get(&path, &host, None), WAIT).await;
            assert!(reply.starts_with("HTTP/1.1 200"), "{path}: {reply}");
        }
        let ws = format!("/ws?token={token}");
        let reply = exchange(addr, &upgrade(&ws, &host, &format!("http://{host}")), WAIT).await;
        assert!(reply.starts_with("HTTP/1.1 101"), "{reply}");
        // That the page's script passes the token on to its WebSocket is checked by
        // web/tests/unit/live_token.test.js.
        ui.shutdown().await;
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn slow_and_silent_connections_are_closed_and_capped() {
        use tokio::io::{AsyncReadExt, AsyncWriteExt};
        let limits = Limits {
            max_connections: 3,
            request_timeout: Duration::from_millis(400),
            idle_timeout: Duration::from_secs(2),
        };
        let ui = server(UiOptions {
            limits,
            require_token: None,
        })
        .await;
        let addr = ui.local_addr();
        let host = addr.to_string();
        // Three connections that never finish a request fill the server.
        let mut silent = Vec::new();
        for _ in 0..3 {
            let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
            s.write_all(b"GET / HTTP/1.1\r\nHost: ").await.unwrap();
            silent.push(s);
        }
        let started = tokio::time::Instant::now();
        // A fourth waits for a slot, then is answered once the slow ones are cut off.
        let reply = exchange(addr, &get("/hello.json", &host, None), WAIT).await;
        assert!(reply.starts_with("HTTP/1.1 200"), "{reply}");
        let waited = started.elapsed();
        assert!(
            waited >= Duration::from_millis(300),
            "no cap: answered after {waited:?}"
        );
        assert!(
            waited < Duration::from_secs(2),
            "no request timeout: {waited:?}"
        );
        for mut s in silent {
            let mut buf = [0u8; 64];
            let read = tokio::time::timeout(WAIT, s.read(&mut buf)).await;
            assert!(
                matches!(read, Ok(Ok(0)) | Ok(Err(_))),
                "still open: {read:?}"
            );
        }
        // A slowloris (a byte every 100 ms, never done) is closed as well.
        let mut slow = tokio::net::TcpStream::connect(addr).await.unwrap();
        let started = tokio::time::Instant::now();
        let mut closed = false;
        for _ in 0..40 {
            if slow.write_all(b"X").await.is_err() {
                closed = true;
                break;
            }
            let mut buf = [0u8; 64];
            if let Ok(r) =
                tokio::time::timeout(Duration::from_millis(100), slow.read(&mut buf)).await
            {
                closed = matches!(r, Ok(0) | Err(_)) || closed;
                if closed {
                    break;
                }
            }
        }
        assert!(closed, "slowloris kept its connection");
        assert!(started.elapsed() < Duration::from_secs(2));
        ui.shutdown().await;
    }

    #[tokio::test]
    async fn malformed_and_unknown_commands_get_error_replies() {
        let ok = answer(&Echo, r#"{"type": "inject", "fault": "estop"}"#).await;
        assert_eq!(ok["ok"], true);
        assert_eq!(ok["message"], "inject estop");
        let unknown = answer(&Echo, r#"{"type": "reboot", "fault": "estop"}"#).await;
        assert_eq!(unknown["ok"], false);
        assert_eq!(unknown["message"], "unknown command `reboot`");
        // The server adds the fault table to the hello and the active faults to the state.
        assert_eq!(hello_message(&Echo)["faults"], json!([]));
        assert_eq!(state_message(&Echo).await["faults"], json!(["estop"]));
        for bad in [
            "",
            "{",
            "[1]",
            r#"{"type": "inject"}"#,
            r#"{"type": 3, "fault": "x"}"#,
        ] {
            let reply = answer(&Echo, bad).await;
            assert_eq!(reply["ok"], false, "{bad}");
            assert_eq!(reply["type"], "ack");
        }
    }
}
