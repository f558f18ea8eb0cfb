//! Recording any bus to a file whose format follows its extension: `.pcap` for pcap, anything
//! else (`.log` by convention) for a candump `-L` log. CAN FD frames are recorded as CAN FD
//! frames with their BRS and ESI flags: candump's `ID##F…` form, pcap's 72-byte packet with
//! `CANFD_FDF` (see [`crate::candump`] and [`crate::pcap`]).

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};

use tokio::sync::broadcast;

use crate::candump::CandumpWriter;
use crate::pcap::PcapWriter;
use crate::ReceivedFrame;

/// The file format of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordFormat {
    /// candump `-L` text log.
    Candump,
    /// pcap with `LINKTYPE_CAN_SOCKETCAN`.
    Pcap,
}

impl RecordFormat {
    /// `.pcap` (any case) means pcap; every other name a candump log.
    pub fn from_path(path: &Path) -> Self {
        let is_pcap = path
            .extension()
            .and_then(|ext| ext.to_str())
            .is_some_and(|ext| ext.eq_ignore_ascii_case("pcap"));
        if is_pcap {
            Self::Pcap
        } else {
            Self::Candump
        }
    }
}

enum Sink {
    Candump(CandumpWriter<BufWriter<File>>),
    Pcap(PcapWriter<BufWriter<File>>),
}

/// A recording in progress. Frames are buffered; [`Recorder::finish`] (or dropping the
/// recorder, ignoring errors) flushes them, so the file is complete when recording stops.
pub struct Recorder {
    sink: Sink,
    path: PathBuf,
    frames: u64,
}

impl std::fmt::Debug for Recorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Recorder")
            .field("path", &self.path)
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

impl Recorder {
    /// Create the file; `iface` names the interface in candump lines.
    pub fn create(path: impl AsRef<Path>, iface: &str) -> io::Result<Self> {
        let path = path.as_ref().to_owned();
        let sink = match RecordFormat::from_path(&path) {
            RecordFormat::Candump => Sink::Candump(CandumpWriter::create(&path, iface)?),
            RecordFormat::Pcap => Sink::Pcap(PcapWriter::create(&path)?),
        };
        Ok(Self {
            sink,
            path,
            frames: 0,
        })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Append one frame.
    pub fn write(&mut self, received: &ReceivedFrame) -> io::Result<()> {
        match &mut self.sink {
            Sink::Candump(writer) => writer.write(received)?,
            Sink::Pcap(writer) => writer.write(received)?,
        }
        self.frames += 1;
        Ok(())
    }

    /// Push buffered frames to the file.
    pub fn flush(&mut self) -> io::Result<()> {
        match &mut self.sink {
            Sink::Candump(writer) => writer.flush(),
            Sink::Pcap(writer) => writer.flush(),
        }
    }

    /// Flush everything and sync the file to disk.
    pub fn finish(self) -> io::Result<u64> {
        let file = match self.sink {
            Sink::Candump(writer) => writer.finish()?,
            Sink::Pcap(writer) => writer.finish()?,
        };
        file.get_ref().sync_all()?;
        Ok(self.frames)
    }
}

/// What a tap recording saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TapSummary {
    /// Frames written.
    pub frames: u64,
    /// Frames the tap fell too far behind to see.
    pub missed: u64,
}

/// Write every frame from a virtual bus tap until the bus goes away (or a write fails).
/// Returns the counts; the caller then [`Recorder::finish`]es the file.
pub async fn record_tap(
    tap: &mut broadcast::Receiver<ReceivedFrame>,
    recorder: &mut Recorder,
) -> io::Result<TapSummary> {
    let mut summary = TapSummary::default();
    loop {
        match tap.recv().await {
            Ok(received) => {
                recorder.write(&received)?;
                summary.frames += 1;
            }
            Err(broadcast::error::RecvError::Lagged(missed)) => {
                tracing::warn!(missed, path = %recorder.path.display(), "tap fell behind, frames missing from the recording");
                summary.missed += missed;
            }
            Err(broadcast::error::RecvError::Closed) => return Ok(summary),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::{CanFrame, CanId, FdFlags};

    fn frames() -> Vec<ReceivedFrame> {
        let at = |micros| Duration::from_micros(1_700_000_000_000_000 + micros);
        let fd = |id, len: usize, brs, esi| {
            CanFrame::fd(id, &vec![0xA5; len], FdFlags { brs, esi }).unwrap()
        };
        [
            CanFrame::standard(0x123, &[1, 2, 3]).unwrap(),
            fd(CanId::Standard(0x124), 64, true, false),
            fd(CanId::Extended(0x1ABC_DEF0), 12, false, true),
            fd(CanId::Standard(0x7FF), 0, true, true),
            fd(CanId::Standard(0x010), 8, false, false),
            CanFrame::extended(0x0200_FD01, &[]).unwrap(),
        ]
        .into_iter()
        .enumerate()
        .map(|(i, frame)| ReceivedFrame {
            frame,
            timestamp: at(10 * i as u64),
        })
        .collect()
    }

    fn record(extension: &str) -> PathBuf {
        let path = std::env::temp_dir().join(format!(
            "armhil-bus-recorder-fd-{}.{extension}",
            std::process::id()
        ));
        let mut recorder = Recorder::create(&path, "can0").unwrap();
        for frame in frames() {
            recorder.write(&frame).unwrap();
        }
        assert_eq!(recorder.finish().unwrap(), 6);
        path
    }

    #[test]
    fn fd_frames_are_recorded_with_their_flags_in_candump_logs() {
        let path = record("log");
        let text = std::fs::read_to_string(&path).unwrap();
        let entries = crate::candump::parse_log(&text).unwrap();
        let _ = std::fs::remove_file(&path);
        assert!(text.contains(" can0 124##1A5A5"), "{text}");
        assert!(text.contains(" can0 1ABCDEF0##2A5A5"), "{text}");
        let read: Vec<CanFrame> = entries.iter().map(|entry| entry.frame).collect();
        let written: Vec<CanFrame> = frames().iter().map(|r| r.frame).collect();
        assert_eq!(read, written);
        assert_eq!(
            read.iter()
                .map(|f| (f.is_fd(), f.brs(), f.esi()))
                .collect::<Vec<_>>(),
            [
                (false, false, false),
                (true, true, false),
                (true, false, true),
                (true, true, true),
                (true, false, false),
                (false, false, false)
            ]
        );
    }

    #[test]
    fn fd_frames_are_recorded_with_their_flags_in_pcap_files() {
        let path = record("pcap");
        let bytes = std::fs::read(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        // Four 72-byte CAN FD packets and two 16-byte classic ones, each with its header.
        assert_eq!(bytes.len(), 24 + 6 * 16 + 4 * 72 + 2 * 16);
        assert_eq!(crate::pcap::parse_capture(&bytes).unwrap(), frames());
    }
}
