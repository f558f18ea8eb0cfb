use std::time::Duration;

use super::*;
use crate::harness::result::{BenchInfo, FaultEvent, StepResult};

fn failed_run() -> ScenarioResult {
    let mut r = ScenarioResult::not_run(
        "demo</script>",
        "scenarios/piper/demo.yaml".into(),
        Verdict::Failed,
        "virtual",
    );
    r.duration = Duration::from_millis(800);
    r.bench_info = BenchInfo {
        drawing: Some(crate::devices::Drawing::arm(sim::piper::BUNDLED_URDF)),
        // A Piper's bench: its frames are named by the Piper's decoder.
        frame_decoders: vec![crate::harness::result::DeviceFrames {
            buses: vec!["vcan0".to_owned()],
            decoder: std::sync::Arc::new(crate::devices::piper::decode::PiperFrames),
        }],
    };
    r.steps.push(StepResult {
        index: 0,
        line: 9,
        label: "wait_until".to_owned(),
        id: None,
        started: Duration::from_millis(100),
        took: Duration::from_millis(500),
        outcome: Outcome::TimedOut {
            waited: Duration::from_millis(500),
            expected: "arm_status <estop>".into(),
            actual: "arm_status normal".into(),
        },
        reply: Vec::new(),
    });
    r.faults.push(FaultEvent {
        at: Duration::from_millis(200),
        action: "inject",
        fault: "estop".into(),
        target: "arm".into(),
    });
    r
}

fn embedded_json(html: &str) -> serde_json::Value {
    let start = html.find("id=\"armhil-data\">").unwrap() + "id=\"armhil-data\">".len();
    let end = start + html[start..].find("</script>").unwrap();
    serde_json::from_str(&html[start..end]).unwrap()
}

#[test]
fn a_failed_report_names_the_step_in_plain_html() {
    let html = report_html(&failed_run());
    let summary = &html[..html.find("<main").unwrap()];
    assert!(summary.contains("Step 1 `wait_until` (line 9) timed out at 0.600 s"));
    assert!(summary.contains("arm_status &lt;estop&gt;"));
    assert!(summary.contains("class=\"verdict fail\""));
    // The name cannot end the data script early.
    assert_eq!(html.matches("</script>").count(), 5, "data + four scripts");
}

#[test]
fn the_embedded_document_round_trips_with_model_and_windows() {
    let html = report_html(&failed_run());
    let doc = embedded_json(&html);
    assert_eq!(doc["name"], "demo</script>");
    assert_eq!(doc["verdict"], "FAIL");
    assert_eq!(doc["steps"][0]["outcome"], "timed_out");
    assert_eq!(doc["windows"][0]["label"], "estop");
    assert_eq!(
        doc["windows"][0]["to"], 0.8,
        "open until the end of the run"
    );
    assert_eq!(doc["model"]["root"], "base_link");
    assert!(
        html.contains("function createArmView"),
        "scripts are inline"
    );
    assert!(!html.contains("src=\"http"), "nothing fetched");
}

#[test]
fn index_links_every_report_and_counts_verdicts() {
    let failed = failed_run();
    let passed = ScenarioResult::not_run("ok", "ok.yaml".into(), Verdict::Passed, "virtual");
    let html = index_html(
        "suite",
        &[
            IndexEntry {
                result: &failed,
                report: Some("piper/demo/report.html".into()),
            },
            IndexEntry {
                result: &passed,
                report: None,
            },
        ],
    );
    assert!(html.contains("2 scenarios: 1 passed, 1 failed, 0 errors, 0 skipped"));
    assert!(html.contains("href=\"piper/demo/report.html\""));
    assert!(html.contains("step 1 `wait_until` (line 9) timed out"));
}

#[test]
fn a_robot_report_draws_its_own_urdf_posed_by_named_columns() {
    // The humanoid's drawing, as the actuator_group kind gives it for its robot file.
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/humanoid.yaml");
    let robot = sim::robot::file::load_robot_file(&file).unwrap().config;
    let settings = crate::devices::actuator_group::model::GroupSettings {
        actuators: Vec::new(),
        buses: Vec::new(),
        robot: Some(robot),
    };
    let drawing = crate::devices::DeviceKind::ActuatorGroup(settings)
        .drawing()
        .unwrap();
    let mut run = failed_run();
    run.bench_info.drawing = Some(drawing);
    let data = embedded_json(&report_html(&run));
    // The model is the robot file's URDF: 20 movable joints from its root link.
    assert_eq!(data["model"]["root"], "trunk");
    let joints = data["pose"]["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 20);
    let knee = joints.iter().find(|j| j["joint"] == "left_knee").unwrap();
    assert_eq!(knee["column"], "left_knee_rad");
    assert!(knee["direction"].as_f64().unwrap().abs() == 1.0);
    assert_eq!(data["pose"]["base"]["position"][2], "base_height_m");
    assert_eq!(data["pose"]["base"]["rpy"][1], "base_pitch_rad");
    // An arm's report keeps the page's own j1_deg... convention: no pose document.
    assert!(embedded_json(&report_html(&failed_run()))
        .get("pose")
        .is_none());
}
