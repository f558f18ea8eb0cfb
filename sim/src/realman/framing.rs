//! Splitting the TCP byte stream into requests (docs/protocols/realman.md §1).
//!
//! Clients terminate a request with CRLF, but some send pretty-printed objects (newlines and
//! tabs inside the object), some send no terminator at all, and several requests can share one
//! TCP segment. So a request is one complete top-level JSON object, found by counting braces
//! outside string literals (escapes respected); CR, LF and other whitespace between objects are
//! skipped. Any other byte outside an object is junk: it is collected up to the next line end and
//! handed out as such, so the caller can log it.
//!
//! A CR LF pair outside a string always ends a request, as on the controller: an object still
//! open at that point was truncated, and is handed out as junk instead of swallowing the
//! requests that follow. Pretty-printed requests use bare LF inside the object (cJSON), so
//! they are unaffected.

/// Longest request (or junk line) kept in memory; a longer one closes the connection.
pub const MAX_REQUEST_BYTES: usize = 1 << 20;

/// One unit taken out of the stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Unit {
    /// The bytes of one complete top-level `{…}` object (not yet parsed).
    Object(Vec<u8>),
    /// Bytes outside any object, up to a line end (never a reply is due for them).
    Junk(Vec<u8>),
}

/// The peer sent more than [`MAX_REQUEST_BYTES`] without completing a request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("request longer than {limit_bytes} bytes without an end")]
pub struct Oversize {
    /// The limit that was exceeded.
    pub limit_bytes: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scan {
    /// Between units.
    Idle,
    /// Inside an object at this brace depth (≥ 1).
    Object {
        depth: u32,
        in_string: bool,
        escaped: bool,
    },
    /// Inside a junk run, until a line end.
    Junk,
}

/// Incremental splitter: feed bytes as they arrive, take units as they complete.
#[derive(Debug, Clone)]
pub struct Splitter {
    current: Vec<u8>,
    scan: Scan,
    limit_bytes: usize,
}

impl Default for Splitter {
    fn default() -> Self {
        Self::new(MAX_REQUEST_BYTES)
    }
}

impl Splitter {
    /// A splitter that refuses units longer than `limit_bytes`.
    pub fn new(limit_bytes: usize) -> Self {
        Self {
            current: Vec::new(),
            scan: Scan::Idle,
            limit_bytes,
        }
    }

    /// Bytes of the unit in progress (0 between units).
    pub fn pending_bytes(&self) -> usize {
        self.current.len()
    }

    /// Consume `bytes`, appending every unit completed by them to `out`.
    pub fn feed(&mut self, bytes: &[u8], out: &mut Vec<Unit>) -> Result<(), Oversize> {
        for &byte in bytes {
            let before = out.len();
            self.step(byte, out);
            // The closing brace hands the object out at once: check what was handed out too
            // (an object one byte over the limit used to pass; found by realman_framing).
            let completed_too_long = out.len() > before
                && matches!(out.last(), Some(Unit::Object(b)) if b.len() > self.limit_bytes);
            if completed_too_long {
                out.pop();
            }
            if completed_too_long || self.current.len() > self.limit_bytes {
                self.current = Vec::new();
                self.scan = Scan::Idle;
                return Err(Oversize {
                    limit_bytes: self.limit_bytes,
                });
            }
        }
        Ok(())
    }

    fn step(&mut self, byte: u8, out: &mut Vec<Unit>) {
        match self.scan {
            Scan::Idle => match byte {
                b'{' => {
                    self.current.push(byte);
                    self.scan = Scan::Object {
                        depth: 1,
                        in_string: false,
                        escaped: false,
                    };
                }
                b' ' | b'\t' | b'\r' | b'\n' | 0 => {}
                _ => {
                    self.current.push(byte);
                    self.scan = Scan::Junk;
                }
            },
            Scan::Junk => {
                if byte == b'\n' {
                    out.push(Unit::Junk(std::mem::take(&mut self.current)));
                    self.scan = Scan::Idle;
                } else {
                    self.current.push(byte);
                }
            }
            Scan::Object {
                depth,
                in_string,
                escaped,
            } => {
                if byte == b'\n' && !in_string && self.current.last() == Some(&b'\r') {
                    out.push(Unit::Junk(std::mem::take(&mut self.current)));
                    self.scan = Scan::Idle;
                    return;
                }
                self.current.push(byte);
                self.scan = match (in_string, escaped, byte) {
                    (true, true, _) => Scan::Object {
                        depth,
                        in_string,
                        escaped: false,
                    },
                    (true, false, b'\\') => Scan::Object {
                        depth,
                        in_string,
                        escaped: true,
                    },
                    (true, false, b'"') | (false, _, b'"') => Scan::Object {
                        depth,
                        in_string: !in_string,
                        escaped: false,
                    },
                    (false, _, b'{') => Scan::Object {
                        depth: depth + 1,
                        in_string,
                        escaped: false,
                    },
                    (false, _, b'}') if depth == 1 => {
                        out.push(Unit::Object(std::mem::take(&mut self.current)));
                        Scan::Idle
                    }
                    (false, _, b'}') => Scan::Object {
                        depth: depth - 1,
                        in_string,
                        escaped: false,
                    },
                    _ => self.scan,
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(chunks: &[&[u8]]) -> Vec<Unit> {
        let mut splitter = Splitter::default();
        let mut out = Vec::new();
        for chunk in chunks {
            splitter.feed(chunk, &mut out).unwrap();
        }
        out
    }

    fn obj(text: &str) -> Unit {
        Unit::Object(text.as_bytes().to_vec())
    }

    #[test]
    fn several_objects_in_one_chunk_with_and_without_crlf() {
        let units = split(&[b"{\"a\":1}\r\n{\"b\":2}{\"c\":3}\r\n"]);
        assert_eq!(
            units,
            vec![obj("{\"a\":1}"), obj("{\"b\":2}"), obj("{\"c\":3}")]
        );
    }

    #[test]
    fn pretty_printed_object_split_across_chunks() {
        let units = split(&[
            b"{\n\t\"command\":\t\"movec\",\n\t\"pose\":\t{",
            b"\n\t\t\"x\": 1\n\t}\n}\r\n",
        ]);
        assert_eq!(
            units,
            vec![obj(
                "{\n\t\"command\":\t\"movec\",\n\t\"pose\":\t{\n\t\t\"x\": 1\n\t}\n}"
            )]
        );
    }

    #[test]
    fn braces_and_escaped_quotes_inside_strings_do_not_count() {
        let units = split(&[br#"{"s":"}{\"}"}{"t":1}"#]);
        assert_eq!(units, vec![obj(r#"{"s":"}{\"}"}"#), obj(r#"{"t":1}"#)]);
    }

    #[test]
    fn junk_outside_objects_is_reported_per_line() {
        let units = split(&[b"hello\r\n{\"a\":1}"]);
        assert_eq!(
            units,
            vec![Unit::Junk(b"hello\r".to_vec()), obj("{\"a\":1}")]
        );
    }

    #[test]
    fn crlf_inside_an_open_object_ends_it_as_junk() {
        let units = split(&[b"{\"command\":\"get_joint_degree\"\r\n{\"a\":1}\r\n"]);
        assert_eq!(
            units,
            vec![
                Unit::Junk(b"{\"command\":\"get_joint_degree\"\r".to_vec()),
                obj("{\"a\":1}")
            ]
        );
    }

    #[test]
    fn oversize_unit_is_refused_and_the_splitter_recovers() {
        let mut splitter = Splitter::new(16);
        let mut out = Vec::new();
        let err = splitter.feed(&[b'x'; 40], &mut out).unwrap_err();
        assert_eq!(err.limit_bytes, 16);
        assert_eq!(splitter.pending_bytes(), 0);
        splitter.feed(b"{\"a\":1}", &mut out).unwrap();
        assert_eq!(out, vec![obj("{\"a\":1}")]);
    }

    #[test]
    fn an_object_is_refused_from_one_byte_over_the_limit() {
        let at_limit = format!("{{\"a\":\"{}\"}}", "x".repeat(8));
        assert_eq!(at_limit.len(), 16);
        let mut out = Vec::new();
        Splitter::new(16)
            .feed(at_limit.as_bytes(), &mut out)
            .unwrap();
        assert_eq!(out, vec![obj(&at_limit)]);
        let over = format!("{{\"a\":\"{}\"}}", "x".repeat(9));
        let mut out = Vec::new();
        let mut splitter = Splitter::new(16);
        assert!(splitter.feed(over.as_bytes(), &mut out).is_err());
        assert!(out.is_empty());
        assert_eq!(splitter.pending_bytes(), 0);
    }
}
