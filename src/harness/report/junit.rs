//! JUnit XML for a suite: one test case per scenario.

use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};

use crate::harness::result::{Outcome, ScenarioResult, Verdict};

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

/// Render a JUnit XML report of `results` (one test case per scenario; times are wall time).
pub fn junit_xml(
    suite: &str,
    results: &[ScenarioResult],
) -> Result<String, quick_junit::SerializeError> {
    let mut test_suite = TestSuite::new(suite);
    for r in results {
        let status = match &r.verdict {
            Verdict::Passed => TestCaseStatus::success(),
            Verdict::Failed => {
                let (message, body) = failure_text(r);
                let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
                status
                    .set_message(message)
                    .set_type("step")
                    .set_description(body);
                status
            }
            Verdict::Skipped(reason) => {
                let mut status = TestCaseStatus::skipped();
                status.set_message(reason.as_str());
                status
            }
            Verdict::Error(message) => {
                let mut status = TestCaseStatus::non_success(NonSuccessKind::Error);
                status
                    .set_message(message.lines().next().unwrap_or_default())
                    .set_type("error")
                    .set_description(message.as_str());
                status
            }
        };
        let classname = r
            .path
            .parent()
            .map(|p| p.to_string_lossy().replace(['/', '\\'], "."))
            .unwrap_or_default();
        let mut case = TestCase::new(r.name.as_str(), status);
        case.set_classname(classname).set_time(r.wall);
        case.extra
            .insert("file".into(), r.path.to_string_lossy().as_ref().into());
        test_suite.add_test_case(case);
    }
    let time: std::time::Duration = results.iter().map(|r| r.wall).sum();
    test_suite.set_time(time);
    let mut report = Report::new(suite);
    report.set_time(time).add_test_suite(test_suite);
    report.to_string()
}
