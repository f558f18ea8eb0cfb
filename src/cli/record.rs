//! `armhil record` (being built).

use std::process::ExitCode;

/// Arguments of `armhil record`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("armhil record is not built yet")
}
