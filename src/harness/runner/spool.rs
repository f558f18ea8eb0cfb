//! Bus recordings written to temporary files while a scenario runs, so a long run's memory
//! stays flat: the frames go to disk as they arrive and the report copies the finished files
//! into the output folder (see `report::write_outputs`).

use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bus::candump::CandumpWriter;
use bus::pcap::PcapWriter;
use bus::pcapng::PcapngWriter;
use bus::ReceivedFrame;
use tempfile::TempPath;

use crate::harness::model::DEFAULT_BUS;

/// Start of every spool file's name, so a file left by a killed process is recognisable.
const SPOOL_PREFIX: &str = ".armhil-spool-";

/// Every spool file this process created. The files are deleted when their [`TempPath`] is
/// dropped, but a process that ends with `std::process::exit` (a second Ctrl-C) runs no
/// destructors: [`Recording::remove_spool_files_before_exit`] deletes them from this list instead.
static SPOOL_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// A new spool file in the temporary folder, remembered in [`SPOOL_FILES`].
fn spool_file(suffix: &str) -> io::Result<(File, TempPath)> {
    // Created and listed under the lock: a quitting process (`Recording::remove_spool_files_before_exit`) finds
    // every spool file there is, and none is created after it has looked.
    let mut listed = SPOOL_FILES
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let (file, path) = tempfile::Builder::new()
        .prefix(SPOOL_PREFIX)
        .suffix(suffix)
        .tempfile()?
        .into_parts();
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
    /// The capture (LINKTYPE_CAN_SOCKETCAN), when one was asked for: classic pcap on a bench
    /// of one bus, pcapng with an interface per bus on a bench of several
    /// ([`Recording::pcapng`]).
    pub pcap: Option<Arc<TempPath>>,
    /// Whether [`Recording::pcap`] is a pcapng file (a bench of several buses).
    pub pcapng: bool,
    /// The first write error, if any: the files are then incomplete and the run reports it.
    pub error: Option<String>,
    /// Frames left out of the files because the recording reached its size limit.
    pub omitted: Option<Omitted>,
}

/// A stretch of the bus left out of a recording that reached its size limit: the files hold
/// every frame before `from` and after `to`, none in between.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Omitted {
    /// How many frames were left out.
    pub frames: u64,
    /// Bus time of the first frame left out.
    pub from: Duration,
    /// Bus time of the last frame left out.
    pub to: Duration,
    /// The size limit of each recording file that made the cut, in bytes.
    pub limit_bytes: u64,
}

impl Omitted {
    /// One sentence for people: which stretch is missing and why.
    pub fn describe(&self) -> String {
        format!(
            "the recording reached its limit of {} MiB per file: {} frames from {:.3} s to {:.3} s \
             are left out (the files keep the run's beginning and end)",
            self.limit_bytes >> 20,
            self.frames,
            self.from.as_secs_f64(),
            self.to.as_secs_f64(),
        )
    }
}

impl Recording {
    /// Delete every spool file this process has created and not yet deleted, whichever run
    /// it belongs to, for a process about to end without running destructors (a second
    /// Ctrl-C quits with `std::process::exit`, which would leave them in the temporary
    /// folder). Recordings still held become unreadable, and the list stays locked so no
    /// spool file is created between this and the exit: call it only on the way out.
    /// Returns how many files it deleted.
    pub fn remove_spool_files_before_exit() -> usize {
        let mut listed = SPOOL_FILES
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let removed = remove_all(&mut listed);
        // Held until the process ends (a run waiting for it never records again).
        std::mem::forget(listed);
        removed
    }
}

/// Delete the files in `listed` and empty it; how many were deleted (some may be gone already).
fn remove_all(listed: &mut Vec<PathBuf>) -> usize {
    std::mem::take(listed)
        .iter()
        .filter(|path| std::fs::remove_file(path).is_ok())
        .count()
}

/// A writer that counts the bytes it passes on, so a segment knows its size without asking
/// the file system (its buffer holds bytes the file does not have yet).
struct Counted<W> {
    inner: W,
    bytes: u64,
}

impl<W: Write> Write for Counted<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

type Sink = Counted<BufWriter<File>>;

fn sink(file: File) -> Sink {
    Counted {
        inner: BufWriter::new(file),
        bytes: 0,
    }
}

/// Flush a finished writer's sink: the bytes are then all in the file.
fn flushed(finished: io::Result<Sink>) -> io::Result<()> {
    finished.and_then(|sink| {
        sink.inner
            .into_inner()
            .map(drop)
            .map_err(|e| e.into_error())
    })
}

/// The capture being written: classic pcap for one bus, pcapng for several, where each frame
/// names its bus (classic pcap has no interface column).
enum CaptureWriter {
    Pcap(PcapWriter<Sink>),
    Pcapng {
        writer: PcapngWriter<Sink>,
        buses: Arc<[String]>,
    },
}

impl CaptureWriter {
    fn create(buses: &Arc<[String]>) -> io::Result<(Self, TempPath)> {
        if buses.len() > 1 {
            let (file, path) = spool_file(".pcapng")?;
            let names: Vec<&str> = buses.iter().map(String::as_str).collect();
            let writer = PcapngWriter::new(sink(file), &names)?;
            let buses = Arc::clone(buses);
            Ok((Self::Pcapng { writer, buses }, path))
        } else {
            let (file, path) = spool_file(".pcap")?;
            Ok((Self::Pcap(PcapWriter::new(sink(file))?), path))
        }
    }

    fn write(&mut self, frame: &ReceivedFrame, bus: &str) -> io::Result<()> {
        match self {
            Self::Pcap(writer) => writer.write(frame),
            Self::Pcapng { writer, buses } => {
                // A bench has a handful of buses: a scan is cheaper than a map.
                let index = buses.iter().position(|b| b == bus).ok_or_else(|| {
                    io::Error::other(format!("a frame of bus `{bus}`, which the bench has not"))
                })?;
                writer.write(u32::try_from(index).unwrap_or(u32::MAX), frame)
            }
        }
    }

    fn bytes(&self) -> u64 {
        match self {
            Self::Pcap(writer) => writer.get_ref().bytes,
            Self::Pcapng { writer, .. } => writer.get_ref().bytes,
        }
    }

    fn finish(self) -> io::Result<()> {
        match self {
            Self::Pcap(writer) => flushed(writer.finish()),
            Self::Pcapng { writer, .. } => flushed(writer.finish()),
        }
    }
}

/// Bytes at the start of every capture file that a joined capture keeps only once.
fn capture_header_len(buses: &[String]) -> u64 {
    if buses.len() > 1 {
        let names: Vec<&str> = buses.iter().map(String::as_str).collect();
        bus::pcapng::header_len(&names) as u64
    } else {
        bus::pcap::GLOBAL_HEADER_LEN as u64
    }
}

/// One stretch of the recording in every format asked for: the same frames in each file.
struct Segment {
    candump: Option<(CandumpWriter<Sink>, TempPath)>,
    pcap: Option<(CaptureWriter, TempPath)>,
    /// Frames written, and the bus time of the first and the last.
    frames: u64,
    first: Duration,
    last: Duration,
}

/// A segment whose files are complete.
struct Written {
    candump: Option<TempPath>,
    pcap: Option<TempPath>,
    frames: u64,
    first: Duration,
    last: Duration,
}

impl Segment {
    fn create(candump: bool, pcap: bool, buses: &Arc<[String]>) -> io::Result<Self> {
        let candump = if candump {
            let (file, path) = spool_file(".log")?;
            Some((CandumpWriter::new(sink(file), DEFAULT_BUS), path))
        } else {
            None
        };
        let pcap = pcap.then(|| CaptureWriter::create(buses)).transpose()?;
        Ok(Self {
            candump,
            pcap,
            frames: 0,
            first: Duration::ZERO,
            last: Duration::ZERO,
        })
    }

    fn write(&mut self, frame: &ReceivedFrame, bus: &str) -> io::Result<()> {
        if let Some((writer, _)) = &mut self.candump {
            writer.write_on(bus, frame)?;
        }
        if let Some((writer, _)) = &mut self.pcap {
            writer.write(frame, bus)?;
        }
        if self.frames == 0 {
            self.first = frame.timestamp;
        }
        self.frames += 1;
        self.last = frame.timestamp;
        Ok(())
    }

    /// The size of the larger of its files.
    fn bytes(&self) -> u64 {
        let candump = self.candump.as_ref().map_or(0, |(w, _)| w.get_ref().bytes);
        let pcap = self.pcap.as_ref().map_or(0, |(w, _)| w.bytes());
        candump.max(pcap)
    }

    fn finish(self) -> io::Result<Written> {
        let candump = match self.candump {
            Some((writer, path)) => flushed(writer.finish()).map(|()| Some(path))?,
            None => None,
        };
        let pcap = match self.pcap {
            Some((writer, path)) => writer.finish().map(|()| Some(path))?,
            None => None,
        };
        Ok(Written {
            candump,
            pcap,
            frames: self.frames,
            first: self.first,
            last: self.last,
        })
    }
}

/// Recordings being written, each file held to a size limit.
///
/// A long run (an hour's wait on a busy bus is ~3,000 frames/s) would otherwise write
/// hundreds of megabytes per file. Past the limit, the files keep the run's beginning (half
/// the limit) and its end (the other half: the newest two quarter-limit segments, older ones
/// deleted as new ones fill), which is where a failure and its cause usually are; the stretch
/// in between is counted in [`Omitted`] and the report says so. The disk holds at most the
/// limit per format while the run lasts, and memory stays flat.
pub(crate) struct Spool {
    formats: (bool, bool),
    /// The bench's buses, by name (the capture's interfaces when there are several).
    buses: Arc<[String]>,
    limit_bytes: u64,
    /// The run's beginning, until it holds half the limit.
    head: Option<Segment>,
    head_written: Option<Written>,
    /// The end so far: at most one finished quarter-limit segment and the one being written.
    tail_written: Option<Written>,
    tail: Option<Segment>,
    omitted: Option<Omitted>,
    error: Option<String>,
}

impl Spool {
    /// Open temporary files for the formats asked for, each held to `limit_bytes`, for a
    /// bench of `buses` (the names the frames come with).
    pub fn create(
        candump: bool,
        pcap: bool,
        limit_bytes: u64,
        buses: &[String],
    ) -> io::Result<Self> {
        let buses: Arc<[String]> = buses.into();
        let head = (candump || pcap)
            .then(|| Segment::create(candump, pcap, &buses))
            .transpose()?;
        Ok(Self {
            formats: (candump, pcap),
            buses,
            limit_bytes,
            head,
            head_written: None,
            tail_written: None,
            tail: None,
            omitted: None,
            error: None,
        })
    }

    /// Whether anything is recorded at all.
    pub fn is_recording(&self) -> bool {
        self.formats.0 || self.formats.1
    }

    /// Append one frame seen on `bus` to every file (the candump log names the bus, and so
    /// does the pcapng of a bench of several buses); after the first error, writing stops and
    /// the error is kept for the report.
    pub fn write(&mut self, frame: &ReceivedFrame, bus: &str) {
        if self.error.is_some() || !self.is_recording() {
            return;
        }
        if let Err(e) = self.write_frame(frame, bus) {
            self.error = Some(format!("cannot write the bus recording: {e}"));
        }
    }

    fn write_frame(&mut self, frame: &ReceivedFrame, bus: &str) -> io::Result<()> {
        if let Some(head) = &mut self.head {
            head.write(frame, bus)?;
            if head.bytes() >= self.limit_bytes / 2 {
                let head = self.head.take().map(Segment::finish).transpose()?;
                self.head_written = head;
            }
            return Ok(());
        }
        let tail = match &mut self.tail {
            Some(tail) => tail,
            None => self.tail.insert(Segment::create(
                self.formats.0,
                self.formats.1,
                &self.buses,
            )?),
        };
        tail.write(frame, bus)?;
        if tail.bytes() >= self.limit_bytes / 4 {
            let full = self.tail.take().map(Segment::finish).transpose()?;
            // The older of the two finished segments goes (its files are deleted with it).
            if let Some(dropped) = std::mem::replace(&mut self.tail_written, full) {
                let omitted = self.omitted.get_or_insert(Omitted {
                    frames: 0,
                    from: dropped.first,
                    to: dropped.last,
                    limit_bytes: self.limit_bytes,
                });
                omitted.frames += dropped.frames;
                omitted.to = dropped.last;
            }
        }
        Ok(())
    }

    /// Flush the files and hand them over: one file per format, the kept segments joined.
    pub fn finish(self) -> Recording {
        let mut error = self.error;
        let mut finish = |segment: Option<Segment>| match segment.map(Segment::finish) {
            Some(Ok(written)) => Some(written),
            Some(Err(e)) => {
                error.get_or_insert_with(|| format!("cannot write the bus recording: {e}"));
                None
            }
            None => None,
        };
        let head = match self.head_written {
            Some(written) => Some(written),
            None => finish(self.head),
        };
        let tail = finish(self.tail);
        // In time order: the beginning, the finished end segment, the one being written.
        let ordered = [head, self.tail_written, tail];
        let (mut candumps, mut pcaps) = (Vec::new(), Vec::new());
        for written in ordered.into_iter().flatten() {
            candumps.extend(written.candump);
            pcaps.extend(written.pcap);
        }
        let pcapng = self.buses.len() > 1;
        let suffix = if pcapng { ".pcapng" } else { ".pcap" };
        let joined = join_files(candumps, ".log", 0).and_then(|candump| {
            let pcap = join_files(pcaps, suffix, capture_header_len(&self.buses))?;
            Ok((candump, pcap))
        });
        let (candump, pcap) = match joined {
            Ok(paths) => paths,
            Err(e) => {
                error.get_or_insert_with(|| format!("cannot write the bus recording: {e}"));
                (None, None)
            }
        };
        Recording {
            candump: candump.map(Arc::new),
            pcap: pcap.map(Arc::new),
            pcapng,
            error,
            omitted: self.omitted,
        }
    }
}

/// One file of the segments `parts` (in order), leaving out the first `header_bytes` of every
/// part but the first (a capture's headers); a single part is handed over as it is. The
/// parts are deleted when they go out of scope here.
fn join_files(
    mut parts: Vec<TempPath>,
    suffix: &str,
    header_bytes: u64,
) -> io::Result<Option<TempPath>> {
    if parts.len() <= 1 {
        return Ok(parts.pop());
    }
    let (file, joined) = spool_file(suffix)?;
    let mut out = BufWriter::new(file);
    for (i, part) in parts.iter().enumerate() {
        let mut source = File::open(part)?;
        if i > 0 {
            source.seek(SeekFrom::Start(header_bytes))?;
        }
        io::copy(&mut source, &mut out)?;
    }
    out.into_inner().map_err(io::IntoInnerError::into_error)?;
    Ok(Some(joined))
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use bus::CanFrame;

    use super::*;

    const UNLIMITED: u64 = u64::MAX;

    fn one_bus() -> Vec<String> {
        vec![DEFAULT_BUS.to_owned()]
    }

    fn frame(i: u16) -> ReceivedFrame {
        ReceivedFrame {
            frame: CanFrame::standard(0x2A1 + i % 2, &[i as u8, 0xAB]).unwrap(),
            timestamp: Duration::from_micros(u64::from(i) * 1500),
        }
    }

    #[test]
    fn both_formats_hold_every_frame_and_read_back() {
        let mut spool = Spool::create(true, true, UNLIMITED, &one_bus()).unwrap();
        for i in 0..500 {
            spool.write(&frame(i), DEFAULT_BUS);
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

    /// Every frame `frame(0..n)` is 1.5 ms after the one before.
    const FRAME_GAP: Duration = Duration::from_micros(1500);

    #[test]
    fn a_recording_past_its_limit_keeps_the_beginning_and_the_end() {
        const LIMIT: u64 = 8 * 1024;
        let n: u16 = 5000;
        let mut spool = Spool::create(true, true, LIMIT, &one_bus()).unwrap();
        for i in 0..n {
            spool.write(&frame(i), DEFAULT_BUS);
        }
        let recording = spool.finish();
        assert_eq!(recording.error, None);
        let omitted = recording.omitted.expect("5,000 frames do not fit in 8 KiB");
        assert_eq!(omitted.limit_bytes, LIMIT);

        let log_path = recording.candump.as_deref().unwrap();
        let pcap_path = recording.pcap.as_deref().unwrap();
        // Each file within its limit (plus at most one frame per segment: a segment is
        // closed after the frame that fills it).
        let slack = 3 * 64;
        for path in [log_path, pcap_path] {
            let size = std::fs::metadata(path).unwrap().len();
            assert!(size <= LIMIT + slack, "{} bytes", size);
            assert!(size >= LIMIT * 3 / 4, "{} bytes: too little kept", size);
        }
        let log = bus::candump::read_log(log_path).unwrap();
        let pcap = bus::pcap::parse_capture(&std::fs::read(pcap_path).unwrap()).unwrap();
        assert_eq!(log.len(), pcap.len(), "both files keep the same frames");
        assert_eq!(log.len() as u64 + omitted.frames, u64::from(n));
        assert_eq!(log[0].frame, frame(0).frame, "the beginning is kept");
        assert_eq!(pcap.last(), Some(&frame(n - 1)), "the end is kept");

        // Exactly one gap, and it is the omitted stretch.
        let gaps: Vec<usize> = (1..log.len())
            .filter(|&i| log[i].timestamp - log[i - 1].timestamp != FRAME_GAP)
            .collect();
        assert_eq!(gaps.len(), 1, "gaps at {gaps:?}");
        let after = gaps[0];
        assert_eq!(log[after - 1].timestamp + FRAME_GAP, omitted.from);
        assert_eq!(omitted.to + FRAME_GAP, log[after].timestamp);
        let span = FRAME_GAP * u32::try_from(omitted.frames - 1).unwrap();
        assert_eq!(omitted.to - omitted.from, span);
        for (i, entry) in pcap.iter().enumerate() {
            assert_eq!(entry.timestamp, log[i].timestamp, "frame {i}");
        }
    }

    #[test]
    fn several_buses_make_one_pcapng_naming_each_frame_s_bus_across_segments() {
        let buses = vec!["can0".to_owned(), "can1".to_owned(), "can3".to_owned()];
        // Small enough that the capture is written in several segments and joined.
        let mut spool = Spool::create(false, true, 16 * 1024, &buses).unwrap();
        for i in 0..2000u16 {
            spool.write(&frame(i), &buses[usize::from(i) % 3]);
        }
        let recording = spool.finish();
        assert!(recording.pcapng);
        let omitted = recording.omitted.expect("the limit was reached");
        let bytes = std::fs::read(recording.pcap.as_deref().unwrap()).unwrap();
        let capture = bus::pcapng::parse_capture(&bytes).unwrap();
        // One set of interfaces however many segments were joined.
        assert_eq!(capture.interfaces, buses);
        assert_eq!(capture.frames.len() as u64 + omitted.frames, 2000);
        for (interface, received) in &capture.frames {
            let i = (received.timestamp.as_micros() / 1500) as u16;
            assert_eq!(*received, frame(i));
            assert_eq!(*interface, u32::from(i % 3), "frame {i}");
        }
        let mut spool = Spool::create(false, true, UNLIMITED, &buses).unwrap();
        spool.write(&frame(1), "can9");
        assert!(spool.finish().error.unwrap().contains("bus `can9`"));
    }

    #[test]
    fn a_recording_within_its_limit_keeps_every_frame_in_one_piece() {
        // Head full and an end segment started, but nothing dropped yet.
        let mut spool = Spool::create(true, true, 64 * 1024, &one_bus()).unwrap();
        for i in 0..1200 {
            spool.write(&frame(i), DEFAULT_BUS);
        }
        let recording = spool.finish();
        assert_eq!(recording.omitted, None);
        let log = bus::candump::read_log(recording.candump.as_deref().unwrap()).unwrap();
        assert_eq!(log.len(), 1200);
        let bytes = std::fs::read(recording.pcap.as_deref().unwrap()).unwrap();
        let pcap = bus::pcap::parse_capture(&bytes).unwrap();
        assert_eq!(pcap.len(), 1200);
        assert!(pcap
            .windows(2)
            .all(|w| w[1].timestamp - w[0].timestamp == FRAME_GAP));
    }

    #[test]
    fn the_files_go_away_with_the_last_result() {
        let mut spool = Spool::create(true, false, UNLIMITED, &one_bus()).unwrap();
        spool.write(&frame(1), DEFAULT_BUS);
        let recording = spool.finish();
        let path = recording.candump.as_deref().unwrap().to_path_buf();
        let copy = recording.clone();
        drop(recording);
        assert!(path.exists(), "a clone still holds the file");
        drop(copy);
        assert!(!path.exists(), "temporary file left behind");
        assert!(recording_is_empty(
            &Spool::create(false, false, UNLIMITED, &one_bus()).unwrap()
        ));
    }

    #[test]
    fn spool_files_can_be_removed_on_the_way_out() {
        let mut spool = Spool::create(true, true, UNLIMITED, &one_bus()).unwrap();
        spool.write(&frame(1), DEFAULT_BUS);
        let head = spool.head.as_ref().unwrap();
        let candump = head.candump.as_ref().unwrap().1.to_path_buf();
        let pcap = head.pcap.as_ref().unwrap().1.to_path_buf();
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
        assert_eq!(remove_all(&mut mine.lock().unwrap()), 2);
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
