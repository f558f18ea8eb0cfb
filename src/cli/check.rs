//! `armhil check`: validate scenario files without running them.

use std::path::PathBuf;
use std::process::ExitCode;

use armhil::harness::{discover_suite, SuiteLoader};

/// Arguments of `armhil check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario files or folders (searched recursively for *.yaml / *.yml).
    #[arg(required = true)]
    paths: Vec<PathBuf>,
}

/// Validate every file; exit 1 if any is invalid.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    // Suite entries: a file with a `matrix:` is checked once per value.
    let files = discover_suite(&args.paths)?;
    if files.is_empty() {
        anyhow::bail!("no scenario files (*.yaml, *.yml) found");
    }
    let mut invalid = 0usize;
    // Parses each file once, however many matrix variants it has.
    let mut loader = SuiteLoader::new();
    for file in &files {
        match loader.load(file) {
            Ok(s) => println!(
                "ok    {} ({}: {} steps, {} scheduled faults{})",
                file.path.display(),
                s.name,
                s.steps.len(),
                s.faults.len(),
                if s.has_tag("vcan") { ", vcan" } else { "" }
            ),
            Err(e) => {
                invalid += 1;
                println!("error {e}");
            }
        }
    }
    println!("{} file(s) checked, {invalid} invalid", files.len());
    Ok(if invalid == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
