//! `armhil sim piper` (being built).

use std::process::ExitCode;

/// Arguments of `armhil sim piper`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run the emulator.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("armhil sim piper is not built yet")
}
