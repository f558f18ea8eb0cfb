//! `report.html` for one scenario and `index.html` for a suite: self-contained pages (styles,
//! scripts and data inline, nothing fetched) that a browser opens from disk.
//!
//! The scripts are web/common/*.js and web/report/report.js, built into the binary. The data is
//! one JSON document ([`data::report_json`]) in a `<script type="application/json">` element;
//! the verdict and the first failure are also written as plain HTML so they show even before
//! (or without) the scripts.

pub mod arm;
mod data;
pub mod visuals;

use std::borrow::Cow;
use std::fmt::Write as _;

pub use arm::{arm_model, arm_model_with_paths, ArmModelError, ArmModelJson};
pub use data::{report_json, MAX_FRAMES};

use sim::description::PackagePaths;

use crate::harness::result::{Outcome, ScenarioResult, Verdict};

macro_rules! web_asset {
    ($path:literal) => {
        include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/web/", $path))
    };
}

/// Styles shared by every page.
pub const STYLE_CSS: &str = web_asset!("common/style.css");
/// The arm's forward kinematics and renderer.
pub const ARM3D_JS: &str = web_asset!("common/arm3d.js");
/// The time plots.
pub const PLOT_JS: &str = web_asset!("common/plot.js");
/// Page-building helpers of the live page and the report.
pub const DOM_JS: &str = web_asset!("common/dom.js");
/// The report page's script.
pub const REPORT_JS: &str = web_asset!("report/report.js");
/// The live page's script (`armhil sim ... --ui`).
pub const LIVE_JS: &str = web_asset!("live/live.js");

/// `text` safe inside HTML text and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// JSON safe inside a `<script>` element: `</script>` and `<!--` cannot occur.
pub fn script_json(value: &serde_json::Value) -> String {
    value
        .to_string()
        .replace("</", "<\\/")
        .replace("<!--", "<\\!--")
}

fn verdict_class(v: &Verdict) -> &'static str {
    match v {
        Verdict::Passed => "pass",
        Verdict::Failed => "fail",
        Verdict::Skipped(_) => "skip",
        Verdict::Error(_) => "error",
    }
}

/// The verdict and, for a failed run, the failing step: plain HTML.
fn summary_html(result: &ScenarioResult) -> String {
    let mut out = String::new();
    let _ = write!(
        out,
        "<h1>{} <span class=\"verdict {}\">{}</span></h1><p class=\"meta\">{} · {} clock · {:.3} s scenario time</p>",
        escape(&result.name),
        verdict_class(&result.verdict),
        result.verdict.word(),
        escape(&result.path.display().to_string()),
        escape(&result.clock),
        result.duration.as_secs_f64(),
    );
    if let Verdict::Skipped(reason) | Verdict::Error(reason) = &result.verdict {
        let _ = write!(out, "<p class=\"failure\">{}</p>", escape(reason));
    }
    if let Some(step) = result.first_failure() {
        let _ = write!(
            out,
            "<div class=\"failure\" id=\"first-failure\"><b>Step {} `{}` (line {}) {} at {:.3} s</b>",
            step.index + 1,
            escape(&step.label),
            step.line,
            step.outcome.name().replace('_', " "),
            (step.started + step.took).as_secs_f64(),
        );
        if let Outcome::Failed { expected, actual }
        | Outcome::TimedOut {
            expected, actual, ..
        } = &step.outcome
        {
            let _ = write!(
                out,
                "<br>expected: <code>{}</code><br>actual: <code>{}</code>",
                escape(expected),
                escape(actual)
            );
        }
        out.push_str("</div>");
    }
    out
}

/// The page around a body and a script.
fn page(title: &str, body: &str, scripts: &[&str]) -> String {
    let mut out = String::with_capacity(body.len() + 64 * 1024);
    let _ = write!(
        out,
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta name=\"viewport\" content=\"width=device-width\"><title>{}</title><style>{STYLE_CSS}</style></head><body>\n{body}\n",
        escape(title)
    );
    for s in scripts {
        let _ = writeln!(out, "<script>{s}</script>");
    }
    out.push_str("</body></html>\n");
    out
}

/// The live page: styles, the shared scripts and `script` (it builds the page and connects to
/// `/ws` on the server that sent it).
pub fn live_page(title: &str, script: &str) -> String {
    page(
        title,
        "<main id=\"app\"></main>",
        &[ARM3D_JS, PLOT_JS, DOM_JS, script],
    )
}

/// The model JSON of the arm or robot a run drove, if it has one that can be read.
fn model_value(result: &ScenarioResult) -> Option<serde_json::Value> {
    // Every report of a suite draws one of a few URDFs (the bundled ones, a robot's): parse
    // each once, and read its meshes once. Keyed by the text, which a robot file's scenarios
    // each hold a copy of, and where its files are.
    type Key = (Cow<'static, str>, PackagePaths);
    static MODELS: std::sync::Mutex<Vec<(Key, Option<serde_json::Value>)>> =
        std::sync::Mutex::new(Vec::new());
    let drawing = result.bench_info.drawing.as_ref()?;
    let paths = drawing.paths.clone().unwrap_or_default();
    let mut models = MODELS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, model)) = models
        .iter()
        .find(|((u, p), _)| *u == drawing.urdf && *p == paths)
    {
        return model.clone();
    }
    let model = arm_model_with_paths(&drawing.urdf, &paths)
        .ok()
        .and_then(|m| serde_json::to_value(m).ok());
    models.push(((drawing.urdf.clone(), paths), model.clone()));
    model
}

/// The report page of one run.
pub fn report_html(result: &ScenarioResult) -> String {
    let data = report_json(result, model_value(result));
    let body = format!(
        "<header id=\"summary\">{}</header>\n<main id=\"app\"></main>\n<script type=\"application/json\" id=\"armhil-data\">{}</script>",
        summary_html(result),
        script_json(&data)
    );
    page(
        &format!("{} — {}", result.name, result.verdict.word()),
        &body,
        &[ARM3D_JS, PLOT_JS, DOM_JS, REPORT_JS],
    )
}

/// One line of a suite's index: the run and where its report is (relative to the index).
#[derive(Debug, Clone)]
pub struct IndexEntry<'a> {
    /// The run.
    pub result: &'a ScenarioResult,
    /// Its report.html relative to index.html, when one was written.
    pub report: Option<String>,
}

/// The index page of a suite: one row per scenario with its verdict, link and first failure.
pub fn index_html(title: &str, entries: &[IndexEntry<'_>]) -> String {
    let count = |f: fn(&Verdict) -> bool| entries.iter().filter(|e| f(&e.result.verdict)).count();
    let mut body = format!(
        "<header><h1>{}</h1><p class=\"meta\">{} scenarios: {} passed, {} failed, {} errors, {} skipped</p></header><main><table class=\"index\"><thead><tr><th>verdict</th><th>scenario</th><th>steps</th><th>time (s)</th><th>first failure</th></tr></thead><tbody>",
        escape(title),
        entries.len(),
        count(|v| matches!(v, Verdict::Passed)),
        count(|v| matches!(v, Verdict::Failed)),
        count(|v| matches!(v, Verdict::Error(_))),
        count(|v| matches!(v, Verdict::Skipped(_))),
    );
    for e in entries {
        let r = e.result;
        let name = match &e.report {
            Some(href) => format!("<a href=\"{}\">{}</a>", escape(href), escape(&r.name)),
            None => escape(&r.name),
        };
        let failure = match (&r.verdict, r.first_failure()) {
            (Verdict::Skipped(reason) | Verdict::Error(reason), _) => escape(reason),
            (_, Some(s)) => format!(
                "step {} `{}` (line {}) {}",
                s.index + 1,
                escape(&s.label),
                s.line,
                s.outcome.name().replace('_', " ")
            ),
            _ => String::new(),
        };
        let passed = r.steps.iter().filter(|s| s.outcome.passed()).count();
        let _ = write!(
            body,
            "<tr class=\"{}\"><td><span class=\"verdict {}\">{}</span></td><td>{name}</td><td>{passed}/{}</td><td>{:.2}</td><td>{failure}</td></tr>",
            verdict_class(&r.verdict),
            verdict_class(&r.verdict),
            r.verdict.word(),
            r.steps.len(),
            r.duration.as_secs_f64(),
        );
    }
    body.push_str("</tbody></table></main>");
    page(title, &body, &[])
}

#[cfg(test)]
mod tests;
