//! `armhil record`: write everything seen on a SocketCAN interface or a socketcand server to a
//! candump log or pcap.

use std::path::PathBuf;
use std::process::ExitCode;

use super::bus_args::BusArgs;

/// Arguments of `armhil record`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The bus to record (one of `--iface`, `--socketcand`).
    #[command(flatten)]
    pub bus: BusArgs,
    /// Output file: `.pcap` writes pcap (Wireshark), anything else a candump `-L` log.
    #[arg(short = 'o', long)]
    pub output: PathBuf,
    /// Stop after this many seconds instead of waiting for Ctrl-C.
    #[arg(long, value_name = "SECS")]
    pub duration: Option<f64>,
}

/// The longest `--duration` accepted: a year (longer would overflow the clock arithmetic).
pub const MAX_DURATION: std::time::Duration = std::time::Duration::from_secs(365 * 24 * 3600);

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let duration = args.duration.map(parse_duration).transpose()?;
    imp::run(args, duration)
}

/// `--duration SECS` as a [`std::time::Duration`]: finite, not negative, at most
/// [`MAX_DURATION`].
pub fn parse_duration(secs: f64) -> anyhow::Result<std::time::Duration> {
    std::time::Duration::try_from_secs_f64(secs)
        .ok()
        .filter(|duration| *duration <= MAX_DURATION)
        .ok_or_else(|| {
            anyhow::anyhow!(
                "--duration must be between 0 and {} seconds (a year), got {secs}",
                MAX_DURATION.as_secs()
            )
        })
}

mod imp {
    use std::time::Duration;

    use anyhow::Context as _;
    use bus::recorder::Recorder;
    use bus::BusError;

    use super::*;

    pub fn run(args: Args, duration: Option<Duration>) -> anyhow::Result<ExitCode> {
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .context("cannot start the async runtime")?;
        runtime.block_on(record(args, duration))
    }

    async fn record(args: Args, duration: Option<Duration>) -> anyhow::Result<ExitCode> {
        let Some(link) = args.bus.link() else {
            anyhow::bail!("give the bus to record: --iface IF or --socketcand HOST:PORT");
        };
        // The output first: a bad path is reported before any bus is touched.
        let mut recorder = Recorder::create(&args.output, link.channel())
            .with_context(|| format!("cannot create {}", args.output.display()))?;
        let bus = link.open_fd("recorder").await.map_err(anyhow::Error::msg)?;
        tracing::info!(on = %bus.name(), output = %args.output.display(), "recording; Ctrl-C stops");
        let stop_after = async {
            match duration {
                Some(duration) => tokio::time::sleep(duration).await,
                None => std::future::pending().await,
            }
        };
        tokio::pin!(stop_after);
        let mut signals = super::super::signals::StopSignals::listen()?;
        // Flush now and then so a killed process leaves at most a second unwritten.
        let mut flush = tokio::time::interval(Duration::from_secs(1));
        let outcome = loop {
            tokio::select! {
                signal = signals.next() => {
                    tracing::info!(signal, "stopping");
                    break Ok(());
                }
                () = &mut stop_after => break Ok(()),
                _ = flush.tick() => {
                    if let Err(error) = recorder.flush() {
                        break Err(anyhow::Error::new(error).context("cannot write the recording"));
                    }
                }
                received = bus.recv() => match received {
                    Ok(frame) => {
                        if let Err(error) = recorder.write(&frame) {
                            break Err(anyhow::Error::new(error).context("cannot write the recording"));
                        }
                    }
                    Err(BusError::BusOff) => tracing::warn!(on = %bus.name(), "bus-off reported; still recording"),
                    Err(error) => break Err(anyhow::Error::new(error).context("reading the bus failed")),
                },
            }
        };
        // Finish the file whatever stopped us, so it is complete.
        let frames = recorder
            .finish()
            .with_context(|| format!("cannot finish {}", args.output.display()))?;
        tracing::info!(frames, output = %args.output.display(), "recording finished");
        outcome.map(|()| ExitCode::SUCCESS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_durations_are_errors_naming_the_option() {
        for secs in [1e300, -1.0, f64::NAN, f64::INFINITY, 4e7] {
            let error = parse_duration(secs).unwrap_err().to_string();
            assert!(error.contains("--duration"), "{error}");
        }
        assert_eq!(parse_duration(2.5).unwrap().as_millis(), 2500);
        assert!(parse_duration(0.0).unwrap().is_zero());
    }
}
