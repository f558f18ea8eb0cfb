//! Refusing HTTP on ports that do not speak it: the one detector every armhil TCP server that
//! is not a web server runs on the bytes it reads (the socketcand server here, the Realman
//! emulator's JSON port in `sim`).
//!
//! Why: a web page can make the browser send a request to any port on the visitor's machine
//! (`fetch("http://127.0.0.1:8080/", {method: "POST", mode: "no-cors", body})`). The page
//! cannot read the answer, but it does not need to: a server that skips the request line and
//! the header lines as junk and then runs the body does what the page says (powers a Realman
//! arm off, e-stops a Piper over socketcand). No client of these protocols ever sends an HTTP
//! request line or a `Host:`/`Origin:` header line, so a connection that does is closed, with
//! nothing in it acted on.
//!
//! How: [`HttpGuard::admit`] sees every chunk before the server's framer does. Until the first
//! line of the connection is known not to be a request line (`METHOD SP target SP HTTP/x.y`)
//! the bytes are held back, so the body of a request, which always follows its request line,
//! is never handed out. A protocol client is let through at its first byte: `{` (Realman) and
//! `<` (socketcand) cannot start an HTTP method. Every line of the connection is also checked
//! for a `Host:` or `Origin:` header at its start.

/// Most bytes held back while the first line could still be an HTTP request line. Longer
/// undecided input (a token, a space and 8 KiB of URL-like text without a line end) is what a
/// browser with a long URL sends and never what a protocol client sends: it is refused.
pub const MAX_HELD_BYTES: usize = 8 * 1024;

/// Header names whose line closes a connection (lower case, colon included).
const HEADERS: [&str; 2] = ["host:", "origin:"];
/// Longest entry of [`HEADERS`].
const MAX_HEADER_PREFIX: usize = 7;

/// Why a connection was taken for an HTTP request and must be closed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HttpRefused {
    /// The connection opened with an HTTP request line.
    #[error("the connection opened with an HTTP request line (method {method}): a web page or HTTP client, not a protocol client")]
    RequestLine {
        /// The request's method (at most 16 characters of it).
        method: String,
    },
    /// A line of the connection starts with an HTTP header that browsers always send.
    #[error("the connection carries an HTTP `{header}` header line: a web page or HTTP client, not a protocol client")]
    Header {
        /// The header, lower case, with its colon.
        header: &'static str,
    },
    /// The first line was still undecided after [`MAX_HELD_BYTES`].
    #[error("the first line is over {MAX_HELD_BYTES} bytes and could be an HTTP request line")]
    Undecided,
}

/// Where the first line stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum First {
    /// Only whitespace so far.
    Leading,
    /// In the method token.
    Method,
    /// In the request target.
    Target { len: usize },
    /// Matching `HTTP/`: this many bytes of it matched.
    Version { matched: usize },
    /// In the version number after `HTTP/`.
    VersionNumber { digits: usize },
    /// The first line is not a request line: everything passes (after the header check).
    Clean,
}

/// What one byte of the first line decided.
enum Step {
    More,
    Clean,
    Http,
}

/// The detector of one connection. See the module documentation.
#[derive(Debug, Clone)]
pub struct HttpGuard {
    first: First,
    /// The method so far (for the log), at most 16 bytes.
    method: Vec<u8>,
    /// Bytes received while the first line was undecided; handed out once it is decided.
    held: Vec<u8>,
    /// The lower-cased start of the current line while it could still be a header in
    /// [`HEADERS`]; `None` once it cannot.
    line_head: Option<Vec<u8>>,
}

impl Default for HttpGuard {
    fn default() -> Self {
        Self::new()
    }
}

impl HttpGuard {
    /// A guard for a new connection.
    pub fn new() -> Self {
        Self {
            first: First::Leading,
            method: Vec::new(),
            held: Vec::new(),
            line_head: Some(Vec::with_capacity(MAX_HEADER_PREFIX)),
        }
    }

    /// Inspect `bytes` just read from the connection. `Ok` carries the bytes the server may
    /// act on now, in order: `bytes` itself, nothing while the first line is undecided, or
    /// everything held so far once it is decided. `Err` means: close the connection and act
    /// on nothing more of it (nothing of it was handed out unless the first line was clean).
    pub fn admit<'a>(&'a mut self, bytes: &'a [u8]) -> Result<&'a [u8], HttpRefused> {
        let was_clean = self.first == First::Clean;
        let mut now_clean = false;
        if !was_clean {
            for &byte in bytes {
                match self.step(byte) {
                    Step::More => {}
                    Step::Http => {
                        let method = String::from_utf8_lossy(&self.method).into_owned();
                        return Err(HttpRefused::RequestLine { method });
                    }
                    Step::Clean => {
                        now_clean = true;
                        break;
                    }
                }
            }
        }
        self.check_headers(bytes)?;
        if was_clean {
            if !self.held.is_empty() {
                // Handed out by the previous call.
                self.held = Vec::new();
            }
            return Ok(bytes);
        }
        self.held.extend_from_slice(bytes);
        if now_clean {
            self.first = First::Clean;
            return Ok(&self.held);
        }
        if self.held.len() > MAX_HELD_BYTES {
            return Err(HttpRefused::Undecided);
        }
        Ok(&[])
    }

    /// Refuse a line that starts with a header of [`HEADERS`] (case-insensitive).
    fn check_headers(&mut self, bytes: &[u8]) -> Result<(), HttpRefused> {
        for &byte in bytes {
            if byte == b'\n' {
                self.line_head = Some(Vec::with_capacity(MAX_HEADER_PREFIX));
                continue;
            }
            let Some(head) = &mut self.line_head else {
                continue;
            };
            head.push(byte.to_ascii_lowercase());
            if let Some(header) = HEADERS.iter().find(|h| h.as_bytes() == head.as_slice()) {
                return Err(HttpRefused::Header { header });
            }
            if !HEADERS.iter().any(|h| h.as_bytes().starts_with(head)) {
                self.line_head = None;
            }
        }
        Ok(())
    }

    /// One byte of the first line through `METHOD SP target SP HTTP/x.y (CR) LF`.
    fn step(&mut self, byte: u8) -> Step {
        match self.first {
            First::Leading if byte.is_ascii_whitespace() => Step::More,
            First::Leading | First::Method if is_tchar(byte) => {
                self.first = First::Method;
                if self.method.len() < 16 {
                    self.method.push(byte);
                }
                Step::More
            }
            First::Method if byte == b' ' => {
                self.first = First::Target { len: 0 };
                Step::More
            }
            First::Target { len } if byte == b' ' && len > 0 => {
                self.first = First::Version { matched: 0 };
                Step::More
            }
            // Visible ASCII, and bytes over 0x7F (obs-text): a lenient reading of the target.
            First::Target { len } if byte > b' ' && byte != 0x7F => {
                self.first = First::Target { len: len + 1 };
                Step::More
            }
            First::Version { matched } if byte.to_ascii_uppercase() == b"HTTP/"[matched] => {
                self.first = if matched + 1 == 5 {
                    First::VersionNumber { digits: 0 }
                } else {
                    First::Version {
                        matched: matched + 1,
                    }
                };
                Step::More
            }
            First::VersionNumber { digits } if byte.is_ascii_digit() || byte == b'.' => {
                self.first = First::VersionNumber { digits: digits + 1 };
                Step::More
            }
            First::VersionNumber { digits } if digits > 0 && matches!(byte, b'\r' | b'\n') => {
                Step::Http
            }
            _ => Step::Clean,
        }
    }
}

/// A byte of an HTTP token (RFC 9110 §5.6.2).
fn is_tchar(byte: u8) -> bool {
    byte.is_ascii_alphanumeric() || b"!#$%&'*+-.^_`|~".contains(&byte)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feed `input` in chunks of `chunk` bytes; what was handed out, and the refusal if any.
    fn run(input: &[u8], chunk: usize) -> (Vec<u8>, Option<HttpRefused>) {
        let mut guard = HttpGuard::new();
        let mut out = Vec::new();
        for piece in input.chunks(chunk.max(1)) {
            match guard.admit(piece) {
                Ok(bytes) => out.extend_from_slice(bytes),
                Err(e) => return (out, Some(e)),
            }
        }
        (out, None)
    }

    const BROWSER_POST: &[u8] = b"POST / HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nConnection: keep-alive\r\nContent-Length: 44\r\nOrigin: https://attacker.example\r\nContent-Type: text/plain;charset=UTF-8\r\n\r\n{\"command\":\"set_arm_power\",\"arm_power\":0}";

    #[test]
    fn a_browser_request_is_refused_before_any_byte_is_handed_out() {
        let socketcand = b"POST /x?y=1 HTTP/1.1\r\nHost: localhost:29536\r\n\r\n< open can0 >< send 150 8 01 00 00 00 00 00 00 00 >";
        for input in [BROWSER_POST, socketcand.as_slice(), b"get / http/1.0\n\n{}"] {
            for chunk in [1, 2, 3, 7, 16, 4096] {
                let (out, refused) = run(input, chunk);
                assert!(out.is_empty(), "chunk {chunk}: handed out {out:?}");
                assert!(
                    matches!(refused, Some(HttpRefused::RequestLine { .. })),
                    "chunk {chunk}: {refused:?}"
                );
            }
        }
    }

    #[test]
    fn header_lines_are_refused_anywhere() {
        for input in [
            b"Host: 127.0.0.1\r\n{}".as_slice(),
            b"{\"command\":\"get_joint_degree\"}\r\nhOsT: x\r\n",
            b"< open can0 >\nOrigin: null\n",
        ] {
            for chunk in [1, 5, 4096] {
                let (_, refused) = run(input, chunk);
                assert!(
                    matches!(refused, Some(HttpRefused::Header { .. })),
                    "{input:?} chunk {chunk}: {refused:?}"
                );
            }
        }
    }

    #[test]
    fn protocol_clients_pass_unchanged_and_at_once() {
        let inputs: [&[u8]; 5] = [
            b"{\"command\":\"get_arm_all_state\"}\r\n{\"command\":\"set_arm_power\",\"arm_power\":1}",
            b"{\n\t\"command\":\t\"get_joint_degree\"\n}",
            b"< open can0 >< rawmode >< send 150 8 01 00 00 00 00 00 00 00 >",
            b"  \r\n< echo >\n< hostname >\nhosting\n",
            b"garbage<open can0>",
        ];
        for input in inputs {
            for chunk in [1, 3, 4096] {
                let (out, refused) = run(input, chunk);
                assert_eq!(refused, None, "{input:?}");
                assert_eq!(out, input, "chunk {chunk}");
            }
        }
        // A protocol client's first byte decides: nothing is held back waiting for a line end.
        let mut guard = HttpGuard::new();
        assert_eq!(guard.admit(b"{").unwrap(), b"{");
        let mut guard = HttpGuard::new();
        assert_eq!(guard.admit(b"<").unwrap(), b"<");
    }

    #[test]
    fn lines_that_are_almost_request_lines_pass() {
        for input in [
            b"GET /\r\n".as_slice(),            // HTTP/0.9: no version
            b"GET / FTP/1.1\r\n",               // not HTTP
            b"GET  / HTTP/1.1\r\n",             // empty target
            b"GET / HTTP/\r\n",                 // no version number
            b"hello world, this is not http\n", // prose
        ] {
            let (out, refused) = run(input, 1);
            assert_eq!(refused, None, "{input:?}");
            assert_eq!(out, input);
        }
    }

    #[test]
    fn an_endless_undecided_first_line_is_refused() {
        let mut input = b"POST /".to_vec();
        input.resize(MAX_HELD_BYTES + 10, b'a');
        let (out, refused) = run(&input, 1000);
        assert!(out.is_empty());
        assert_eq!(refused, Some(HttpRefused::Undecided));
    }
}
