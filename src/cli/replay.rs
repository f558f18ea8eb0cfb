//! `armhil replay` (being built).

use std::process::ExitCode;

/// Arguments of `armhil replay`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("armhil replay is not built yet")
}
