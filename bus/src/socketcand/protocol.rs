//! The socketcand wire format: ASCII elements `< word args… >` over TCP, with no separator
//! between elements (socketcand sends none; some clients add spaces or newlines).
//!
//! Only what raw mode needs is understood: the handshake (`hi`, `open`, `rawmode`, `ok`),
//! `bcmmode`, `echo`, `send` (client to server), `frame` and `error` (server to client).
//!
//! Conventions copied from socketcand and relied on by python-can's `socketcand` interface:
//! - An identifier written with exactly eight hex digits is extended (29-bit); any other
//!   width is standard (11-bit). Frames are written `%03X` or `%08X`.
//! - `send` carries the DLC and then one hex token per data byte (`< send 1AAAAAAA 2 1 F1 >`).
//! - `frame` carries `seconds.microseconds` and the data as one run of hex digits; an empty
//!   payload leaves two spaces before `>` (`< frame 123 1.000000  >`), which python-can needs
//!   to split the element into its three fields.
//!
//! **Classic CAN only.** socketcand's protocol document has no CAN FD element. Newer
//! socketcand sources write `< fdframe ID FLAGS SECS.USECS DATA >` and read
//! `< fdsend ID FLAGS LEN BYTES… >` on CAN FD interfaces, but python-can's `socketcand`
//! interface parses `< frame … >` only (it logs any other element as invalid) and sends only
//! `< send … >`. So nothing here writes or reads a CAN FD form: the server does not forward
//! CAN FD frames (it counts them), the client refuses to send one, and `fdsend` is an unknown
//! command. [`format_send`] and [`format_frame`] are for classic frames; given a CAN FD frame
//! they would write its payload as if classic, which no reader accepts past eight bytes.

use std::fmt::Write as _;
use std::time::Duration;

use crate::{CanFrame, CanId, MAX_DATA_LEN};

/// Longest element accepted, `<` and `>` included. The longest legal raw-mode element
/// (`< send XXXXXXXX 8 xx xx xx xx xx xx xx xx >`) is 43 characters; room is left for bus
/// names and error texts.
pub const MAX_ELEMENT_LEN: usize = 256;

/// A command a client sends to the server.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Command {
    /// `< open NAME >`: select a bus.
    Open(String),
    /// `< rawmode >`: receive every frame on the bus.
    RawMode,
    /// `< bcmmode >`: back to broadcast-manager mode (no frames are forwarded).
    BcmMode,
    /// `< echo >`: the server answers `< echo >`.
    Echo,
    /// `< send ID DLC BYTES… >`: put one frame on the bus.
    Send(CanFrame),
}

/// A message the server sends to a client.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Reply {
    /// `< hi >`: the greeting.
    Hi,
    /// `< ok >`: a command was accepted.
    Ok,
    /// `< echo >`: the answer to `echo`.
    Echo,
    /// `< frame ID SECS.USECS DATA >`: a frame seen on the bus.
    Frame {
        /// The frame.
        frame: CanFrame,
        /// Time since the Unix epoch at which it was received, microsecond resolution.
        timestamp: Duration,
    },
    /// `< error TEXT >`: a command was refused (or, from socketcand, a CAN error frame).
    Error(String),
}

/// Why an element could not be understood.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParseError {
    /// The element does not have the `< … >` shape.
    #[error("not an element (text between angle brackets)")]
    NotAnElement,
    /// The element is empty (`< >`).
    #[error("empty element")]
    Empty,
    /// The first word names no known command or reply.
    #[error("unknown command `{word}`")]
    Unknown {
        /// The first word.
        word: String,
    },
    /// The command has the wrong number of fields.
    #[error("`{word}` takes {expected}, got {got} field(s)")]
    FieldCount {
        /// The command word.
        word: &'static str,
        /// What it takes, in words.
        expected: &'static str,
        /// How many fields followed the word.
        got: usize,
    },
    /// A field that should be hexadecimal is not.
    #[error("`{text}` is not a hex {what}")]
    BadHex {
        /// Which field.
        what: &'static str,
        /// The offending text.
        text: String,
    },
    /// The identifier does not fit its width (3 digits: 11 bits; 8 digits: 29 bits).
    #[error("identifier `{text}` does not fit a {} identifier", if *.extended { "29-bit" } else { "11-bit" })]
    IdOutOfRange {
        /// The identifier as written.
        text: String,
        /// Whether it was read as extended (eight digits).
        extended: bool,
    },
    /// The DLC is not 0–8 or disagrees with the number of data bytes.
    #[error("DLC `{dlc}` does not match {bytes} data byte(s) (classic CAN, 0-8)")]
    BadDlc {
        /// The DLC as written.
        dlc: String,
        /// How many data bytes followed.
        bytes: usize,
    },
    /// The timestamp is not `seconds.microseconds`.
    #[error("`{text}` is not a seconds.microseconds timestamp")]
    BadTimestamp {
        /// The offending text.
        text: String,
    },
}

/// What [`Framer::next_element`] found in the bytes received so far.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Element {
    /// A complete `< … >` element, brackets included.
    Complete(String),
    /// Bytes that cannot start an element (text outside `< >`, or an element longer than
    /// [`MAX_ELEMENT_LEN`]); they were discarded.
    Garbage(String),
}

/// Splits a TCP byte stream into `< … >` elements.
#[derive(Debug, Default)]
pub struct Framer {
    buf: Vec<u8>,
}

impl Framer {
    /// Append received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.buf.extend_from_slice(bytes);
    }

    /// The next element, or `None` when more bytes are needed.
    pub fn next_element(&mut self) -> Option<Element> {
        let leading = self
            .buf
            .iter()
            .take_while(|b| b.is_ascii_whitespace())
            .count();
        self.buf.drain(..leading);
        let first = *self.buf.first()?;
        if first != b'<' {
            // Everything up to the next `<` is junk.
            let end = self
                .buf
                .iter()
                .position(|&b| b == b'<')
                .unwrap_or(self.buf.len());
            return Some(Element::Garbage(self.take(end)));
        }
        match self.buf.iter().position(|&b| b == b'>') {
            Some(end) if end < MAX_ELEMENT_LEN => Some(Element::Complete(self.take(end + 1))),
            Some(_) => Some(Element::Garbage(self.take_overlong())),
            None if self.buf.len() >= MAX_ELEMENT_LEN => {
                Some(Element::Garbage(self.take_overlong()))
            }
            None => None,
        }
    }

    /// Drop an overlong element: up to its `>` if that arrived, else up to the next `<`
    /// after the first byte, else everything.
    fn take_overlong(&mut self) -> String {
        let close = self.buf.iter().position(|&b| b == b'>').map(|i| i + 1);
        let reopen = self
            .buf
            .iter()
            .skip(1)
            .position(|&b| b == b'<')
            .map(|i| i + 1);
        let end = match (close, reopen) {
            (Some(c), Some(r)) => c.min(r),
            (Some(c), None) => c,
            (None, Some(r)) => r,
            (None, None) => self.buf.len(),
        };
        self.take(end)
    }

    fn take(&mut self, n: usize) -> String {
        let bytes: Vec<u8> = self.buf.drain(..n).collect();
        String::from_utf8_lossy(&bytes).into_owned()
    }
}

/// The words between `<` and `>`.
fn words(element: &str) -> Result<Vec<&str>, ParseError> {
    let inner = element
        .trim()
        .strip_prefix('<')
        .and_then(|rest| rest.strip_suffix('>'))
        .ok_or(ParseError::NotAnElement)?;
    let words: Vec<&str> = inner.split_ascii_whitespace().collect();
    if words.is_empty() {
        return Err(ParseError::Empty);
    }
    Ok(words)
}

/// Parse a client command.
pub fn parse_command(element: &str) -> Result<Command, ParseError> {
    let words = words(element)?;
    let fields = &words[1..];
    let exact = |word: &'static str, n: usize, expected: &'static str| {
        if fields.len() == n {
            Ok(())
        } else {
            Err(ParseError::FieldCount {
                word,
                expected,
                got: fields.len(),
            })
        }
    };
    match words[0] {
        "open" => {
            exact("open", 1, "a bus name")?;
            Ok(Command::Open(fields[0].to_owned()))
        }
        "rawmode" => exact("rawmode", 0, "no fields").map(|()| Command::RawMode),
        "bcmmode" => exact("bcmmode", 0, "no fields").map(|()| Command::BcmMode),
        "echo" => exact("echo", 0, "no fields").map(|()| Command::Echo),
        "send" => parse_send(fields).map(Command::Send),
        word => Err(ParseError::Unknown {
            word: word.to_owned(),
        }),
    }
}

fn parse_send(fields: &[&str]) -> Result<CanFrame, ParseError> {
    let [id, dlc, data @ ..] = fields else {
        return Err(ParseError::FieldCount {
            word: "send",
            expected: "an id, a DLC and DLC data bytes",
            got: fields.len(),
        });
    };
    let id = parse_id(id)?;
    let bad_dlc = || ParseError::BadDlc {
        dlc: (*dlc).to_owned(),
        bytes: data.len(),
    };
    // socketcand reads the DLC as decimal and python-can writes it as hex: one digit 0-8
    // reads the same either way.
    let len: usize = dlc.parse().map_err(|_| bad_dlc())?;
    if len > MAX_DATA_LEN || len != data.len() {
        return Err(bad_dlc());
    }
    let mut bytes = [0u8; MAX_DATA_LEN];
    for (slot, text) in bytes.iter_mut().zip(data) {
        *slot = parse_hex_byte(text)?;
    }
    // Cannot fail: the id was range-checked and len <= 8.
    CanFrame::new(id, &bytes[..len]).map_err(|_| bad_dlc())
}

fn parse_hex_byte(text: &str) -> Result<u8, ParseError> {
    let ok = (1..=2).contains(&text.len()) && text.bytes().all(|b| b.is_ascii_hexdigit());
    ok.then(|| u8::from_str_radix(text, 16).ok())
        .flatten()
        .ok_or_else(|| ParseError::BadHex {
            what: "data byte",
            text: text.to_owned(),
        })
}

/// An identifier: eight hex digits are extended, anything else standard.
pub fn parse_id(text: &str) -> Result<CanId, ParseError> {
    let digits_ok = !text.is_empty() && text.bytes().all(|b| b.is_ascii_hexdigit());
    let value = digits_ok
        .then(|| u32::from_str_radix(text, 16).ok())
        .flatten()
        .ok_or_else(|| ParseError::BadHex {
            what: "identifier",
            text: text.to_owned(),
        })?;
    let extended = text.len() == 8;
    let out_of_range = || ParseError::IdOutOfRange {
        text: text.to_owned(),
        extended,
    };
    if extended {
        CanId::extended(value).map_err(|_| out_of_range())
    } else {
        u16::try_from(value)
            .ok()
            .and_then(|v| CanId::standard(v).ok())
            .ok_or_else(out_of_range)
    }
}

/// Parse a server message.
pub fn parse_reply(element: &str) -> Result<Reply, ParseError> {
    let words = words(element)?;
    match words[0] {
        "hi" => Ok(Reply::Hi),
        "ok" => Ok(Reply::Ok),
        "echo" => Ok(Reply::Echo),
        "error" => Ok(Reply::Error(words[1..].join(" "))),
        "frame" => parse_frame(&words[1..]),
        word => Err(ParseError::Unknown {
            word: word.to_owned(),
        }),
    }
}

fn parse_frame(fields: &[&str]) -> Result<Reply, ParseError> {
    let [id, stamp, data @ ..] = fields else {
        return Err(ParseError::FieldCount {
            word: "frame",
            expected: "an id, a timestamp and data",
            got: fields.len(),
        });
    };
    let id = parse_id(id)?;
    let timestamp = parse_timestamp(stamp)?;
    // socketcand writes the data as one run of hex digits; the protocol document shows one
    // token per byte. Both read the same once joined.
    let hex: String = data.concat();
    let bad = || ParseError::BadHex {
        what: "payload",
        text: hex.clone(),
    };
    if !hex.len().is_multiple_of(2) || hex.len() / 2 > MAX_DATA_LEN {
        return Err(bad());
    }
    let mut bytes = [0u8; MAX_DATA_LEN];
    for (i, slot) in bytes.iter_mut().take(hex.len() / 2).enumerate() {
        let pair = hex.get(2 * i..2 * i + 2).ok_or_else(bad)?;
        *slot = parse_hex_byte(pair).map_err(|_| bad())?;
    }
    let frame = CanFrame::new(id, &bytes[..hex.len() / 2]).map_err(|_| bad())?;
    Ok(Reply::Frame { frame, timestamp })
}

fn parse_timestamp(text: &str) -> Result<Duration, ParseError> {
    let bad = || ParseError::BadTimestamp {
        text: text.to_owned(),
    };
    let (secs, frac) = text.split_once('.').unwrap_or((text, ""));
    let digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if secs.is_empty() || !digits(secs) || !digits(frac) || frac.len() > 9 {
        return Err(bad());
    }
    let secs: u64 = secs.parse().map_err(|_| bad())?;
    // Right-pad the fraction to nanoseconds ("5" is 0.5 s).
    let nanos: u32 = if frac.is_empty() {
        0
    } else {
        format!("{frac:0<9}").parse().map_err(|_| bad())?
    };
    Ok(Duration::new(secs, nanos))
}

/// The identifier as socketcand writes it: `%03X` or `%08X`.
fn write_id(out: &mut String, id: CanId) {
    // Writing to a String cannot fail.
    let _ = match id {
        CanId::Standard(id) => write!(out, "{id:03X}"),
        CanId::Extended(id) => write!(out, "{id:08X}"),
    };
}

/// `< send ID DLC BYTES… >` for a frame.
pub fn format_send(frame: &CanFrame) -> String {
    let mut out = String::with_capacity(48);
    out.push_str("< send ");
    write_id(&mut out, frame.id());
    let _ = write!(out, " {}", frame.len());
    for byte in frame.data() {
        let _ = write!(out, " {byte:02X}");
    }
    out.push_str(" >");
    out
}

/// `< frame ID SECS.USECS DATA >` for a received frame (socketcand's exact layout).
pub fn format_frame(frame: &CanFrame, timestamp: Duration) -> String {
    let mut out = String::with_capacity(56);
    out.push_str("< frame ");
    write_id(&mut out, frame.id());
    let _ = write!(
        out,
        " {}.{:06} ",
        timestamp.as_secs(),
        timestamp.subsec_micros()
    );
    for byte in frame.data() {
        let _ = write!(out, "{byte:02X}");
    }
    out.push_str(" >");
    out
}

/// The text of a command.
pub fn format_command(command: &Command) -> String {
    match command {
        Command::Open(name) => format!("< open {name} >"),
        Command::RawMode => "< rawmode >".to_owned(),
        Command::BcmMode => "< bcmmode >".to_owned(),
        Command::Echo => "< echo >".to_owned(),
        Command::Send(frame) => format_send(frame),
    }
}

/// The text of a reply.
pub fn format_reply(reply: &Reply) -> String {
    match reply {
        Reply::Hi => "< hi >".to_owned(),
        Reply::Ok => "< ok >".to_owned(),
        Reply::Echo => "< echo >".to_owned(),
        Reply::Frame { frame, timestamp } => format_frame(frame, *timestamp),
        Reply::Error(text) => format!("< error {} >", wire_text(text)),
    }
}

/// `text` as an element may carry it: `<` and `>` would end the element early, and clients
/// read the stream as ASCII (python-can's backend fails on any other byte), so brackets become
/// `[` `]`, an ellipsis three dots, control characters spaces and anything else outside
/// printable ASCII its `\u{…}` escape. What the text quotes stays quoted.
fn wire_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '<' => out.push('['),
            '>' => out.push(']'),
            '\u{2026}' => out.push_str("..."),
            ' '..='~' => out.push(c),
            c if c.is_control() => out.push(' '),
            c => out.extend(c.escape_unicode()),
        }
    }
    out
}

#[cfg(test)]
mod tests;
