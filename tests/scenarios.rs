//! Scenario tests, one libtest test per scenario file (named by its path under `scenarios/`
//! without extension, e.g. `piper/move_l`): it must pass and match its committed insta
//! snapshot. Besides: a determinism check (two runs of the suite write the same set of files,
//! byte for byte) and a check that every committed snapshot belongs to a scenario.
//!
//! `cargo test --test scenarios -- piper/move_l` runs one scenario;
//! `cargo nextest run --partition hash:1/4` runs a quarter of them.

use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use armhil::harness::report::{snapshot_yaml, write_outputs};
use armhil::harness::{discover_suite, load_suite_file, run_scenario, Clock, SuiteFile, Verdict};
use libtest_mimic::{Arguments, Failed, Trial};

const SUITE: &str = "scenarios";
const SNAPSHOTS: &str = "tests/snapshots";

fn suite() -> Vec<SuiteFile> {
    discover_suite(&[PathBuf::from(SUITE)]).expect("scenarios/ is readable")
}

/// Test and snapshot names of a scenario: its path under the suite (`piper/move_l`), and the
/// same with `/` → `__` (`piper__move_l`).
fn test_name(file: &SuiteFile) -> String {
    file.out_dir.to_string_lossy().replace('\\', "/")
}

fn snapshot_name(file: &SuiteFile) -> String {
    test_name(file).replace('/', "__")
}

/// Turn a panic (an insta mismatch, an assertion) into a test failure.
fn guarded(f: impl FnOnce() -> Result<(), Failed>) -> Result<(), Failed> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(panic) => Err(panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
            .unwrap_or_else(|| "panicked".to_owned())
            .into()),
    }
}

/// Run one scenario and compare it with its snapshot.
fn scenario_passes_and_matches_its_snapshot(file: &SuiteFile) -> Result<(), Failed> {
    let scenario = load_suite_file(file).map_err(|e| e.to_string())?;
    let result = run_scenario(&scenario, &Clock::Virtual);
    let text = snapshot_yaml(&result);
    if result.verdict != Verdict::Passed {
        return Err(format!("verdict {:?}\n{text}", result.verdict).into());
    }
    let name = snapshot_name(file);
    insta::with_settings!({
        prepend_module_to_snapshot => false,
        omit_expression => true,
        snapshot_path => Path::new(env!("CARGO_MANIFEST_DIR")).join(SNAPSHOTS),
    }, {
        insta::assert_snapshot!(name.as_str(), text);
    });
    Ok(())
}

/// Every file under `dir`, by path relative to it.
fn files_under(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(root, &path, out);
            } else if let Ok(bytes) = std::fs::read(&path) {
                out.insert(
                    path.strip_prefix(root).unwrap_or(&path).to_path_buf(),
                    bytes,
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Run the whole suite and write every output under `dir`, as `armhil run` does.
fn run_suite_into(files: &[SuiteFile], dir: &Path) -> Result<(), Failed> {
    for file in files {
        let scenario = load_suite_file(file).map_err(|e| e.to_string())?;
        let result = run_scenario(&scenario, &Clock::Virtual);
        write_outputs(&result, &scenario.record, &dir.join(&file.out_dir))
            .map_err(|e| format!("{}: {e}", file.path.display()))?;
    }
    Ok(())
}

/// Two runs of the suite write the same set of files with the same bytes.
fn runs_are_deterministic_to_the_byte() -> Result<(), Failed> {
    let files = suite();
    let a = tempfile::tempdir()?;
    let b = tempfile::tempdir()?;
    run_suite_into(&files, a.path())?;
    run_suite_into(&files, b.path())?;
    let (a, b) = (files_under(a.path()), files_under(b.path()));
    if a.len() < files.len() {
        return Err(format!("{} files for {} scenarios", a.len(), files.len()).into());
    }
    if let Some(name) = a.keys().find(|k| !b.contains_key(*k)) {
        return Err(format!("{} written by the first run only", name.display()).into());
    }
    if let Some(name) = b.keys().find(|k| !a.contains_key(*k)) {
        return Err(format!("{} written by the second run only", name.display()).into());
    }
    for (name, bytes) in &a {
        if b.get(name) != Some(bytes) {
            return Err(format!("{} differs between runs", name.display()).into());
        }
    }
    Ok(())
}

/// Every committed snapshot belongs to a scenario (a renamed or deleted scenario must take
/// its snapshot with it).
fn every_snapshot_has_a_scenario() -> Result<(), Failed> {
    let wanted: Vec<String> = suite()
        .iter()
        .map(|f| format!("{}.snap", snapshot_name(f)))
        .collect();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(SNAPSHOTS);
    let mut orphans = Vec::new();
    for entry in std::fs::read_dir(&dir)?.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(".snap") && !wanted.contains(&name) {
            orphans.push(name);
        }
    }
    if orphans.is_empty() {
        Ok(())
    } else {
        Err(format!("snapshots with no scenario: {}", orphans.join(", ")).into())
    }
}

fn main() {
    let args = Arguments::from_args();
    let files = suite();
    assert!(
        files.len() >= 26,
        "expected the full suite, found {} files",
        files.len()
    );
    let mut trials: Vec<Trial> = files
        .into_iter()
        .map(|file| {
            Trial::test(test_name(&file), move || {
                guarded(|| scenario_passes_and_matches_its_snapshot(&file))
            })
        })
        .collect();
    trials.push(Trial::test(
        "suite::runs_are_deterministic_to_the_byte",
        || guarded(runs_are_deterministic_to_the_byte),
    ));
    trials.push(Trial::test("suite::every_snapshot_has_a_scenario", || {
        guarded(every_snapshot_has_a_scenario)
    }));
    libtest_mimic::run(&args, trials).exit();
}
