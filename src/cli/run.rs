//! `armhil run` (being built).

use std::process::ExitCode;

/// Arguments of `armhil run`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("armhil run is not built yet")
}
