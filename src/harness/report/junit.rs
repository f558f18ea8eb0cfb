//! JUnit XML for a suite: one test case per scenario.

use std::fmt::Write as _;

use crate::harness::result::{Outcome, ScenarioResult, Verdict};

fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && !matches!(c, '\n' | '\t' | '\r') => {}
            c => out.push(c),
        }
    }
    out
}

/// Why a scenario failed, as a one-line message and a body.
fn failure_text(result: &ScenarioResult) -> (String, String) {
    match result.first_failure() {
        Some(step) => {
            let headline = format!(
                "step {} ({}, line {}) {}",
                step.index + 1,
                step.label,
                step.line,
                step.outcome.name().replace('_', " ")
            );
            let body = match &step.outcome {
                Outcome::Failed { expected, actual } => {
                    format!("expected: {expected}\nactual: {actual}")
                }
                Outcome::TimedOut {
                    waited,
                    expected,
                    actual,
                } => format!(
                    "waited {} ms\nexpected: {expected}\nactual: {actual}",
                    waited.as_millis()
                ),
                Outcome::Passed | Outcome::NotRun => String::new(),
            };
            (headline, body)
        }
        None => ("failed".to_owned(), String::new()),
    }
}

/// Render a JUnit XML report of `results`.
pub fn junit_xml(suite: &str, results: &[ScenarioResult]) -> String {
    let count = |f: fn(&Verdict) -> bool| results.iter().filter(|r| f(&r.verdict)).count();
    let failures = count(|v| matches!(v, Verdict::Failed));
    let errors = count(|v| matches!(v, Verdict::Error(_)));
    let skipped = count(|v| matches!(v, Verdict::Skipped(_)));
    let time: f64 = results.iter().map(|r| r.wall.as_secs_f64()).sum();
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        out,
        "<testsuites name=\"{}\" tests=\"{}\" failures=\"{failures}\" errors=\"{errors}\" skipped=\"{skipped}\" time=\"{time:.3}\">",
        escape(suite),
        results.len()
    );
    let _ = writeln!(
        out,
        "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{failures}\" errors=\"{errors}\" skipped=\"{skipped}\" time=\"{time:.3}\">",
        escape(suite),
        results.len()
    );
    for r in results {
        let classname = r
            .path
            .parent()
            .map(|p| p.to_string_lossy().replace(['/', '\\'], "."))
            .unwrap_or_default();
        let _ = write!(
            out,
            "    <testcase name=\"{}\" classname=\"{}\" file=\"{}\" time=\"{:.3}\"",
            escape(&r.name),
            escape(&classname),
            escape(&r.path.to_string_lossy()),
            r.wall.as_secs_f64()
        );
        match &r.verdict {
            Verdict::Passed => out.push_str(" />\n"),
            Verdict::Failed => {
                let (message, body) = failure_text(r);
                let _ = writeln!(
                    out,
                    ">\n      <failure message=\"{}\" type=\"step\">{}</failure>\n    </testcase>",
                    escape(&message),
                    escape(&body)
                );
            }
            Verdict::Skipped(reason) => {
                let _ = writeln!(
                    out,
                    ">\n      <skipped message=\"{}\" />\n    </testcase>",
                    escape(reason)
                );
            }
            Verdict::Error(message) => {
                let headline = message.lines().next().unwrap_or_default();
                let _ = writeln!(
                    out,
                    ">\n      <error message=\"{}\" type=\"error\">{}</error>\n    </testcase>",
                    escape(headline),
                    escape(message)
                );
            }
        }
    }
    out.push_str("  </testsuite>\n</testsuites>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(escape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
    }
}
