//! Bus recordings written to temporary files while a scenario runs, so a long run's memory
//! stays flat: the frames go to disk as they arrive and the report copies the finished files
//! into the output folder (see `report::write_outputs`).

use std::fs::File;
use std::io::{self, BufWriter};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use bus::candump::CandumpWriter;
use bus::pcap::PcapWriter;
use bus::ReceivedFrame;
use tempfile::TempPath;

/// Interface name written in the candump log (`vcan0` so can-utils replays it as is).
const LOG_IFACE: &str = "vcan0";

/// Start of every spool file's name, so a file left by a killed process is recognisable.
const SPOOL_PREFIX: &str = ".armhil-spool-";

/// Every spool file this process created. The files are deleted when their [`TempPath`] is
/// dropped, but a process that ends with `std::process::exit` (a second Ctrl-C) runs no
/// destructors: [`Recording::remove_spool_files`] deletes them from this list instead.
static SPOOL_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// A new spool file in the temporary folder, remembered in [`SPOOL_FILES`].
fn spool_file(suffix: &str) -> io::Result<(File, TempPath)> {
    let (file, path) = tempfile::Builder::new()
        .prefix(SPOOL_PREFIX)
        .suffix(suffix)
        .tempfile()?
        .into_parts();
    let mut listed = SPOOL_FILES
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    // Forget the files already deleted now and then (amortised: at each power of two), so a
    // process that runs thousands of scenarios keeps a short list.
    if listed.len() >= 64 && listed.len().is_power_of_two() {
        listed.retain(|listed| listed.exists());
    }
    listed.push(path.to_path_buf());
    drop(listed);
    Ok((file, path))
}

/// The recordings of one run, once finished: temporary files deleted when the last clone of
/// the result is dropped.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// The candump `-L` log, when one was asked for.
    pub candump: Option<Arc<TempPath>>,
    /// The pcap (LINKTYPE_CAN_SOCKETCAN), when one was asked for.
    pub pcap: Option<Arc<TempPath>>,
    /// The first write error, if any: the files are then incomplete and the run reports it.
    pub error: Option<String>,
}

impl Recording {
    /// Delete every spool file this process has created and not yet deleted, whichever run
    /// it belongs to, for a process about to end without running destructors (a second
    /// Ctrl-C quits with `std::process::exit`, which would leave them in the temporary
    /// folder). Recordings still held become unreadable: call it only on the way out.
    /// Returns how many files it deleted.
    pub fn remove_spool_files() -> usize {
        remove_listed(&SPOOL_FILES)
    }
}

/// Delete the files in `list` and empty it; how many were deleted (some may be gone already).
fn remove_listed(list: &Mutex<Vec<PathBuf>>) -> usize {
    let paths = std::mem::take(&mut *list.lock().unwrap_or_else(|poisoned| poisoned.into_inner()));
    paths
        .iter()
        .filter(|path| std::fs::remove_file(path).is_ok())
        .count()
}

/// Recordings being written.
pub(crate) struct Spool {
    candump: Option<(CandumpWriter<BufWriter<File>>, TempPath)>,
    pcap: Option<(PcapWriter<BufWriter<File>>, TempPath)>,
    error: Option<String>,
}

impl Spool {
    /// Open temporary files for the formats asked for.
    pub fn create(candump: bool, pcap: bool) -> io::Result<Self> {
        let candump = if candump {
            let (file, path) = spool_file(".log")?;
            Some((CandumpWriter::new(BufWriter::new(file), LOG_IFACE), path))
        } else {
            None
        };
        let pcap = if pcap {
            let (file, path) = spool_file(".pcap")?;
            Some((PcapWriter::new(BufWriter::new(file))?, path))
        } else {
            None
        };
        Ok(Self {
            candump,
            pcap,
            error: None,
        })
    }

    /// Whether anything is recorded at all.
    pub fn is_recording(&self) -> bool {
        self.candump.is_some() || self.pcap.is_some()
    }

    /// Append one frame to every file; after the first error, writing stops and the error is
    /// kept for the report.
    pub fn write(&mut self, frame: &ReceivedFrame) {
        if self.error.is_some() {
            return;
        }
        let result = (|| {
            if let Some((writer, _)) = &mut self.candump {
                writer.write(frame)?;
            }
            if let Some((writer, _)) = &mut self.pcap {
                writer.write(frame)?;
            }
            io::Result::Ok(())
        })();
        if let Err(e) = result {
            self.error = Some(format!("cannot write the bus recording: {e}"));
        }
    }

    /// Flush the files and hand them over.
    pub fn finish(self) -> Recording {
        let mut error = self.error;
        let mut keep = |finished: io::Result<BufWriter<File>>, path: TempPath| match finished
            .and_then(|w| w.into_inner().map_err(io::IntoInnerError::into_error))
        {
            Ok(_) => Some(Arc::new(path)),
            Err(e) => {
                error.get_or_insert_with(|| format!("cannot write the bus recording: {e}"));
                None
            }
        };
        let candump = self
            .candump
            .and_then(|(writer, path)| keep(writer.finish(), path));
        let pcap = self
            .pcap
            .and_then(|(writer, path)| keep(writer.finish(), path));
        Recording {
            candump,
            pcap,
            error,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use bus::CanFrame;

    use super::*;

    fn frame(i: u16) -> ReceivedFrame {
        ReceivedFrame {
            frame: CanFrame::standard(0x2A1 + i % 2, &[i as u8, 0xAB]).unwrap(),
            timestamp: Duration::from_micros(u64::from(i) * 1500),
        }
    }

    #[test]
    fn both_formats_hold_every_frame_and_read_back() {
        let mut spool = Spool::create(true, true).unwrap();
        for i in 0..500 {
            spool.write(&frame(i));
        }
        let recording = spool.finish();
        assert_eq!(recording.error, None);
        let log = bus::candump::read_log(recording.candump.as_deref().unwrap()).unwrap();
        assert_eq!(log.len(), 500);
        assert_eq!(log[3].frame, frame(3).frame);
        assert_eq!(log[3].timestamp, Duration::from_micros(4500));
        let bytes = std::fs::read(recording.pcap.as_deref().unwrap()).unwrap();
        let pcap = bus::pcap::parse_capture(&bytes).unwrap();
        assert_eq!(pcap.len(), 500);
        assert_eq!(pcap[499], frame(499));
    }

    #[test]
    fn the_files_go_away_with_the_last_result() {
        let mut spool = Spool::create(true, false).unwrap();
        spool.write(&frame(1));
        let recording = spool.finish();
        let path = recording.candump.as_deref().unwrap().to_path_buf();
        let copy = recording.clone();
        drop(recording);
        assert!(path.exists(), "a clone still holds the file");
        drop(copy);
        assert!(!path.exists(), "temporary file left behind");
        assert!(recording_is_empty(&Spool::create(false, false).unwrap()));
    }

    #[test]
    fn spool_files_can_be_removed_on_the_way_out() {
        let mut spool = Spool::create(true, true).unwrap();
        spool.write(&frame(1));
        let candump = spool.candump.as_ref().unwrap().1.to_path_buf();
        let pcap = spool.pcap.as_ref().unwrap().1.to_path_buf();
        assert!(candump.exists() && pcap.exists());
        let name = candump.file_name().unwrap().to_string_lossy().into_owned();
        assert!(name.starts_with(SPOOL_PREFIX), "{name}");
        let listed = SPOOL_FILES.lock().unwrap().clone();
        assert!(
            listed.contains(&candump) && listed.contains(&pcap),
            "spool files are listed for removal on the way out"
        );
        // What a second Ctrl-C does before `process::exit` (no destructor runs then), on a
        // list of this test's files only: other tests' spools run in this process too.
        let mine = Mutex::new(vec![candump.clone(), pcap.clone()]);
        assert_eq!(remove_listed(&mine), 2);
        assert!(
            !candump.exists() && !pcap.exists(),
            "spool files left behind"
        );
        assert!(mine.lock().unwrap().is_empty());
        drop(spool);
    }

    fn recording_is_empty(spool: &Spool) -> bool {
        !spool.is_recording()
    }
}
