//! Recording any bus to a file whose format follows its extension: `.pcap` for pcap, anything
//! else (`.log` by convention) for a candump `-L` log.

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
