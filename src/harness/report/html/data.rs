//! A run as the JSON document report.html embeds: steps, faults, the trace (column-major,
//! integers in the column's quantum), bus figures and a decoded excerpt of the recording.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::time::Duration;

use bus::ReceivedFrame;
use serde_json::{json, Value};

use super::super::svg::fault_windows;
use crate::devices::Posing;
use crate::harness::result::{BenchInfo, Outcome, ScenarioResult, StepResult};
use crate::interop::DecodedFrame;

/// Most frames listed in a report: the recording can hold hundreds of thousands; the table
/// keeps the start and the frames around the first failure (bus.log / bus.pcap keep all).
pub const MAX_FRAMES: usize = 3000;

fn secs(d: Duration) -> f64 {
    // Microsecond resolution keeps the document small and stable.
    (d.as_secs_f64() * 1e6).round() / 1e6
}

fn step_json(s: &StepResult) -> Value {
    let (expected, actual) = match &s.outcome {
        Outcome::Failed { expected, actual }
        | Outcome::TimedOut {
            expected, actual, ..
        } => (Some(expected.as_str()), Some(actual.as_str())),
        Outcome::Passed | Outcome::NotRun => (None, None),
    };
    json!({
        "index": s.index,
        "line": s.line,
        "label": s.label,
        "id": s.id,
        "started": secs(s.started),
        "took": secs(s.took),
        "outcome": s.outcome.name(),
        "expected": expected,
        "actual": actual,
        "reply": s.reply.iter().map(|(k, v)| json!([k, v])).collect::<Vec<_>>(),
    })
}

fn trace_json(result: &ScenarioResult) -> Value {
    let trace = &result.trace;
    let columns: Vec<Value> = trace
        .columns
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let values: Vec<Option<i64>> = trace
                .rows
                .iter()
                .map(|(_, row)| row.get(i).copied().flatten())
                .collect();
            json!({"name": c.name, "quantum": c.quantum, "group": c.group, "values": values})
        })
        .collect();
    json!({
        "t": trace.rows.iter().map(|(t, _)| secs(*t)).collect::<Vec<_>>(),
        "columns": columns,
    })
}

fn decode(bus: Option<&str>, frame: &ReceivedFrame, info: &BenchInfo) -> Option<DecodedFrame> {
    info.decode(bus, &frame.frame)
}

/// Which frames the table lists, out of `n` with the first failure's frame at `centre` (`n`
/// when there is none): all when few, else the first half of the budget and the half around
/// `centre` (a quarter of the budget after it), or the last ones without a failure.
fn listed(n: usize, centre: usize) -> impl Fn(usize) -> bool {
    let half = MAX_FRAMES / 2;
    let hi = (centre + half / 2).min(n);
    let lo = hi.saturating_sub(half).max(half);
    move |i| n <= MAX_FRAMES || i < half || (lo..hi).contains(&i)
}

/// Every frame of the recording in order, read one at a time from the spooled candump log
/// (so a long recording is never held in memory), else from the pcap; with the bus the log
/// names (a pcap names none).
fn for_each_frame(
    result: &ScenarioResult,
    mut each: impl FnMut(usize, Option<&str>, ReceivedFrame),
) {
    use std::io::BufRead as _;
    if let Some(path) = result.recording.candump.as_deref() {
        let Ok(file) = std::fs::File::open(path) else {
            return;
        };
        let lines = std::io::BufReader::new(file).lines().map_while(Result::ok);
        let entries = lines.filter_map(|line| bus::candump::parse_line(&line).ok());
        for (i, entry) in entries.enumerate() {
            each(
                i,
                Some(&entry.iface),
                ReceivedFrame {
                    frame: entry.frame,
                    timestamp: entry.timestamp,
                },
            );
        }
    } else if let Some(path) = result.recording.pcap.as_deref() {
        let frames = std::fs::read(path)
            .ok()
            .and_then(|bytes| bus::pcap::parse_capture(&bytes).ok())
            .unwrap_or_default();
        for (i, frame) in frames.into_iter().enumerate() {
            each(i, None, frame);
        }
    }
}

fn frames_json(result: &ScenarioResult) -> Value {
    // First pass: how many frames, where the first failure falls, where time starts.
    let focus = result.first_failure().map(|s| s.started + s.took);
    let (mut n, mut t0, mut centre) = (0, Duration::ZERO, None);
    for_each_frame(result, |i, _, f| {
        if i == 0 && f.timestamp > Duration::from_secs(1_000_000) {
            // Frames on a real interface carry Unix time: count from the first one instead.
            t0 = f.timestamp;
        }
        if centre.is_none() && focus.is_some_and(|t| f.timestamp.saturating_sub(t0) >= t) {
            centre = Some(i);
        }
        n = i + 1;
    });
    let keep = listed(n, centre.unwrap_or(n));
    // Feedback repeats itself (an arm at rest sends the same payloads): decode each distinct
    // frame on each bus once.
    type FrameKey = (Option<String>, u32, bool, Vec<u8>);
    let mut decoded: HashMap<FrameKey, (String, String)> = HashMap::new();
    let mut rows: Vec<Value> = Vec::new();
    for_each_frame(result, |i, bus, f| {
        if !keep(i) {
            return;
        }
        let key = (
            bus.map(str::to_owned),
            f.frame.raw_id(),
            f.frame.is_extended(),
            f.frame.data().to_vec(),
        );
        let (name, fields) = decoded
            .entry(key)
            .or_insert_with(|| match decode(bus, &f, &result.bench_info) {
                Some(d) => {
                    let fields = d
                        .fields
                        .iter()
                        .map(|x| format!("{}={}{}", x.name, x.value, x.unit))
                        .collect::<Vec<_>>()
                        .join(" ");
                    (d.name, fields)
                }
                None => (String::new(), String::new()),
            })
            .clone();
        let mut data = String::with_capacity(16);
        for b in f.frame.data() {
            let _ = write!(data, "{b:02X}");
        }
        let id = if f.frame.is_extended() {
            format!("{:08X}", f.frame.raw_id())
        } else {
            format!("{:03X}", f.frame.raw_id())
        };
        rows.push(json!([
            i,
            secs(f.timestamp.saturating_sub(t0)),
            id,
            data,
            name,
            fields
        ]));
    });
    json!({"total": n, "rows": rows})
}

/// Which trace columns pose the drawn model, for a model posed by named joints (an arm's
/// `j1_deg`… columns are the page's default and need no document).
fn posing_json(posing: &Posing) -> Option<Value> {
    let Posing::Joints { joints, base } = posing else {
        return None;
    };
    Some(json!({
        "joints": joints.iter().map(|j| json!({
            "column": j.column, "joint": j.joint, "direction": j.direction, "offset": j.offset_rad,
        })).collect::<Vec<_>>(),
        "base": base.as_ref().map(|b| json!({"position": b.position_m, "rpy": b.rpy_rad})),
    }))
}

fn verdict_reason(result: &ScenarioResult) -> Option<&str> {
    match &result.verdict {
        crate::harness::Verdict::Skipped(r) | crate::harness::Verdict::Error(r) => Some(r),
        _ => None,
    }
}

/// The whole document for one run (`model`: the arm to draw, already as JSON).
pub fn report_json(result: &ScenarioResult, model: Option<Value>) -> Value {
    let windows: Vec<Value> = fault_windows(result)
        .into_iter()
        .map(|w| json!({"from": secs(w.from), "to": secs(w.to), "label": w.label}))
        .collect();
    let bus = &result.bus;
    let mut document = json!({
        "name": result.name,
        "path": result.path.display().to_string(),
        "verdict": result.verdict.word(),
        "reason": verdict_reason(result),
        "clock": result.clock,
        "duration": secs(result.duration),
        "steps": result.steps.iter().map(step_json).collect::<Vec<_>>(),
        "faults": result.faults.iter().map(|e| json!({
            "at": secs(e.at), "action": e.action, "fault": e.fault, "target": e.target,
        })).collect::<Vec<_>>(),
        "windows": windows,
        "trace": trace_json(result),
        "bus": {
            "frames": bus.frames,
            "load_percent": bus.load_percent,
            "errors": bus.errors,
            "dropped": bus.dropped,
            "recorder_missed": bus.recorder_missed,
            "frames_by_id": bus.frames_by_id.iter()
                .map(|(id, n)| json!([format!("{id:X}"), n])).collect::<Vec<_>>(),
        },
        "frames": frames_json(result),
        "model": model,
    });
    if let Some(pose) = result
        .bench_info
        .drawing
        .as_ref()
        .and_then(|d| posing_json(&d.posed_by))
    {
        document["pose"] = pose;
    }
    // Only for a recording cut at its size limit, so other reports stay as they were.
    if let Some(omitted) = &result.recording.omitted {
        document["bus"]["recording_omitted"] = json!(omitted.describe());
    }
    document
}

#[cfg(test)]
mod tests {
    use super::*;

    fn picked(n: usize, centre: usize) -> Vec<usize> {
        let keep = listed(n, centre);
        (0..n).filter(|&i| keep(i)).collect()
    }

    #[test]
    fn a_long_recording_keeps_its_start_and_the_failure() {
        let long = picked(MAX_FRAMES * 4, 9000);
        assert_eq!(long.len(), MAX_FRAMES);
        assert_eq!(long[0], 0);
        assert!(long.contains(&9000), "the failure's frame is listed");
        assert!(long.windows(2).all(|w| w[0] < w[1]), "in order, no repeats");
        assert_eq!(picked(10, 3).len(), 10, "a short recording is listed whole");
    }

    #[test]
    fn without_a_failure_the_end_is_kept() {
        let n = MAX_FRAMES * 2;
        let end = picked(n, n);
        assert_eq!(end.len(), MAX_FRAMES);
        assert_eq!(end.last(), Some(&(n - 1)));
    }
}
