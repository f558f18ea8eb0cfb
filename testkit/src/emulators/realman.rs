//! A Realman emulator in virtual time (in-memory streams) and a client reading its CRLF lines.

use std::net::{IpAddr, Ipv4Addr};
use std::time::Duration;

use serde_json::Value;
use sim::realman::model::ArmModel;
use sim::realman::{ControllerConfig, EmulatorConfig, RealmanEmulator, RealmanHandle, Transport};
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};

/// The IP in-memory clients claim.
pub const PEER: IpAddr = IpAddr::V4(Ipv4Addr::new(192, 168, 1, 10));

/// An RM65-B emulator on in-memory streams (call under a paused clock).
pub async fn emulator() -> RealmanHandle {
    emulator_with(|_| {}).await
}

/// Same, with the configuration adjusted first.
pub async fn emulator_with(adjust: impl FnOnce(&mut EmulatorConfig)) -> RealmanHandle {
    let mut config = EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b()));
    adjust(&mut config);
    RealmanEmulator::spawn(config, Transport::InMemory)
        .await
        .expect("emulator starts")
}

/// A client reading CRLF-terminated lines.
pub struct LineClient<S> {
    /// The connection, for tests that write or close it directly.
    pub stream: S,
    buf: Vec<u8>,
}

impl<S: AsyncRead + AsyncWrite + Unpin> LineClient<S> {
    /// A client over `stream`, with nothing read yet.
    pub fn new(stream: S) -> Self {
        Self {
            stream,
            buf: Vec::new(),
        }
    }

    /// Writes `text` as it is (the caller adds any line ending).
    pub async fn send(&mut self, text: &str) {
        self.stream.write_all(text.as_bytes()).await.expect("send");
    }

    /// The next line (without CRLF), or `None` on timeout or EOF.
    pub async fn line(&mut self, timeout: Duration) -> Option<String> {
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            if let Some(pos) = self.buf.windows(2).position(|w| w == b"\r\n") {
                let line: Vec<u8> = self.buf.drain(..pos + 2).collect();
                return Some(String::from_utf8_lossy(&line[..pos]).into_owned());
            }
            let mut chunk = [0u8; 4096];
            let read = tokio::time::timeout_at(deadline, self.stream.read(&mut chunk)).await;
            match read {
                Ok(Ok(0)) | Ok(Err(_)) | Err(_) => return None,
                Ok(Ok(n)) => self.buf.extend_from_slice(&chunk[..n]),
            }
        }
    }

    /// The next line parsed as JSON.
    pub async fn json(&mut self, timeout: Duration) -> Option<Value> {
        let line = self.line(timeout).await?;
        Some(serde_json::from_str(&line).unwrap_or_else(|e| panic!("bad JSON {line:?}: {e}")))
    }

    /// Send one compact request + CRLF and read the next line as JSON.
    pub async fn ask(&mut self, request: &str) -> Value {
        self.send(&format!("{request}\r\n")).await;
        self.json(Duration::from_millis(500))
            .await
            .unwrap_or_else(|| panic!("no reply to {request}"))
    }

    /// Whether the peer closed the stream (EOF) within `timeout`.
    pub async fn closed(&mut self, timeout: Duration) -> bool {
        let mut chunk = [0u8; 4096];
        let deadline = tokio::time::Instant::now() + timeout;
        loop {
            match tokio::time::timeout_at(deadline, self.stream.read(&mut chunk)).await {
                Ok(Ok(0)) | Ok(Err(_)) => return true,
                Ok(Ok(_)) => continue,
                Err(_) => return false,
            }
        }
    }
}

/// An in-memory client of `emu`.
pub fn client(emu: &RealmanHandle) -> LineClient<tokio::io::DuplexStream> {
    LineClient::new(emu.connect(PEER).expect("in-memory connect"))
}

/// Joint angles of a `get_current_arm_state` reply, degrees.
pub fn joints_deg(state: &Value) -> Vec<f64> {
    state["arm_state"]["joint"]
        .as_array()
        .expect("joint array")
        .iter()
        .map(|v| v.as_f64().expect("number") / 1000.0)
        .collect()
}

/// Error codes of a `get_current_arm_state` reply.
pub fn err_codes(state: &Value) -> Vec<i64> {
    state["arm_state"]["err"]
        .as_array()
        .expect("err array")
        .iter()
        .map(|v| v.as_i64().expect("int"))
        .collect()
}
