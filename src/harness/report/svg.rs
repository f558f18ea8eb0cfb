//! An SVG plot of the trace: one panel per signal group (joints, currents, gripper...), time
//! on the x axis, fault windows shaded.

use std::fmt::Write as _;
use std::time::Duration;

use crate::harness::result::{ScenarioResult, Trace};

const WIDTH: f64 = 960.0;
const PANEL_HEIGHT: f64 = 220.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 150.0;
const TOP: f64 = 40.0;
const GAP: f64 = 40.0;
const COLORS: [&str; 8] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

/// Groups plotted, in order, with their axis label.
const GROUPS: [(&str, &str); 5] = [
    ("joints", "joint angle (deg)"),
    ("currents", "motor current (A)"),
    ("gripper", "gripper stroke (mm)"),
    ("speeds", "joint speed (deg/s)"),
    ("temperatures", "motor temperature (°C)"),
];

/// A shaded time window with its label.
pub(super) struct Window {
    /// Start (scenario time).
    pub from: Duration,
    /// End (scenario time).
    pub to: Duration,
    /// The fault.
    pub label: String,
}

/// The time windows during which each fault was active.
pub(super) fn fault_windows(result: &ScenarioResult) -> Vec<Window> {
    let mut open: Vec<(Duration, String, String)> = Vec::new();
    let mut windows = Vec::new();
    for e in &result.faults {
        if e.action == "inject" {
            open.push((e.at, e.fault.clone(), e.target.clone()));
        } else if e.fault == "all faults" {
            for (from, label, _) in open.drain(..) {
                windows.push(Window {
                    from,
                    to: e.at,
                    label,
                });
            }
        } else if let Some(i) = open
            .iter()
            .position(|(_, f, t)| *f == e.fault && *t == e.target)
        {
            let (from, label, _) = open.remove(i);
            windows.push(Window {
                from,
                to: e.at,
                label,
            });
        }
    }
    for (from, label, _) in open {
        windows.push(Window {
            from,
            to: result.duration,
            label,
        });
    }
    windows.sort_by_key(|w| w.from);
    windows
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Tidy axis bounds around the data (with a little margin, never a zero range).
fn bounds(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return None;
    }
    if (hi - lo).abs() < 1e-9 {
        lo -= 1.0;
        hi += 1.0;
    }
    let margin = (hi - lo) * 0.05;
    Some((lo - margin, hi + margin))
}

fn panel(
    out: &mut String,
    trace: &Trace,
    group: &str,
    label: &str,
    top: f64,
    t_end: f64,
    windows: &[Window],
) {
    let cols: Vec<usize> = trace
        .columns
        .iter()
        .enumerate()
        .filter(|(_, c)| c.group == group)
        .map(|(i, _)| i)
        .collect();
    let value = |row: &[Option<i64>], c: usize| {
        row.get(c)
            .copied()
            .flatten()
            .map(|v| v as f64 * trace.columns[c].quantum)
    };
    let Some((lo, hi)) = bounds(
        trace
            .rows
            .iter()
            .flat_map(|(_, row)| cols.iter().filter_map(move |c| value(row, *c))),
    ) else {
        return;
    };
    let plot_w = WIDTH - LEFT - RIGHT;
    let x = |t: f64| LEFT + plot_w * (t / t_end);
    let y = |v: f64| top + PANEL_HEIGHT * (1.0 - (v - lo) / (hi - lo));
    let _ = writeln!(
        out,
        r##"<rect x="{LEFT}" y="{top}" width="{plot_w}" height="{PANEL_HEIGHT}" fill="#fafafa" stroke="#999"/>"##
    );
    for w in windows {
        let x0 = x(w.from.as_secs_f64());
        let x1 = x(w.to.as_secs_f64()).max(x0 + 1.0);
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{top}" width="{:.1}" height="{PANEL_HEIGHT}" fill="#d62728" fill-opacity="0.15"><title>{}</title></rect>"##,
            x1 - x0,
            escape(&w.label)
        );
    }
    // Label the fault windows once, on the first panel.
    if top <= TOP {
        for (k, w) in windows.iter().enumerate() {
            let _ = writeln!(
                out,
                r##"<text x="{:.1}" y="{:.1}" font-size="10" fill="#a01010">{}</text>"##,
                x(w.from.as_secs_f64()) + 3.0,
                top + 12.0 + 12.0 * (k % 4) as f64,
                escape(&w.label)
            );
        }
    }
    // Horizontal grid: bottom, middle, top values.
    for frac in [0.0, 0.5, 1.0] {
        let v = lo + (hi - lo) * frac;
        let yy = y(v);
        let _ = writeln!(
            out,
            r##"<line x1="{LEFT}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{v:.1}</text>"##,
            LEFT + plot_w,
            LEFT - 6.0,
            yy + 4.0
        );
    }
    if lo < 0.0 && hi > 0.0 {
        let _ = writeln!(
            out,
            r##"<line x1="{LEFT}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#999" stroke-dasharray="3,3"/>"##,
            y(0.0),
            LEFT + plot_w,
            y(0.0)
        );
    }
    let _ = writeln!(
        out,
        r##"<text x="14" y="{:.1}" font-size="12" transform="rotate(-90 14 {:.1})" text-anchor="middle">{}</text>"##,
        top + PANEL_HEIGHT / 2.0,
        top + PANEL_HEIGHT / 2.0,
        escape(label)
    );
    for (k, c) in cols.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let points = trace
            .rows
            .iter()
            .filter_map(|(t, row)| value(row, *c).map(|v| (x(t.as_secs_f64()), y(v))));
        let _ = writeln!(
            out,
            r##"<polyline fill="none" stroke="{color}" stroke-width="1.5" points="{}"/>"##,
            polyline_points(points)
        );
        let ly = top + 14.0 + 16.0 * k as f64;
        let _ = writeln!(
            out,
            r##"<line x1="{:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{color}" stroke-width="2"/><text x="{:.1}" y="{:.1}" font-size="11">{}</text>"##,
            WIDTH - RIGHT + 10.0,
            WIDTH - RIGHT + 30.0,
            WIDTH - RIGHT + 35.0,
            ly + 4.0,
            escape(&trace.columns[*c].name)
        );
    }
}

/// The `points` attribute of a polyline, at 0.1 px, without the points that draw nothing: a
/// repeat of the point before, or a point inside a horizontal run (the line through it is
/// drawn by its neighbours anyway). A long steady trace then costs a few points instead of
/// one per sample; the drawing is the same.
fn polyline_points(points: impl Iterator<Item = (f64, f64)>) -> String {
    let mut shown: Vec<(String, String)> = Vec::new();
    for (px, py) in points {
        let point = (format!("{px:.1}"), format!("{py:.1}"));
        if shown.last() != Some(&point) {
            shown.push(point);
        }
    }
    let mut out = String::new();
    for (i, (px, py)) in shown.iter().enumerate() {
        let level_before = i > 0 && shown[i - 1].1 == *py;
        let level_after = shown.get(i + 1).is_some_and(|next| next.1 == *py);
        if !(level_before && level_after) {
            if !out.is_empty() {
                out.push(' ');
            }
            let _ = write!(out, "{px},{py}");
        }
    }
    out
}

/// Render the plot of a run: one panel per signal group, fault windows shaded.
pub fn plot_svg(result: &ScenarioResult) -> String {
    let trace = &result.trace;
    let groups: Vec<(&str, &str)> = GROUPS
        .iter()
        .copied()
        .filter(|(g, _)| trace.columns.iter().any(|c| c.group == *g))
        .collect();
    let panels = groups.len().max(1) as f64;
    let height = TOP + panels * (PANEL_HEIGHT + GAP) + 20.0;
    let t_end = result
        .duration
        .as_secs_f64()
        .max(trace.rows.last().map_or(0.0, |(t, _)| t.as_secs_f64()))
        .max(1e-3);
    let windows = fault_windows(result);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height:.0}" viewBox="0 0 {WIDTH} {height:.0}" font-family="sans-serif">"#
    );
    let _ = writeln!(
        out,
        r##"<rect width="100%" height="100%" fill="white"/><text x="{LEFT}" y="24" font-size="15">{} — {} ({})</text>"##,
        escape(&result.name),
        result.verdict.word(),
        escape(&result.clock)
    );
    for (i, (group, label)) in groups.iter().enumerate() {
        let top = TOP + i as f64 * (PANEL_HEIGHT + GAP);
        panel(&mut out, trace, group, label, top, t_end, &windows);
        // Time axis under every panel.
        let plot_w = WIDTH - LEFT - RIGHT;
        for k in 0..=5 {
            let t = t_end * f64::from(k) / 5.0;
            let xx = LEFT + plot_w * f64::from(k) / 5.0;
            let _ = writeln!(
                out,
                r#"<text x="{xx:.1}" y="{:.1}" font-size="10" text-anchor="middle">{:.0} ms</text>"#,
                top + PANEL_HEIGHT + 13.0,
                t * 1000.0
            );
        }
    }
    out.push_str("</svg>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_stretches_cost_their_ends_only() {
        // Flat, a ramp of three samples, flat again: 1,000 samples.
        let ys = (0..1000).map(|i| match i {
            0..=499 => 10.0,
            500..=502 => 10.0 + f64::from(i - 499),
            _ => 13.0,
        });
        let points = ys.enumerate().map(|(i, y)| (i as f64 * 0.5, y));
        assert_eq!(
            polyline_points(points),
            "0.0,10.0 249.5,10.0 250.0,11.0 250.5,12.0 251.0,13.0 499.5,13.0"
        );
    }

    #[test]
    fn repeats_go_and_every_turn_stays() {
        let points = [(1.0, 5.0), (1.04, 5.0), (2.0, 6.0), (3.0, 5.0), (3.0, 5.0)];
        assert_eq!(
            polyline_points(points.into_iter()),
            "1.0,5.0 2.0,6.0 3.0,5.0"
        );
        assert_eq!(polyline_points(std::iter::empty()), "");
        assert_eq!(polyline_points([(1.0, 2.0)].into_iter()), "1.0,2.0");
    }
}
