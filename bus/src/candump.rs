//! candump `-L` log files: a writer byte-compatible with can-utils and a reader for replay and
//! test fixtures.
//!
//! One frame per line: `(1700000000.123456) vcan0 2A1#0011223344556677`. Seconds are padded
//! to ten digits and microseconds to six, as `candump -L` prints them; standard identifiers
//! take three hex digits, extended ones eight; data bytes are upper-case hex pairs.
//!
//! CAN FD frames take can-utils' `##` form: `123##1AABBCC`, where the one hex digit after `##`
//! is the frame's flags (BRS 1, ESI 2; the reader also accepts the FDF bit 4 newer can-utils
//! print, and refuses 8 and above) and the data follows as for a classic frame, in one of the
//! CAN FD lengths (0-8, 12, 16, 20, 24, 32, 48, 64 bytes; any other is refused, naming the
//! length).
//!
//! The reader skips blank lines and lines starting with `#` (the project's fixture files use
//! them for comments). It also accepts `.` between data bytes and an optional trailing `R` or
//! `T` direction marker, as newer can-utils accept. Remote frames are reported as unsupported:
//! the bus carries data frames only.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::{CanFrame, CanId, FdFlags, FrameError, ReceivedFrame, MAX_STANDARD_ID};

/// One frame of a candump log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogEntry {
    /// The logged timestamp (time since the Unix epoch in real captures).
    pub timestamp: Duration,
    /// The interface name, e.g. `vcan0`.
    pub iface: String,
    /// The frame.
    pub frame: CanFrame,
}

/// Why one line of a candump log could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LineError {
    /// The line does not start with `(seconds.fraction)`.
    #[error("expected a timestamp like (1700000000.123456)")]
    BadTimestamp,
    /// No interface name after the timestamp.
    #[error("missing interface name")]
    MissingInterface,
    /// No frame after the interface name.
    #[error("missing frame")]
    MissingFrame,
    /// The frame has no `#` between identifier and data.
    #[error("frame {0:?} has no '#'")]
    MissingHash(String),
    /// The identifier is not 3 (standard) or 8 (extended) hex digits, or is out of range.
    #[error("bad CAN identifier {0:?}")]
    BadId(String),
    /// The data is not hex byte pairs, or longer than eight bytes.
    #[error("bad data {0:?}")]
    BadData(String),
    /// A remote frame, which the bus does not carry.
    #[error("unsupported frame {0:?} (remote frames are not supported)")]
    Unsupported(String),
    /// A CAN FD frame whose flag digit (the one after `##`) is missing or not 0-7.
    #[error("bad CAN FD flags in {0:?} (one hex digit after '##': 0-7, BRS 1, ESI 2, FDF 4)")]
    BadFdFlags(String),
    /// A CAN FD frame whose payload has a length no CAN FD frame has.
    #[error(
        "CAN FD frame {frame:?} has {len} data bytes; a CAN FD frame has 0-8, 12, 16, 20, 24, \
         32, 48 or 64"
    )]
    BadFdLength {
        /// The frame as written.
        frame: String,
        /// The number of data bytes it has.
        len: usize,
    },
    /// Unexpected text after the frame.
    #[error("unexpected text after the frame: {0:?}")]
    TrailingText(String),
}

/// Why a candump log could not be read.
#[derive(Debug, thiserror::Error)]
pub enum CandumpError {
    /// The file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// A line is not a candump log line.
    #[error("line {line}: {error}")]
    Malformed {
        /// 1-based line number.
        line: usize,
        /// What is wrong with it.
        #[source]
        error: LineError,
    },
}

/// Format one frame as a candump `-L` line, without the newline.
pub fn format_line(iface: &str, received: &ReceivedFrame) -> String {
    let mut line = String::with_capacity(40 + 2 * received.frame.len());
    // Writing to a String cannot fail.
    let _ = write!(
        line,
        "({:010}.{:06}) {iface} {}",
        received.timestamp.as_secs(),
        received.timestamp.subsec_micros(),
        received.frame
    );
    line
}

/// Writes frames to a candump `-L` log.
#[derive(Debug)]
pub struct CandumpWriter<W: Write> {
    out: W,
    iface: String,
}

impl CandumpWriter<BufWriter<File>> {
    /// Create (or truncate) a log file; every line is written with `iface` as interface name.
    pub fn create(path: impl AsRef<Path>, iface: &str) -> io::Result<Self> {
        Ok(Self::new(BufWriter::new(File::create(path)?), iface))
    }
}

impl<W: Write> CandumpWriter<W> {
    /// Write to any byte sink; every line carries `iface` as interface name.
    pub fn new(out: W, iface: &str) -> Self {
        Self {
            out,
            iface: iface.to_owned(),
        }
    }

    /// Append one frame.
    pub fn write(&mut self, received: &ReceivedFrame) -> io::Result<()> {
        writeln!(self.out, "{}", format_line(&self.iface, received))
    }

    /// Append one frame seen on `iface` (a log of several buses names each line's).
    pub fn write_on(&mut self, iface: &str, received: &ReceivedFrame) -> io::Result<()> {
        writeln!(self.out, "{}", format_line(iface, received))
    }

    /// Push buffered lines to the underlying sink.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The sink being written (e.g. to ask a counting writer how much has been written).
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    /// Flush and hand back the sink; the log is complete.
    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

/// Read a candump log file.
pub fn read_log(path: impl AsRef<Path>) -> Result<Vec<LogEntry>, CandumpError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| CandumpError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_log(&text)
}

/// Parse the text of a candump log, skipping blank lines and `#` comments.
pub fn parse_log(text: &str) -> Result<Vec<LogEntry>, CandumpError> {
    let mut entries = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let entry = parse_line(trimmed).map_err(|error| CandumpError::Malformed {
            line: index + 1,
            error,
        })?;
        entries.push(entry);
    }
    Ok(entries)
}

/// Parse one candump `-L` line.
pub fn parse_line(line: &str) -> Result<LogEntry, LineError> {
    let mut tokens = line.split_whitespace();
    let timestamp = parse_timestamp(tokens.next().ok_or(LineError::BadTimestamp)?)?;
    let iface = tokens.next().ok_or(LineError::MissingInterface)?.to_owned();
    let frame = parse_frame(tokens.next().ok_or(LineError::MissingFrame)?)?;
    match tokens.next() {
        None | Some("R" | "T") => {}
        Some(other) => return Err(LineError::TrailingText(other.to_owned())),
    }
    if let Some(other) = tokens.next() {
        return Err(LineError::TrailingText(other.to_owned()));
    }
    Ok(LogEntry {
        timestamp,
        iface,
        frame,
    })
}

fn parse_timestamp(token: &str) -> Result<Duration, LineError> {
    let inner = token
        .strip_prefix('(')
        .and_then(|rest| rest.strip_suffix(')'))
        .ok_or(LineError::BadTimestamp)?;
    let (secs, fraction) = inner.split_once('.').ok_or(LineError::BadTimestamp)?;
    let all_digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !all_digits(secs) || !all_digits(fraction) || fraction.len() > 9 {
        return Err(LineError::BadTimestamp);
    }
    let secs: u64 = secs.parse().map_err(|_| LineError::BadTimestamp)?;
    let fraction_value: u32 = fraction.parse().map_err(|_| LineError::BadTimestamp)?;
    // Scale the fraction to nanoseconds: "123456" means 123456 µs, "5" means 0.5 s.
    let nanos = fraction_value * 10u32.pow(9 - fraction.len() as u32);
    Ok(Duration::new(secs, nanos))
}

/// Parse `ID#DATA` (classic) or `ID##FDATA` (CAN FD, `F` the flags digit) as can-utils
/// writes them.
pub fn parse_frame(token: &str) -> Result<CanFrame, LineError> {
    let (id_text, data_text) = token
        .split_once('#')
        .ok_or_else(|| LineError::MissingHash(token.to_owned()))?;
    let bad_id = || LineError::BadId(id_text.to_owned());
    if !id_text.bytes().all(|b| b.is_ascii_hexdigit()) {
        return Err(bad_id());
    }
    let raw = u32::from_str_radix(id_text, 16).map_err(|_| bad_id())?;
    let id = match id_text.len() {
        3 if raw <= u32::from(MAX_STANDARD_ID) => CanId::Standard(raw as u16),
        8 => CanId::extended(raw).map_err(|_| bad_id())?,
        _ => return Err(bad_id()),
    };
    if data_text.starts_with(['R', 'r']) {
        return Err(LineError::Unsupported(token.to_owned()));
    }
    if let Some(fd_text) = data_text.strip_prefix('#') {
        return parse_fd(token, id, fd_text);
    }
    let data = parse_data(data_text)?;
    CanFrame::new(id, &data).map_err(|_| LineError::BadData(data_text.to_owned()))
}

/// The CAN FD part after `ID##`: the flags digit, then the data.
fn parse_fd(token: &str, id: CanId, fd_text: &str) -> Result<CanFrame, LineError> {
    let bad_flags = || LineError::BadFdFlags(token.to_owned());
    let mut chars = fd_text.chars();
    let flags = chars
        .next()
        .and_then(|digit| digit.to_digit(16))
        .filter(|&bits| bits <= 7)
        .ok_or_else(bad_flags)?;
    // Cannot truncate: at most 7.
    let flags = FdFlags::from_bits(flags as u8);
    let data = parse_data(chars.as_str())?;
    CanFrame::fd(id, &data, flags).map_err(|error| match error {
        FrameError::BadFdLength { len } => LineError::BadFdLength {
            frame: token.to_owned(),
            len,
        },
        _ => LineError::BadData(chars.as_str().to_owned()),
    })
}

/// Hex byte pairs, `.` allowed between them, however many (the frame checks the length).
fn parse_data(data_text: &str) -> Result<Vec<u8>, LineError> {
    let bad_data = || LineError::BadData(data_text.to_owned());
    let digits: Vec<u8> = data_text.bytes().filter(|&b| b != b'.').collect();
    if !digits.len().is_multiple_of(2) {
        return Err(bad_data());
    }
    let mut data = Vec::with_capacity(digits.len() / 2);
    for pair in digits.chunks(2) {
        let text = std::str::from_utf8(pair).map_err(|_| bad_data())?;
        if !text.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(bad_data());
        }
        data.push(u8::from_str_radix(text, 16).map_err(|_| bad_data())?);
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn received(frame: CanFrame, secs: u64, micros: u32) -> ReceivedFrame {
        ReceivedFrame {
            frame,
            timestamp: Duration::new(secs, micros * 1000),
        }
    }

    #[test]
    fn writes_lines_like_candump() {
        let frame =
            CanFrame::standard(0x2A1, &[0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77]).unwrap();
        assert_eq!(
            format_line("vcan0", &received(frame, 1_700_000_000, 123_456)),
            "(1700000000.123456) vcan0 2A1#0011223344556677"
        );
        let frame = CanFrame::extended(0x0200_FD01, &[0xAB]).unwrap();
        assert_eq!(
            format_line("can1", &received(frame, 5, 7)),
            "(0000000005.000007) can1 0200FD01#AB"
        );
        let empty = CanFrame::standard(0x7, &[]).unwrap();
        assert_eq!(
            format_line("vcan0", &received(empty, 0, 0)),
            "(0000000000.000000) vcan0 007#"
        );
    }

    #[test]
    fn writer_output_round_trips_through_the_reader() {
        let frames = [
            received(CanFrame::standard(0x000, &[]).unwrap(), 1, 0),
            received(CanFrame::standard(0x7FF, &[0xFF; 8]).unwrap(), 1, 999_999),
            received(
                CanFrame::extended(0x1FFF_FFFF, &[1, 2, 3]).unwrap(),
                1_700_000_000,
                42,
            ),
            received(CanFrame::extended(0x7, &[0xDE, 0xAD]).unwrap(), 2, 500_000),
        ];
        let mut writer = CandumpWriter::new(Vec::new(), "vcan0");
        for frame in &frames {
            writer.write(frame).unwrap();
        }
        let text = String::from_utf8(writer.finish().unwrap()).unwrap();
        let entries = parse_log(&text).unwrap();
        assert_eq!(entries.len(), frames.len());
        for (entry, original) in entries.iter().zip(&frames) {
            assert_eq!(entry.frame, original.frame);
            assert_eq!(entry.timestamp, original.timestamp);
            assert_eq!(entry.iface, "vcan0");
        }
    }

    #[test]
    fn skips_comments_and_blank_lines_and_numbers_errors_by_line() {
        let text = "# request\n\n  \n(0.000100) vcan0 123#01.02\n# reply\n(0.5) vcan0 1234#00\n";
        match parse_log(text) {
            Err(CandumpError::Malformed { line, error }) => {
                assert_eq!(line, 6);
                assert_eq!(error, LineError::BadId("1234".into()));
            }
            other => panic!("expected a malformed line, got {other:?}"),
        }
        let entries = parse_log(&text.replace("1234#00", "12345678#00 R")).unwrap();
        assert_eq!(entries.len(), 2);
        assert_eq!(entries[0].frame.data(), &[1, 2]);
        assert_eq!(entries[0].timestamp, Duration::from_micros(100));
        assert_eq!(entries[1].timestamp, Duration::from_millis(500));
        assert!(entries[1].frame.is_extended());
    }

    #[test]
    fn rejects_malformed_lines_with_a_reason() {
        let cases = [
            ("1.0 vcan0 123#00", LineError::BadTimestamp),
            ("(1.x) vcan0 123#00", LineError::BadTimestamp),
            ("(1.0)", LineError::MissingInterface),
            ("(1.0) vcan0", LineError::MissingFrame),
            ("(1.0) vcan0 12300", LineError::MissingHash("12300".into())),
            ("(1.0) vcan0 800#00", LineError::BadId("800".into())),
            ("(1.0) vcan0 2FFFFFFF#", LineError::BadId("2FFFFFFF".into())),
            ("(1.0) vcan0 12G#00", LineError::BadId("12G".into())),
            ("(1.0) vcan0 123#0", LineError::BadData("0".into())),
            ("(1.0) vcan0 123#zz", LineError::BadData("zz".into())),
            (
                "(1.0) vcan0 123#000000000000000000",
                LineError::BadData("000000000000000000".into()),
            ),
            ("(1.0) vcan0 123#R", LineError::Unsupported("123#R".into())),
            ("(1.0) vcan0 123##", LineError::BadFdFlags("123##".into())),
            (
                "(1.0) vcan0 123##8AA",
                LineError::BadFdFlags("123##8AA".into()),
            ),
            ("(1.0) vcan0 123##G", LineError::BadFdFlags("123##G".into())),
            ("(1.0) vcan0 123##1A", LineError::BadData("A".into())),
            ("(1.0) vcan0 123##1ZZ", LineError::BadData("ZZ".into())),
            (
                "(1.0) vcan0 123##1000000000000000000",
                LineError::BadFdLength {
                    frame: "123##1000000000000000000".into(),
                    len: 9,
                },
            ),
            ("(1.0) vcan0 123#00 X", LineError::TrailingText("X".into())),
        ];
        for (line, expected) in cases {
            assert_eq!(parse_line(line), Err(expected), "{line}");
        }
    }

    #[test]
    fn read_log_reports_missing_files() {
        let missing = std::env::temp_dir().join("armhil-no-such-file.log");
        assert!(matches!(read_log(&missing), Err(CandumpError::Io { .. })));
    }

    fn fd(id: CanId, len: usize, brs: bool, esi: bool) -> CanFrame {
        let data: Vec<u8> = (0..len).map(|i| i as u8).collect();
        CanFrame::fd(id, &data, FdFlags { brs, esi }).unwrap()
    }

    #[test]
    fn writes_fd_frames_in_the_double_hash_form() {
        let frame = CanFrame::fd(
            CanId::Standard(0x123),
            &[0xAA, 0xBB, 0xCC],
            FdFlags {
                brs: true,
                esi: false,
            },
        )
        .unwrap();
        assert_eq!(
            format_line("vcan0", &received(frame, 1_700_000_000, 1)),
            "(1700000000.000001) vcan0 123##1AABBCC"
        );
        let frame = fd(CanId::Extended(0x0200_FD01), 0, false, true);
        assert_eq!(
            format_line("can1", &received(frame, 5, 7)),
            "(0000000005.000007) can1 0200FD01##2"
        );
        let line = format_line(
            "can0",
            &received(fd(CanId::Standard(1), 64, true, true), 0, 0),
        );
        assert_eq!(line.len(), "(0000000000.000000) can0 001##3".len() + 128);
        assert!(line.ends_with("3C3D3E3F"), "{line}");
    }

    #[test]
    fn fd_frames_round_trip_with_their_flags_and_classic_ones_stay_classic() {
        let mut frames = Vec::new();
        for (i, &len) in crate::FD_DATA_LENS.iter().enumerate() {
            let id = if i % 2 == 0 {
                CanId::Standard(0x100 + i as u16)
            } else {
                CanId::Extended(0x1000_0000 + i as u32)
            };
            frames.push(received(fd(id, len, i % 3 == 0, i % 4 == 1), 1, i as u32));
        }
        frames.push(received(CanFrame::standard(0x7FF, &[1; 8]).unwrap(), 2, 0));
        frames.push(received(CanFrame::extended(0x5, &[]).unwrap(), 2, 1));
        let mut writer = CandumpWriter::new(Vec::new(), "vcan0");
        for frame in &frames {
            writer.write(frame).unwrap();
        }
        let text = String::from_utf8(writer.finish().unwrap()).unwrap();
        let entries = parse_log(&text).unwrap();
        assert_eq!(entries.len(), frames.len());
        for (entry, original) in entries.iter().zip(&frames) {
            assert_eq!(entry.frame, original.frame);
            assert_eq!(entry.frame.is_fd(), original.frame.is_fd());
            assert_eq!(entry.frame.fd_flags(), original.frame.fd_flags());
            assert_eq!(entry.timestamp, original.timestamp);
        }
        // The classic lines are written as before: one '#'.
        assert!(text.contains(" vcan0 7FF#0101010101010101\n"), "{text}");
        assert!(text.contains(" vcan0 00000005#\n"), "{text}");
    }

    #[test]
    fn reads_fd_flags_as_can_utils_writes_them() {
        // FDF (4), which newer can-utils print with the other flags, is implied and ignored.
        for (digit, brs, esi) in [
            ('0', false, false),
            ('1', true, false),
            ('2', false, true),
            ('3', true, true),
            ('4', false, false),
            ('5', true, false),
            ('7', true, true),
        ] {
            let frame = parse_frame(&format!("123##{digit}11.22")).unwrap();
            assert!(frame.is_fd());
            assert_eq!(frame.fd_flags(), Some(FdFlags { brs, esi }), "{digit}");
            assert_eq!(frame.data(), &[0x11, 0x22]);
        }
        // Lower case digits, as can-utils accepts them.
        assert_eq!(
            parse_frame("1abcdef0##1aabb").unwrap(),
            fd_bytes(CanId::Extended(0x1ABC_DEF0), &[0xAA, 0xBB])
        );
    }

    fn fd_bytes(id: CanId, data: &[u8]) -> CanFrame {
        CanFrame::fd(
            id,
            data,
            FdFlags {
                brs: true,
                esi: false,
            },
        )
        .unwrap()
    }

    #[test]
    fn a_bad_fd_length_names_the_line_and_the_length() {
        let twelve = "00".repeat(12);
        let thirteen = "00".repeat(13);
        let text =
            format!("(1.0) vcan0 123##1{twelve}\n# a comment\n(1.1) vcan0 123##1{thirteen}\n");
        let error = parse_log(&text).unwrap_err();
        assert!(
            matches!(
                &error,
                CandumpError::Malformed {
                    line: 3,
                    error: LineError::BadFdLength { len: 13, .. }
                }
            ),
            "{error:?}"
        );
        let message = error.to_string();
        assert!(
            message.starts_with("line 3: CAN FD frame \"123##1"),
            "{message}"
        );
        assert!(
            message.ends_with(
                "has 13 data bytes; a CAN FD frame has 0-8, 12, 16, 20, 24, 32, 48 or 64"
            ),
            "{message}"
        );
        // 65 bytes and beyond: the same error, never a panic.
        let long = format!("(1.0) vcan0 123##0{}", "FF".repeat(65));
        assert!(matches!(
            parse_line(&long),
            Err(LineError::BadFdLength { len: 65, .. })
        ));
        let longer = format!("(1.0) vcan0 123##0{}", "FF".repeat(4000));
        assert!(matches!(
            parse_line(&longer),
            Err(LineError::BadFdLength { len: 4000, .. })
        ));
    }
}
