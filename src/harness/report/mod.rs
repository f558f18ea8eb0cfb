//! Outputs of a run: the snapshot document, the plot, the bus recordings, JUnit XML and the
//! HTML report. Every file is written completely or not at all (temp file + rename).

pub mod html;
mod junit;
mod snapshot;
mod svg;

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

pub use html::{index_html, report_html, IndexEntry};
pub use junit::junit_xml;
pub use snapshot::snapshot_yaml;
pub use svg::plot_svg;

use super::model::Record;
use super::result::{BenchInfo, DeviceFrames, ScenarioResult};
use super::Scenario;

/// What the HTML report needs to know about `scenario`'s bench, asked of each device's kind.
pub fn bench_info(scenario: &Scenario) -> BenchInfo {
    let devices = &scenario.bench.devices;
    BenchInfo {
        // The first device that is drawn: the arm or robot the scenario drives.
        drawing: devices.iter().find_map(|d| d.kind.drawing()),
        frame_decoders: devices
            .iter()
            .filter_map(|d| {
                let buses: Vec<String> = d
                    .buses
                    .iter()
                    .filter_map(|&i| scenario.bench.buses.get(i))
                    .map(|b| b.name.clone())
                    .collect();
                let decoder = d.kind.frame_decoder(&buses)?;
                Some(DeviceFrames { buses, decoder })
            })
            .collect(),
    }
}

/// Write `bytes` to `path` atomically: a temporary file beside it, then a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |file| file.write_all(bytes))
}

/// Copy the file `from` to `path` atomically (streamed, never held in memory whole).
pub fn copy_atomic(from: &Path, path: &Path) -> std::io::Result<()> {
    write_atomic_with(path, |file| {
        let mut source = std::fs::File::open(from)?;
        std::io::copy(&mut source, file).map(drop)
    })
}

/// Create a temporary file beside `path`, let `fill` write it, sync it and rename it over
/// `path`; on any error the temporary file is removed and `path` is left as it was.
fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir)?;
        }
    }
    let file_name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{file_name}.tmp{}", std::process::id()));
    let (unfinished, mut file) = Unfinished::create(tmp.clone())?;
    let result = (|| {
        fill(&mut file)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drop(unfinished);
    result
}

/// The temporary files of outputs being written at this moment, for
/// [`remove_unfinished_outputs_before_exit`].
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// An entry of [`UNFINISHED`] for as long as it lives.
struct Unfinished(PathBuf);

impl Unfinished {
    /// Create the temporary file and list it, both under the list's lock: a quitting process
    /// ([`remove_unfinished_outputs_before_exit`]) then finds every file that exists, and
    /// none is created after it has looked.
    fn create(path: PathBuf) -> std::io::Result<(Self, std::fs::File)> {
        let mut listed = lock_unfinished();
        let file = std::fs::File::create(&path)?;
        listed.push(path.clone());
        Ok((Self(path), file))
    }
}

impl Drop for Unfinished {
    fn drop(&mut self) {
        let mut listed = lock_unfinished();
        if let Some(i) = listed.iter().position(|p| *p == self.0) {
            listed.swap_remove(i);
        }
    }
}

fn lock_unfinished() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Delete the temporary files of the outputs being written right now (each exists under a
/// hidden name, `.bus.log.tmp<pid>`, until it is complete and renamed), for a process about
/// to quit without finishing them (a second Ctrl-C). Returns how many were deleted.
///
/// The list stays locked afterwards, so no output starts between this and the exit (one that
/// did was left behind, 2 ms after a first Ctrl-C): call it only on the way out.
pub fn remove_unfinished_outputs_before_exit() -> usize {
    let mut listed = lock_unfinished();
    let removed = std::mem::take(&mut *listed)
        .iter()
        .filter(|path| std::fs::remove_file(path).is_ok())
        .count();
    // Held until the process ends (a writer waiting for it never runs again).
    std::mem::forget(listed);
    removed
}

/// Remove the listed files `pick` chooses (the others stay listed), as the quit-time
/// cleanup does, without keeping the list locked (tests).
#[cfg(test)]
fn remove_unfinished_where(pick: impl Fn(&Path) -> bool) -> usize {
    let mut listed = lock_unfinished();
    let (picked, kept): (Vec<PathBuf>, Vec<PathBuf>) = std::mem::take(&mut *listed)
        .into_iter()
        .partition(|p| pick(p));
    *listed = kept;
    drop(listed);
    picked
        .iter()
        .filter(|path| std::fs::remove_file(path).is_ok())
        .count()
}

/// The files written for one run.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Written {
    /// The snapshot document (`result.yaml`).
    pub snapshot: Option<PathBuf>,
    /// The candump log (`bus.log`).
    pub candump: Option<PathBuf>,
    /// The capture (`bus.pcap`, or `bus.pcapng` on a bench of several buses).
    pub pcap: Option<PathBuf>,
    /// The plot (`plot.svg`).
    pub plot: Option<PathBuf>,
    /// The HTML report (`report.html`).
    pub html: Option<PathBuf>,
}

/// Write the outputs of `result` into `dir`, as `record` asks.
pub fn write_outputs(
    result: &ScenarioResult,
    record: &Record,
    dir: &Path,
) -> std::io::Result<Written> {
    let mut written = Written::default();
    let snapshot = dir.join("result.yaml");
    write_atomic(&snapshot, snapshot_yaml(result).as_bytes())?;
    written.snapshot = Some(snapshot);
    if let Some(error) = &result.recording.error {
        return Err(std::io::Error::other(error.clone()));
    }
    if let Some(spooled) = result
        .recording
        .candump
        .as_deref()
        .filter(|_| record.candump)
    {
        let path = dir.join("bus.log");
        copy_atomic(spooled, &path)?;
        written.candump = Some(path);
    }
    if let Some(spooled) = result.recording.pcap.as_deref().filter(|_| record.pcap) {
        // A bench of several buses is a pcapng: classic pcap cannot say a frame's bus.
        let name = if result.recording.pcapng {
            "bus.pcapng"
        } else {
            "bus.pcap"
        };
        let path = dir.join(name);
        copy_atomic(spooled, &path)?;
        written.pcap = Some(path);
    }
    if record.plot {
        let path = dir.join("plot.svg");
        write_atomic(&path, plot_svg(result).as_bytes())?;
        written.plot = Some(path);
    }
    let path = dir.join("report.html");
    write_atomic(&path, report_html(result).as_bytes())?;
    written.html = Some(path);
    Ok(written)
}

#[cfg(test)]
mod unfinished_tests {
    use super::*;

    #[test]
    fn an_output_being_written_is_listed_until_it_is_renamed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bus.log");
        let tmp = dir
            .path()
            .join(format!(".bus.log.tmp{}", std::process::id()));
        write_atomic_with(&path, |file| {
            file.write_all(b"half")?;
            assert!(tmp.exists());
            assert!(lock_unfinished().contains(&tmp), "not listed while written");
            Ok(())
        })
        .unwrap();
        assert!(
            !lock_unfinished().contains(&tmp),
            "still listed once renamed"
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"half");
    }

    #[test]
    fn quitting_midway_removes_the_output_being_written_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let finished = dir.path().join("result.yaml");
        write_atomic(&finished, b"done").unwrap();
        let path = dir.path().join("bus.pcap");
        let tmp = dir
            .path()
            .join(format!(".bus.pcap.tmp{}", std::process::id()));
        let error = write_atomic_with(&path, |file| {
            file.write_all(b"half")?;
            // What the second Ctrl-C does from the signal thread, within this test's folder
            // (other tests of this binary may be writing outputs at this moment).
            assert_eq!(remove_unfinished_where(|p| p.starts_with(dir.path())), 1);
            assert!(!tmp.exists(), "the unfinished output is left behind");
            Err(std::io::Error::other("quit"))
        });
        assert!(error.is_err());
        assert!(!path.exists() && !tmp.exists());
        assert_eq!(std::fs::read(&finished).unwrap(), b"done");
    }
}
