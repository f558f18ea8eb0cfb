//! What every `armhil sim` subcommand is: an emulator kind served alone (`armhil sim KIND`)
//! or as one device of a rig (`armhil sim rig FILE`). A kind implements [`ServedKind`] in
//! its own file here and is registered by one line in [`served_kinds!`](super::served_kinds);
//! the subcommand, its entry in rig files and the rig's dispatch come from that line.

use std::future::Future;
use std::path::PathBuf;
use std::pin::Pin;
use std::process::ExitCode;

use armhil::rigs::{RigDevice, SimKind};
use clap::Parser;

use super::StopSource;

/// One emulator kind as `armhil sim` serves it.
pub(crate) trait ServedKind: 'static {
    /// The subcommand, and a rig entry's `kind:`.
    const NAME: &'static str;
    /// Option keys a rig entry gives as positional arguments (`file:` of a robot).
    const POSITIONAL_KEYS: &'static [&'static str] = &[];
    /// The options (without dashes, `_` between words) whose value is a file the device
    /// writes: a rig refuses two devices that would write one file. Every path option is
    /// one of these or an input (a test in `mod.rs` holds each kind to it).
    const OUTPUT_KEYS: &'static [&'static str];
    /// Its command-line options.
    type Args: clap::Args + Send + std::fmt::Debug + 'static;

    /// The options that name files (a rig resolves them against its file's folder).
    fn paths_mut(args: &mut Self::Args) -> Vec<&mut PathBuf>;

    /// Serve until `stop` asks (a signal, or the rig this device is part of stopping).
    fn serve(
        args: Self::Args,
        stop: StopSource,
    ) -> impl Future<Output = anyhow::Result<ExitCode>> + Send;
}

/// The kind as a rig file names it.
pub(crate) const fn sim_kind<K: ServedKind>() -> SimKind {
    SimKind {
        name: K::NAME,
        positional_keys: K::POSITIONAL_KEYS,
        output_keys: K::OUTPUT_KEYS,
    }
}

/// `armhil sim KIND` alone: serve until Ctrl-C or SIGTERM.
pub(crate) fn run_alone<K: ServedKind>(args: K::Args) -> anyhow::Result<ExitCode> {
    super::real_time_runtime()?.block_on(async { K::serve(args, StopSource::signals()?).await })
}

/// One device of a rig, its options parsed by its kind's own parser.
pub(crate) trait RigEntry: Send {
    /// The options that name files.
    fn paths_mut(&mut self) -> Vec<&mut PathBuf>;
    /// Serve until the rig stops.
    fn serve(
        self: Box<Self>,
        stop: StopSource,
    ) -> Pin<Box<dyn Future<Output = anyhow::Result<ExitCode>> + Send>>;
}

struct Parsed<K: ServedKind>(K::Args);

impl<K: ServedKind> RigEntry for Parsed<K> {
    fn paths_mut(&mut self) -> Vec<&mut PathBuf> {
        K::paths_mut(&mut self.0)
    }

    fn serve(
        self: Box<Self>,
        stop: StopSource,
    ) -> Pin<Box<dyn Future<Output = anyhow::Result<ExitCode>> + Send>> {
        Box::pin(K::serve(self.0, stop))
    }
}

/// `armhil sim KIND` alone: what a rig entry's options are parsed with, so they take what
/// the command line takes and fail with its messages.
#[derive(Debug, Parser)]
#[command(no_binary_name = true, disable_help_flag = true)]
struct Entry<T: clap::Args> {
    #[command(flatten)]
    args: T,
}

/// How a rig device's options are parsed: by its kind's own parser ([`parse_entry`]).
pub(crate) type EntryParser = fn(&RigDevice) -> Result<Box<dyn RigEntry>, clap::Error>;

/// Parse a rig device's options with its kind's parser; clap's message, on failure.
pub(crate) fn parse_entry<K: ServedKind>(
    device: &RigDevice,
) -> Result<Box<dyn RigEntry>, clap::Error> {
    let entry = Entry::<K::Args>::try_parse_from(&device.args)?;
    Ok(Box::new(Parsed::<K>(entry.args)))
}
