//! The Piper's fault front ends agree: a scenario file, the web view and the emulator's
//! builder refuse the same arguments with the same message.

use std::path::Path;

use serde_json::{json, Map, Value};
use sim::fault_args::{FaultArgValue, FaultArgs};

use crate::harness::parse_scenario;

/// The message of the scenario error `fault` (YAML flow mapping) gives as a step's fault.
fn scenario_message(fault: &str) -> String {
    let text = format!(
        "bench:\n  devices:\n    arm: {{kind: piper}}\nsteps:\n  - inject: {{fault: {fault}}}\n"
    );
    match parse_scenario(Path::new("f.yaml"), &text) {
        Ok(_) => panic!("{fault}: accepted"),
        Err(e) => {
            let headline = e.scenario_error().expect("a scenario error").headline();
            // `f.yaml:LINE:COL: message`
            headline
                .splitn(4, ':')
                .nth(3)
                .unwrap_or_default()
                .trim()
                .to_owned()
        }
    }
}

fn page_args(v: Value) -> Map<String, Value> {
    v.as_object().cloned().unwrap_or_default()
}

#[test]
fn scenario_web_view_and_builder_refuse_bad_arguments_alike() {
    let cases = [
        (
            "{external_torque: {joint: 1, torque_nm: 1e308}}",
            "external_torque",
            json!({"joint": 1, "torque_nm": 1e308}),
            FaultArgs::new()
                .with("joint", FaultArgValue::Number(1.0))
                .with("torque_nm", FaultArgValue::Number(1e308)),
        ),
        (
            "{under_voltage: {voltage_v: -1}}",
            "under_voltage",
            json!({"voltage_v": -1}),
            FaultArgs::new().with("voltage_v", FaultArgValue::Number(-1.0)),
        ),
        (
            "{stall: {joint: 7}}",
            "stall",
            json!({"joint": 7}),
            FaultArgs::new().with("joint", FaultArgValue::Number(7.0)),
        ),
        (
            "{estop: {joint: 1}}",
            "estop",
            json!({"joint": 1}),
            FaultArgs::new().with("joint", FaultArgValue::Number(1.0)),
        ),
        (
            "{ntc_over_temp: {board: aux}}",
            "ntc_over_temp",
            json!({"board": "aux"}),
            FaultArgs::new().with("board", FaultArgValue::Text("aux".into())),
        ),
        (
            "{external_torque: {joint: 2}}",
            "external_torque",
            json!({"joint": 2}),
            FaultArgs::new().with("joint", FaultArgValue::Number(2.0)),
        ),
    ];
    for (yaml, name, page, args) in cases {
        let built = sim::piper::build_fault(name, &args).unwrap_err().message;
        assert_eq!(scenario_message(yaml), built, "{yaml}");
        let web = sim::piper::build_fault(name, &crate::ui::page_fault_args(&page_args(page)))
            .unwrap_err()
            .message;
        assert_eq!(web, built, "{yaml}");
    }
}
