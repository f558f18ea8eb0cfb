//! Outputs of a run: the snapshot document, the plot, the bus recordings, JUnit XML and the
//! HTML report. Every file is written completely or not at all (temp file + rename).

pub mod html;
mod junit;
mod snapshot;
mod svg;

use std::io::Write as _;
use std::path::{Path, PathBuf};

pub use html::{index_html, report_html, IndexEntry};
pub use junit::junit_xml;
pub use snapshot::snapshot_yaml;
pub use svg::plot_svg;

use super::model::Record;
use super::result::{BenchInfo, ScenarioResult};
use super::Scenario;
use crate::devices::DeviceKind;

/// What the HTML report needs to know about `scenario`'s bench.
pub fn bench_info(scenario: &Scenario) -> BenchInfo {
    let robstride_motors = scenario
        .bench
        .devices
        .iter()
        .filter_map(|d| match &d.kind {
            DeviceKind::Robstride(s) => Some(s.motors.iter().map(|m| (m.can_id, m.model.name()))),
            _ => None,
        })
        .flatten()
        .collect();
    BenchInfo {
        arm_urdf: html::scenario_urdf(scenario),
        robstride_motors,
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
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        fill(&mut file)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The files written for one run.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Written {
    /// The snapshot document (`result.yaml`).
    pub snapshot: Option<PathBuf>,
    /// The candump log (`bus.log`).
    pub candump: Option<PathBuf>,
    /// The pcap (`bus.pcap`).
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
        let path = dir.join("bus.pcap");
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
