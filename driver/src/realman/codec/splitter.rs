//! Incremental splitter of the TCP byte stream into top-level JSON objects.
//!
//! The controller ends each reply with CRLF, but clients and controllers in the field also send
//! pretty-printed objects (newlines inside), several objects in one segment, or no terminator at
//! all (docs/protocols/realman.md §1). So we split on object boundaries: brace depth, with braces
//! inside strings (and escaped quotes) ignored. Bytes outside any object that are not whitespace
//! are reported as [`Frame::Stray`] so the client can flag a malformed reply.

/// Default maximum size of one object (bytes). The largest documented replies are well under 4 KiB.
pub const DEFAULT_MAX_FRAME: usize = 16 * 1024;

/// One unit cut from the stream.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Frame {
    /// A complete top-level `{…}` object (not yet parsed as JSON).
    Object(String),
    /// Non-whitespace text outside any object, up to the next line end or `{`.
    Stray(String),
    /// An object cut short: a CR LF arrived before its closing brace. The controller's replies
    /// are compact and end with CR LF, so a line end inside an object means the rest was lost;
    /// dropping the fragment there keeps the stream in step with the next reply.
    Truncated(String),
    /// An object longer than the limit was dropped entirely; this many bytes were discarded.
    Overflow {
        /// Bytes thrown away.
        discarded: usize,
    },
}

/// Splitter state; feed bytes with [`Splitter::push`], take frames with [`Splitter::next_frame`].
#[derive(Debug)]
pub struct Splitter {
    buf: Vec<u8>,
    max_frame: usize,
    /// Where scanning of `buf` resumes.
    pos: usize,
    depth: usize,
    in_string: bool,
    escaped: bool,
    /// Bytes of an oversized object that were dropped so far (`Some` while skipping).
    skipping: Option<usize>,
}

impl Default for Splitter {
    fn default() -> Self {
        Self::new(DEFAULT_MAX_FRAME)
    }
}

impl Splitter {
    /// A splitter that drops objects longer than `max_frame` bytes.
    pub fn new(max_frame: usize) -> Self {
        Self {
            buf: Vec::new(),
            max_frame: max_frame.max(2),
            pos: 0,
            depth: 0,
            in_string: false,
            escaped: false,
            skipping: None,
        }
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// Bytes buffered and not yet returned.
    pub fn buffered(&self) -> usize {
        self.buf.len()
    }

    /// The next complete frame, if the buffer holds one.
    pub fn next_frame(&mut self) -> Option<Frame> {
        loop {
            if self.skipping.is_some() {
                if let Some(frame) = self.skip_oversized() {
                    return Some(frame);
                }
                return None;
            }
            if self.depth == 0 {
                match self.scan_outside() {
                    Outside::Frame(f) => return Some(f),
                    Outside::ObjectStart => {}
                    Outside::NeedMore => return None,
                }
            }
            match self.scan_object() {
                Some(frame) => return Some(frame),
                None if self.skipping.is_some() => continue,
                None => return None,
            }
        }
    }

    /// Skips whitespace before an object; cuts stray text. Leaves `buf[0]` at `{` with depth 1.
    fn scan_outside(&mut self) -> Outside {
        let lead = self
            .buf
            .iter()
            .take_while(|b| b.is_ascii_whitespace())
            .count();
        self.buf.drain(..lead);
        let Some(&first) = self.buf.first() else {
            return Outside::NeedMore;
        };
        if first == b'{' {
            self.depth = 1;
            self.pos = 1;
            return Outside::ObjectStart;
        }
        // Stray text ends at a line end, at the next object, or after `max_frame` bytes,
        // whichever comes first. Looking only at the first `max_frame` bytes makes the cut the
        // same however the stream was segmented (a whole-buffer search would let a stray run
        // past the limit when its line end happened to arrive in the same read).
        let window = &self.buf[..self.buf.len().min(self.max_frame)];
        let end = match window.iter().position(|&b| b == b'\n' || b == b'{') {
            Some(e) => e,
            None if self.buf.len() >= self.max_frame => self.max_frame,
            None => return Outside::NeedMore,
        };
        let stray: Vec<u8> = self.buf.drain(..end).collect();
        let text = String::from_utf8_lossy(&stray).trim().to_string();
        Outside::Frame(Frame::Stray(text))
    }

    /// Continues scanning an object; returns it when its closing brace arrives.
    fn scan_object(&mut self) -> Option<Frame> {
        while self.pos < self.buf.len() {
            let b = self.buf[self.pos];
            self.pos += 1;
            if b == b'\n' && self.pos >= 2 && self.buf[self.pos - 2] == b'\r' {
                let bytes: Vec<u8> = self.buf.drain(..self.pos).collect();
                self.pos = 0;
                self.depth = 0;
                self.in_string = false;
                self.escaped = false;
                let text = String::from_utf8_lossy(&bytes).trim_end().to_string();
                return Some(Frame::Truncated(text));
            }
            if self.step(b) {
                let bytes: Vec<u8> = self.buf.drain(..self.pos).collect();
                self.pos = 0;
                return Some(Frame::Object(String::from_utf8_lossy(&bytes).into_owned()));
            }
            if self.pos > self.max_frame {
                // Too long: forget what we have and skip the rest of this object.
                self.skipping = Some(self.pos);
                self.buf.drain(..self.pos);
                self.pos = 0;
                return None;
            }
        }
        None
    }

    /// Drops the remainder of an oversized object, tracking depth to find its end.
    fn skip_oversized(&mut self) -> Option<Frame> {
        let mut consumed = 0;
        let mut done = false;
        for i in 0..self.buf.len() {
            consumed += 1;
            if self.step(self.buf[i]) {
                done = true;
                break;
            }
        }
        self.buf.drain(..consumed);
        let discarded = self.skipping.as_mut()?;
        *discarded += consumed;
        if done {
            let discarded = *discarded;
            self.skipping = None;
            return Some(Frame::Overflow { discarded });
        }
        None
    }

    /// Feeds one byte inside an object; true when the object closed.
    fn step(&mut self, b: u8) -> bool {
        if self.in_string {
            if self.escaped {
                self.escaped = false;
            } else if b == b'\\' {
                self.escaped = true;
            } else if b == b'"' {
                self.in_string = false;
            }
            return false;
        }
        match b {
            b'"' => self.in_string = true,
            b'{' => self.depth += 1,
            b'}' => {
                self.depth = self.depth.saturating_sub(1);
                return self.depth == 0;
            }
            _ => {}
        }
        false
    }
}

enum Outside {
    Frame(Frame),
    ObjectStart,
    NeedMore,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(s: &mut Splitter) -> Vec<Frame> {
        std::iter::from_fn(|| s.next_frame()).collect()
    }

    #[test]
    fn splits_coalesced_pretty_and_unterminated_objects() {
        let mut s = Splitter::default();
        s.push(b"{\"a\":1}\r\n{\n\t\"b\":\t{\"c\": \"}{\\\"\"}\n}\r\n{\"d\":");
        let got = all(&mut s);
        assert_eq!(
            got,
            vec![
                Frame::Object("{\"a\":1}".into()),
                Frame::Object("{\n\t\"b\":\t{\"c\": \"}{\\\"\"}\n}".into()),
            ]
        );
        s.push(b"2}");
        assert_eq!(all(&mut s), vec![Frame::Object("{\"d\":2}".into())]);
        assert_eq!(s.buffered(), 0);
    }

    #[test]
    fn byte_by_byte_matches_whole() {
        let text = b"{\"x\":\"a{b\"}\r\n  {\"y\":[1,{\"z\":2}]}";
        let mut s = Splitter::default();
        let mut got = Vec::new();
        for b in text {
            s.push(&[*b]);
            got.extend(all(&mut s));
        }
        assert_eq!(got.len(), 2);
        assert_eq!(got[1], Frame::Object("{\"y\":[1,{\"z\":2}]}".into()));
    }

    #[test]
    fn stray_text_and_overflow_resynchronise() {
        let mut s = Splitter::new(32);
        s.push(b"garbage\r\n{\"big\":\"");
        s.push(&[b'x'; 100]);
        s.push(b"\",\"n\":{}}\r\n{\"ok\":true}\r\n");
        let got = all(&mut s);
        assert_eq!(got[0], Frame::Stray("garbage".into()));
        assert!(matches!(got[1], Frame::Overflow { discarded } if discarded > 100));
        assert_eq!(got[2], Frame::Object("{\"ok\":true}".into()));
        assert_eq!(got.len(), 3);
    }

    #[test]
    fn a_line_end_inside_an_object_ends_it_as_truncated() {
        let mut s = Splitter::default();
        s.push(b"{\"state\":\"joint_de\r\n{\"ok\":true}\r\n{\"a\":{\"b\":1\r\n{\"c\":2}");
        assert_eq!(
            all(&mut s),
            vec![
                Frame::Truncated("{\"state\":\"joint_de".into()),
                Frame::Object("{\"ok\":true}".into()),
                Frame::Truncated("{\"a\":{\"b\":1".into()),
                Frame::Object("{\"c\":2}".into()),
            ]
        );
    }

    #[test]
    fn endless_stray_text_is_bounded() {
        let mut s = Splitter::new(16);
        s.push(&[b'q'; 40]);
        assert_eq!(
            all(&mut s),
            vec![Frame::Stray("q".repeat(16)), Frame::Stray("q".repeat(16))]
        );
        assert_eq!(
            s.buffered(),
            8,
            "the last 8 bytes wait for more or a line end"
        );
    }

    /// Found by the `realman_reply` fuzz target: a stray run longer than the limit whose line
    /// end arrives in the same read as the limit was cut at the line end when read whole but
    /// at the limit when read byte by byte.
    #[test]
    fn long_stray_text_is_cut_the_same_however_the_stream_arrives() {
        let mut stream = vec![b'x'; 40];
        stream.extend_from_slice(b"true}\r\n{\"ok\":1}\r\n");
        let mut whole = Splitter::new(16);
        whole.push(&stream);
        let whole = all(&mut whole);
        let mut bytewise = Splitter::new(16);
        let mut pieces = Vec::new();
        for b in &stream {
            bytewise.push(&[*b]);
            pieces.extend(all(&mut bytewise));
        }
        assert_eq!(whole, pieces);
        assert_eq!(
            whole,
            vec![
                Frame::Stray("x".repeat(16)),
                Frame::Stray("x".repeat(16)),
                Frame::Stray("xxxxxxxxtrue}".into()),
                Frame::Object("{\"ok\":1}".into()),
            ]
        );
    }
}
