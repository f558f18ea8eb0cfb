//! `armhil sim robstride` (being built).

use std::process::ExitCode;

/// Arguments of `armhil sim robstride`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run the emulator.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("armhil sim robstride is not built yet")
}
