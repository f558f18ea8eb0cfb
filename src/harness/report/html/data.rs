//! A run as the JSON document report.html embeds: steps, faults, the trace (column-major,
//! integers in the column's quantum), bus figures and a decoded excerpt of the recording.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::time::Duration;

use bus::{CanId, ReceivedFrame};
use serde_json::{json, Value};

use super::super::svg::fault_windows;
use crate::harness::result::{BenchInfo, Outcome, ScenarioResult, StepResult};
use crate::interop::{decode_piper, decode_robstride, DecodedFrame};

/// Most frames listed in a report: the recording can hold hundreds of thousands; the table
/// keeps the start and the frames around the first failure (bus.log / bus.pcap keep all).
pub const MAX_FRAMES: usize = 3000;

/// The RobStride driver's host ID (the address motors reply to).
const ROBSTRIDE_HOST_ID: u8 = 0xFD;

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

fn decode(frame: &ReceivedFrame, info: &BenchInfo) -> Option<DecodedFrame> {
    match frame.frame.id() {
        CanId::Standard(_) => decode_piper(&frame.frame).ok().flatten(),
        CanId::Extended(raw) => {
            // Motor replies carry the motor's CAN ID in bits 8..16.
            let motor = ((raw >> 8) & 0xFF) as u8;
            let model = info
                .robstride_motors
                .iter()
                .find(|(id, _)| *id == motor)
                .and_then(|(_, name)| driver::robstride::Model::parse(name))?;
            decode_robstride(&frame.frame, ROBSTRIDE_HOST_ID, model)
        }
    }
}

/// Indices of the frames the table lists: all when few, else the first half of the budget and
/// the frames around `focus` (the first failure), or the last ones without a failure.
fn frame_selection(frames: &[ReceivedFrame], t0: Duration, focus: Option<Duration>) -> Vec<usize> {
    let n = frames.len();
    if n <= MAX_FRAMES {
        return (0..n).collect();
    }
    let half = MAX_FRAMES / 2;
    let centre = match focus {
        Some(t) => frames.partition_point(|f| f.timestamp.saturating_sub(t0) < t),
        None => n,
    };
    let hi = (centre + half / 2).min(n);
    let lo = hi.saturating_sub(half).max(half);
    (0..half).chain(lo..hi).collect()
}

fn frames_json(result: &ScenarioResult) -> Value {
    let frames = &result.frames;
    // Frames on a real interface carry Unix time: count from the first one instead.
    let t0 = match frames.first() {
        Some(f) if f.timestamp > Duration::from_secs(1_000_000) => f.timestamp,
        _ => Duration::ZERO,
    };
    let focus = result.first_failure().map(|s| s.started + s.took);
    // Feedback repeats itself (an arm at rest sends the same payloads): decode each distinct
    // frame once.
    let mut decoded: HashMap<(u32, bool, Vec<u8>), (String, String)> = HashMap::new();
    let rows: Vec<Value> = frame_selection(frames, t0, focus)
        .into_iter()
        .map(|i| {
            let f = &frames[i];
            let key = (
                f.frame.raw_id(),
                f.frame.is_extended(),
                f.frame.data().to_vec(),
            );
            let (name, fields) = decoded
                .entry(key)
                .or_insert_with(|| match decode(f, &result.bench_info) {
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
            json!([
                i,
                secs(f.timestamp.saturating_sub(t0)),
                id,
                data,
                name,
                fields
            ])
        })
        .collect();
    json!({"total": frames.len(), "rows": rows})
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
    json!({
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
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use bus::CanFrame;

    fn frames(n: usize) -> Vec<ReceivedFrame> {
        (0..n)
            .map(|i| ReceivedFrame {
                frame: CanFrame::standard(0x2A5, &[0; 8]).unwrap(),
                timestamp: Duration::from_millis(i as u64),
            })
            .collect()
    }

    #[test]
    fn a_long_recording_keeps_its_start_and_the_failure() {
        let all = frames(MAX_FRAMES * 4);
        let picked = frame_selection(&all, Duration::ZERO, Some(Duration::from_millis(9000)));
        assert_eq!(picked.len(), MAX_FRAMES);
        assert_eq!(picked[0], 0);
        assert!(picked.contains(&9000), "the failure's frame is listed");
        assert!(
            picked.windows(2).all(|w| w[0] < w[1]),
            "in order, no repeats"
        );
        let few = frames(10);
        assert_eq!(frame_selection(&few, Duration::ZERO, None).len(), 10);
    }

    #[test]
    fn without_a_failure_the_end_is_kept() {
        let all = frames(MAX_FRAMES * 2);
        let picked = frame_selection(&all, Duration::ZERO, None);
        assert_eq!(picked.last(), Some(&(MAX_FRAMES * 2 - 1)));
    }
}
