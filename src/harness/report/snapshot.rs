//! The snapshot document: step results, fault events, bus figures and the trace, as YAML
//! written by hand so the bytes are stable (fixed decimals, sorted keys, no wall time).

use std::fmt::Write as _;
use std::time::Duration;

use crate::harness::result::{Outcome, ScenarioResult, Verdict};

/// A YAML double-quoted scalar (JSON string syntax is valid YAML).
pub(crate) fn quote(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_else(|_| "\"\"".to_owned())
}

/// Milliseconds with one decimal (0.1 ms resolution).
pub(crate) fn ms(d: Duration) -> String {
    let tenths = (d.as_micros() + 50) / 100;
    format!("{}.{}", tenths / 10, tenths % 10)
}

/// An integer count of `10^-decimals` units as a fixed-point decimal.
pub(crate) fn fixed(value: i64, decimals: u32) -> String {
    if decimals == 0 {
        return value.to_string();
    }
    let scale = 10i64.pow(decimals);
    let sign = if value < 0 { "-" } else { "" };
    let abs = value.unsigned_abs();
    let scale_u = scale.unsigned_abs();
    format!(
        "{sign}{}.{:0width$}",
        abs / scale_u,
        abs % scale_u,
        width = decimals as usize
    )
}

/// Decimals that show one quantum exactly (0.1 → 1, 0.01 → 2, 1 → 0).
pub(crate) fn decimals_of(quantum: f64) -> u32 {
    let mut d = 0;
    let mut q = quantum;
    while d < 6 && (q - q.round()).abs() > 1e-9 {
        q *= 10.0;
        d += 1;
    }
    d
}

/// Render the snapshot document of a run.
pub fn snapshot_yaml(result: &ScenarioResult) -> String {
    let mut out = String::new();
    let path = result.path.to_string_lossy().replace('\\', "/");
    let _ = writeln!(out, "scenario: {}", quote(&result.name));
    let _ = writeln!(out, "file: {}", quote(&path));
    let _ = writeln!(out, "clock: {}", result.clock);
    let verdict = match &result.verdict {
        Verdict::Passed => "passed".to_owned(),
        Verdict::Failed => "failed".to_owned(),
        Verdict::Skipped(reason) => format!("skipped\nreason: {}", quote(reason)),
        Verdict::Error(message) => format!("error\nerror: {}", quote(message)),
    };
    let _ = writeln!(out, "verdict: {verdict}");
    let _ = writeln!(out, "duration_ms: {}", ms(result.duration));

    out.push_str("steps:\n");
    for s in &result.steps {
        let _ = writeln!(out, "  - step: {}", s.index + 1);
        let _ = writeln!(out, "    line: {}", s.line);
        let _ = writeln!(out, "    action: {}", s.label);
        if let Some(id) = &s.id {
            let _ = writeln!(out, "    id: {}", quote(id));
        }
        let _ = writeln!(out, "    at_ms: {}", ms(s.started));
        let _ = writeln!(out, "    took_ms: {}", ms(s.took));
        let _ = writeln!(out, "    result: {}", s.outcome.name());
        match &s.outcome {
            Outcome::Failed { expected, actual } => {
                let _ = writeln!(out, "    expected: {}", quote(expected));
                let _ = writeln!(out, "    actual: {}", quote(actual));
            }
            Outcome::TimedOut {
                waited,
                expected,
                actual,
            } => {
                let _ = writeln!(out, "    waited_ms: {}", ms(*waited));
                let _ = writeln!(out, "    expected: {}", quote(expected));
                let _ = writeln!(out, "    actual: {}", quote(actual));
            }
            Outcome::Passed | Outcome::NotRun => {}
        }
        if !s.reply.is_empty() {
            out.push_str("    reply:\n");
            for (k, v) in &s.reply {
                let _ = writeln!(out, "      {k}: {}", quote(v));
            }
        }
    }

    if result.faults.is_empty() {
        out.push_str("faults: []\n");
    } else {
        out.push_str("faults:\n");
        for f in &result.faults {
            let _ = writeln!(
                out,
                "  - {{at_ms: {}, {}: {}, target: {}}}",
                ms(f.at),
                f.action,
                quote(&f.fault),
                quote(&f.target)
            );
        }
    }

    out.push_str("bus:\n");
    let _ = writeln!(out, "  frames: {}", result.bus.frames);
    if let Some(load) = result.bus.load_percent {
        let tenths = (load * 10.0).round() as i64;
        let _ = writeln!(out, "  load_percent: {}", fixed(tenths, 1));
    }
    let _ = writeln!(out, "  crc_errors: {}", result.bus.errors);
    let _ = writeln!(out, "  dropped: {}", result.bus.dropped);
    // Only for a bench of several buses: each one's frames and load against its bit rate.
    if !result.bus.per_bus.is_empty() {
        out.push_str("  per_bus:\n");
        for bus in &result.bus.per_bus {
            let tenths = (bus.load_percent * 10.0).round() as i64;
            let _ = writeln!(
                out,
                "    - {{name: {}, frames: {}, load_percent: {}}}",
                quote(&bus.name),
                bus.frames,
                fixed(tenths, 1)
            );
        }
    }
    // Only when it happened, so that complete recordings keep their snapshots.
    if result.bus.recorder_missed > 0 {
        let _ = writeln!(out, "  recorder_missed: {}", result.bus.recorder_missed);
    }
    // Likewise only for a recording cut at its size limit.
    if let Some(omitted) = &result.recording.omitted {
        out.push_str("  recording_omitted:\n");
        let _ = writeln!(out, "    frames: {}", omitted.frames);
        let _ = writeln!(out, "    from_ms: {}", ms(omitted.from));
        let _ = writeln!(out, "    to_ms: {}", ms(omitted.to));
        let _ = writeln!(out, "    limit_mib: {}", omitted.limit_bytes >> 20);
    }
    if result.bus.frames_by_id.is_empty() {
        out.push_str("  frames_by_id: {}\n");
    } else {
        out.push_str("  frames_by_id:\n");
        for (id, count) in &result.bus.frames_by_id {
            let _ = writeln!(out, "    \"0x{id:03X}\": {count}");
        }
    }

    let t = &result.trace;
    out.push_str("trace:\n");
    let _ = writeln!(out, "  period_ms: {}", t.period.as_millis());
    let names: Vec<&str> = std::iter::once("t_ms")
        .chain(t.columns.iter().map(|c| c.name.as_str()))
        .collect();
    let _ = writeln!(out, "  columns: [{}]", names.join(", "));
    if t.rows.is_empty() {
        out.push_str("  rows: []\n");
    } else {
        out.push_str("  rows:\n");
        let decimals: Vec<u32> = t.columns.iter().map(|c| decimals_of(c.quantum)).collect();
        for (at, values) in &t.rows {
            let mut cells = vec![at.as_millis().to_string()];
            for (v, d) in values.iter().zip(&decimals) {
                cells.push(v.map_or_else(|| "~".to_owned(), |v| fixed(v, *d)));
            }
            let _ = writeln!(out, "    - [{}]", cells.join(", "));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_formatting() {
        assert_eq!(fixed(900, 1), "90.0");
        assert_eq!(fixed(-5, 1), "-0.5");
        assert_eq!(fixed(-123, 2), "-1.23");
        assert_eq!(fixed(7, 0), "7");
        assert_eq!(decimals_of(0.1), 1);
        assert_eq!(decimals_of(0.01), 2);
        assert_eq!(decimals_of(1.0), 0);
        assert_eq!(ms(Duration::from_micros(12_345)), "12.3");
    }
}
