//! `armhil check` (being built).

use std::process::ExitCode;

/// Arguments of `armhil check`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("armhil check is not built yet")
}
