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

/// Plot groups, in the order their panels stand, with the quantity their axis shows. A group
/// not listed gets a panel after these, named by the group; `status` (mode and fault codes)
/// gets none: its numbers are labels, not quantities.
const GROUPS: [(&str, &str); 10] = [
    ("joints", "joint angle"),
    ("angles", "joint angle"),
    ("currents", "motor current"),
    ("gripper", "gripper stroke"),
    ("speeds", "joint speed"),
    ("torques", "torque"),
    ("temperatures", "motor temperature"),
    ("pose", "pose"),
    ("base", "floating base"),
    ("status", ""),
];

/// Units by column-name suffix, longest first (`_rad_s` before `_s`-less `_rad`).
const UNITS: [(&str, &str); 10] = [
    ("_deg_s", "deg/s"),
    ("_rad_s", "rad/s"),
    ("_deg", "deg"),
    ("_rad", "rad"),
    ("_nm", "N·m"),
    ("_mm", "mm"),
    ("_m", "m"),
    ("_a", "A"),
    ("_c", "°C"),
    ("_v", "V"),
];

/// The unit of a column, from its name's suffix.
fn unit_of(column: &str) -> Option<&'static str> {
    UNITS
        .iter()
        .find(|(suffix, _)| column.ends_with(suffix))
        .map(|(_, unit)| *unit)
}

/// The panels to draw: each group of the trace once, in [`GROUPS`]' order then the trace's,
/// with its axis label (the unit when every column of the group shares one).
fn panels(trace: &Trace) -> Vec<(&'static str, String)> {
    let mut groups: Vec<&'static str> = Vec::new();
    for known in GROUPS.iter().map(|(g, _)| *g) {
        if trace.columns.iter().any(|c| c.group == known) {
            groups.push(known);
        }
    }
    for column in &trace.columns {
        if !groups.contains(&column.group) {
            groups.push(column.group);
        }
    }
    groups
        .into_iter()
        .filter_map(|group| {
            let quantity = GROUPS
                .iter()
                .find(|(g, _)| *g == group)
                .map_or(group, |(_, q)| *q);
            if quantity.is_empty() {
                return None;
            }
            let mut units = trace
                .columns
                .iter()
                .filter(|c| c.group == group)
                .map(|c| unit_of(&c.name));
            let first = units.next().flatten();
            let label = match first {
                Some(unit) if units.all(|u| u == Some(unit)) => format!("{quantity} ({unit})"),
                _ => quantity.to_owned(),
            };
            Some((group, label))
        })
        .collect()
}

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

/// Where a panel stands: its top, its height (enough for its legend) and the right margin
/// the legends take.
#[derive(Debug, Clone, Copy)]
struct Frame {
    top: f64,
    height: f64,
    right: f64,
}

/// Height of one legend line, px.
const LEGEND_LINE: f64 = 16.0;

/// A panel's height: the standard one, or taller when its legend needs it (a robot's 20
/// joints).
fn panel_height(trace: &Trace, group: &str) -> f64 {
    let lines = trace.columns.iter().filter(|c| c.group == group).count() as f64;
    PANEL_HEIGHT.max(14.0 + LEGEND_LINE * lines)
}

/// The right margin: the standard one, or wider for long column names (`right_shoulder_pitch_rad`).
fn right_margin(trace: &Trace) -> f64 {
    let longest = trace
        .columns
        .iter()
        .map(|c| c.name.chars().count())
        .max()
        .unwrap_or(0) as f64;
    RIGHT.max(45.0 + 6.5 * longest).min(WIDTH / 3.0)
}

fn panel(
    out: &mut String,
    trace: &Trace,
    group: &str,
    label: &str,
    frame: Frame,
    t_end: f64,
    windows: &[Window],
) {
    let Frame {
        top,
        height: panel_height,
        right,
    } = frame;
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
    let plot_w = WIDTH - LEFT - right;
    let x = |t: f64| LEFT + plot_w * (t / t_end);
    let y = |v: f64| top + panel_height * (1.0 - (v - lo) / (hi - lo));
    let _ = writeln!(
        out,
        r##"<rect x="{LEFT}" y="{top}" width="{plot_w}" height="{panel_height}" fill="#fafafa" stroke="#999"/>"##
    );
    for w in windows {
        let x0 = x(w.from.as_secs_f64());
        let x1 = x(w.to.as_secs_f64()).max(x0 + 1.0);
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{top}" width="{:.1}" height="{panel_height}" fill="#d62728" fill-opacity="0.15"><title>{}</title></rect>"##,
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
    // Horizontal grid: bottom, middle, top values, with the decimals their spacing needs (a
    // floating base resting at 0.805-0.810 m reads as such, not as 0.8 three times).
    let decimals = (1.0 - (hi - lo).log10()).ceil().clamp(1.0, 4.0) as usize;
    for frac in [0.0, 0.5, 1.0] {
        let v = lo + (hi - lo) * frac;
        let yy = y(v);
        let _ = writeln!(
            out,
            r##"<line x1="{LEFT}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="end">{v:.decimals$}</text>"##,
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
        top + panel_height / 2.0,
        top + panel_height / 2.0,
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
            WIDTH - right + 10.0,
            WIDTH - right + 30.0,
            WIDTH - right + 35.0,
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
    let groups = panels(trace);
    let right = right_margin(trace);
    let mut frames = Vec::with_capacity(groups.len());
    let mut top = TOP;
    for (group, _) in &groups {
        let height = panel_height(trace, group);
        frames.push(Frame { top, height, right });
        top += height + GAP;
    }
    let height = if groups.is_empty() {
        TOP + PANEL_HEIGHT + GAP + 20.0
    } else {
        top + 20.0
    };
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
    for ((group, label), frame) in groups.iter().zip(&frames) {
        panel(&mut out, trace, group, label, *frame, t_end, &windows);
        // Time axis under every panel.
        let (top, panel_height) = (frame.top, frame.height);
        let plot_w = WIDTH - LEFT - right;
        for k in 0..=5 {
            let t = t_end * f64::from(k) / 5.0;
            let xx = LEFT + plot_w * f64::from(k) / 5.0;
            let _ = writeln!(
                out,
                r#"<text x="{xx:.1}" y="{:.1}" font-size="10" text-anchor="middle">{:.0} ms</text>"#,
                top + panel_height + 13.0,
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

    fn trace_of(columns: &[(&str, &'static str)]) -> Trace {
        Trace {
            period: Duration::from_millis(10),
            columns: columns
                .iter()
                .map(|(name, group)| crate::harness::result::Column {
                    name: (*name).to_owned(),
                    quantum: 0.001,
                    group,
                })
                .collect(),
            rows: (0..3)
                .map(|i| {
                    let t = Duration::from_millis(10 * i);
                    (t, columns.iter().map(|_| Some(805 + i as i64)).collect())
                })
                .collect(),
        }
    }

    /// Every group a kind traces gets its panel (a RobStride bus's and a robot's `angles` had
    /// none: their plot was empty), with the unit its columns share; codes are not plotted.
    #[test]
    fn every_traced_quantity_gets_a_panel_labelled_with_its_unit() {
        let trace = trace_of(&[
            ("m1_rad", "angles"),
            ("m1_nm", "torques"),
            ("m1_mode", "status"),
            ("base_height_m", "base"),
            ("base_roll_rad", "base"),
        ]);
        let labels: Vec<String> = panels(&trace).into_iter().map(|(_, l)| l).collect();
        assert_eq!(
            labels,
            ["joint angle (rad)", "torque (N·m)", "floating base"]
        );
    }

    /// A robot's twenty joints: the panel grows so that its legend stays inside it, the margin
    /// so that the longest name is not cut, and the axis shows the decimals its range needs.
    #[test]
    fn a_panel_of_many_long_columns_makes_room_for_its_legend() {
        let names: Vec<String> = (0..20)
            .map(|i| format!("right_shoulder_pitch_{i}_rad"))
            .collect();
        let columns: Vec<(&str, &'static str)> =
            names.iter().map(|n| (n.as_str(), "angles")).collect();
        let trace = trace_of(&columns);
        assert!(panel_height(&trace, "angles") >= 14.0 + LEGEND_LINE * 20.0);
        assert!(right_margin(&trace) > RIGHT);
        let mut out = String::new();
        let frame = Frame {
            top: TOP,
            height: panel_height(&trace, "angles"),
            right: right_margin(&trace),
        };
        panel(
            &mut out,
            &trace,
            "angles",
            "joint angle (rad)",
            frame,
            0.02,
            &[],
        );
        // Values 0.805 to 0.807: the middle tick is 0.806, not "0.8".
        assert!(out.contains(">0.8060</text>"), "{out}");
    }
}
