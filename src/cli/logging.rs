//! `tracing` setup shared by every subcommand.

use tracing_subscriber::EnvFilter;

/// Log to stderr at `base_level` (`info` for long-running tools, `warn` where the command
/// prints its own report), `debug` with `-v`, `trace` with `-vv`; `RUST_LOG` wins when set.
pub fn init(verbosity: u8, base_level: &str) {
    let default_level = match verbosity {
        0 => base_level,
        1 => "debug",
        _ => "trace",
    };
    let filter =
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default_level));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}
