//! The dependency rule of docs/architecture.md: the driver and the emulators never depend on each other,
//! in any dependency kind, so neither can borrow the other's codec.

use std::process::Command;

use serde_json::Value;

fn workspace_metadata() -> Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
    let output = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--offline",
            "--no-deps",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        output.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("cargo metadata prints JSON")
}

fn dependency_names(metadata: &Value, package: &str) -> Vec<String> {
    let packages = metadata["packages"].as_array().expect("packages array");
    let found = packages
        .iter()
        .find(|candidate| candidate["name"] == package)
        .unwrap_or_else(|| panic!("package {package} is in the workspace"));
    found["dependencies"]
        .as_array()
        .expect("dependencies array")
        .iter()
        .map(|dependency| dependency["name"].as_str().unwrap_or_default().to_owned())
        .collect()
}

#[test]
fn driver_and_sim_do_not_depend_on_each_other() {
    let metadata = workspace_metadata();
    let driver = dependency_names(&metadata, "armhil-driver");
    let sim = dependency_names(&metadata, "armhil-sim");
    assert!(
        driver.iter().any(|name| name == "armhil-bus"),
        "driver uses the bus: {driver:?}"
    );
    assert!(
        !driver.iter().any(|name| name == "armhil-sim"),
        "driver depends on sim: {driver:?}"
    );
    assert!(
        !sim.iter().any(|name| name == "armhil-driver"),
        "sim depends on driver: {sim:?}"
    );
}

/// The features of `package` as `cargo metadata` lists them: name → what each enables.
fn features(metadata: &Value, package: &str) -> serde_json::Map<String, Value> {
    let packages = metadata["packages"].as_array().expect("packages array");
    let found = packages
        .iter()
        .find(|candidate| candidate["name"] == package)
        .unwrap_or_else(|| panic!("package {package} is in the workspace"));
    found["features"].as_object().expect("features map").clone()
}

/// The test support crate is a dev-dependency of both sides; the part the emulator tests use
/// must not bring the driver in, or a `sim` test could decode with the driver's codec.
#[test]
fn the_emulators_test_support_does_not_bring_in_the_driver() {
    let metadata = workspace_metadata();
    let features = features(&metadata, "armhil-testkit");
    let enables = |feature: &str| -> Vec<String> {
        features[feature]
            .as_array()
            .unwrap_or_else(|| panic!("feature {feature} of armhil-testkit"))
            .iter()
            .map(|item| item.as_str().unwrap_or_default().to_owned())
            .collect()
    };
    let emulators = enables("emulators");
    assert!(
        emulators.iter().any(|item| item == "dep:armhil-sim"),
        "the emulators feature brings in sim: {emulators:?}"
    );
    assert!(
        !emulators.iter().any(|item| item.contains("armhil-driver")),
        "the emulators feature brings in the driver: {emulators:?}"
    );
    assert!(
        enables("default").is_empty(),
        "armhil-testkit's default features stay empty"
    );
    let sim_dev: Vec<String> = dependency_names(&metadata, "armhil-sim");
    assert!(
        sim_dev.iter().any(|name| name == "armhil-testkit"),
        "sim's tests use the test support crate: {sim_dev:?}"
    );
}
