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
//! A WebSocket request from a browser page of another origin is refused ([`same_origin`]).

pub mod bus_tap;
pub mod piper;
pub mod realman;
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

use crate::harness::report::html::{live_page, LIVE_JS};

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

/// What the page shows: one emulator.
#[async_trait::async_trait]
pub trait LiveSource: Send + Sync + 'static {
    /// The message sent once per connection.
    fn hello(&self) -> Value;
    /// The current state message.
    async fn state(&self) -> Value;
    /// Apply a fault command; `Ok` carries a line for the page, `Err` why it was refused.
    async fn command(&self, command: &Command) -> Result<String, String>;
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
}

/// A running web view; dropping it leaves the server running until the runtime stops.
#[derive(Debug)]
pub struct UiServer {
    addr: SocketAddr,
    stop: tokio::sync::watch::Sender<bool>,
    task: tokio::task::JoinHandle<()>,
}

impl UiServer {
    /// The address it listens on (the bound port when 0 was asked for).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
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

/// Serve the page for `source` on `addr` (`HOST:PORT`; a bare port means 127.0.0.1).
pub async fn serve(addr: &str, source: Arc<dyn LiveSource>) -> Result<UiServer, UiError> {
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
        .with_state(app);
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
    Json(app.source.state().await)
}

async fn hello_json(State(app): State<App>) -> Json<Value> {
    Json(app.source.hello())
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
    if send(&mut socket, &app.source.hello()).await.is_err() {
        return;
    }
    let mut tick = tokio::time::interval(STATE_PERIOD);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    loop {
        tokio::select! {
            _ = tick.tick() => {
                let state = app.source.state().await;
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
        Ok(command) if matches!(command.action.as_str(), "inject" | "clear") => {
            source.command(&command).await
        }
        Ok(command) => Err(format!("unknown command `{}`", command.action)),
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

    #[async_trait::async_trait]
    impl LiveSource for Echo {
        fn hello(&self) -> Value {
            json!({"type": "hello"})
        }
        async fn state(&self) -> Value {
            json!({"type": "state"})
        }
        async fn command(&self, command: &Command) -> Result<String, String> {
            Ok(format!("{} {}", command.action, command.fault))
        }
    }

    #[tokio::test]
    async fn malformed_and_unknown_commands_get_error_replies() {
        let ok = answer(&Echo, r#"{"type": "inject", "fault": "estop"}"#).await;
        assert_eq!(ok["ok"], true);
        assert_eq!(ok["message"], "inject estop");
        let unknown = answer(&Echo, r#"{"type": "reboot", "fault": "estop"}"#).await;
        assert_eq!(unknown["ok"], false);
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
