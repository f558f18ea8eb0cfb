//! `armhil replay`: send a candump log onto a SocketCAN interface with its original timing.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use bus::candump::LogEntry;
use bus::CanFrame;

/// Arguments of `armhil replay`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// candump `-L` log to replay (blank lines and `#` comments are skipped).
    pub log: PathBuf,
    /// CAN interface to send on, e.g. `vcan0`.
    #[arg(long)]
    pub iface: String,
    /// Start over at the end until interrupted.
    #[arg(long = "loop")]
    pub repeat: bool,
    /// Time scale: 2 plays twice as fast, 0.5 at half speed.
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
}

/// The longest send offset a replay accepts: a year. Longer ones come from a broken log or an
/// absurd `--speed`, and would overflow the clock arithmetic.
pub const MAX_OFFSET: Duration = Duration::from_secs(365 * 24 * 3600);

/// Frames with their send offset from the start of the replay: the log's gaps divided by
/// `speed`. Timestamps that go backwards are sent without a gap. An offset past
/// [`MAX_OFFSET`] (a huge timestamp gap, a tiny `speed`) is an error naming both.
pub fn schedule(entries: &[LogEntry], speed: f64) -> anyhow::Result<Vec<(Duration, CanFrame)>> {
    let Some(first) = entries.first() else {
        return Ok(Vec::new());
    };
    entries
        .iter()
        .enumerate()
        .map(|(index, entry)| {
            let gap = entry.timestamp.saturating_sub(first.timestamp);
            let offset = Duration::try_from_secs_f64(gap.as_secs_f64() / speed)
                .ok()
                .filter(|offset| *offset <= MAX_OFFSET);
            let Some(offset) = offset else {
                anyhow::bail!(
                    "frame {} comes {:.3} s after the first; at --speed {speed:?} that is more \
                     than a year of replay",
                    index + 1,
                    gap.as_secs_f64()
                );
            };
            Ok((offset, entry.frame))
        })
        .collect()
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(
        args.speed.is_finite() && args.speed > 0.0,
        "--speed must be a positive number, got {}",
        args.speed
    );
    imp::run(args)
}

#[cfg(not(target_os = "linux"))]
mod imp {
    use super::*;

    pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
        anyhow::bail!("armhil replay needs SocketCAN, which only exists on Linux")
    }
}

#[cfg(target_os = "linux")]
mod imp {
    use anyhow::Context as _;
    use bus::socketcan_bus::SocketCanBus;
    use bus::{BusError, CanBus};
    use tokio::time::Instant;

    use super::*;

    /// How long a full transmit queue may keep one frame waiting before the replay gives up.
    const QUEUE_FULL_PATIENCE: Duration = Duration::from_secs(1);

    pub fn run(args: Args) -> anyhow::Result<ExitCode> {
        let entries = bus::candump::read_log(&args.log)
            .with_context(|| format!("cannot read {}", args.log.display()))?;
        let plan = schedule(&entries, args.speed)?;
        anyhow::ensure!(!plan.is_empty(), "{} holds no frames", args.log.display());
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .context("cannot start the async runtime")?;
        runtime.block_on(async {
            // The bus crate's error names the interface and says what to do. A log with CAN FD
            // frames needs a CAN FD socket (and an interface of MTU 72, which the send's error
            // explains otherwise).
            let fd = plan.iter().any(|(_, frame)| frame.is_fd());
            let options = bus::socketcan_bus::SocketCanOptions {
                fd,
                ..Default::default()
            };
            let bus = SocketCanBus::open_with(&args.iface, options)?;
            tokio::select! {
                result = replay(&bus, &plan, &args) => result,
                signal = tokio::signal::ctrl_c() => {
                    signal.context("cannot listen for Ctrl-C")?;
                    tracing::info!("interrupted");
                    Ok(ExitCode::SUCCESS)
                }
            }
        })
    }

    async fn replay(
        bus: &SocketCanBus,
        plan: &[(Duration, CanFrame)],
        args: &Args,
    ) -> anyhow::Result<ExitCode> {
        let mut pass = 0u64;
        loop {
            pass += 1;
            tracing::info!(pass, frames = plan.len(), iface = %args.iface, speed = args.speed, "replaying");
            let start = Instant::now();
            for (offset, frame) in plan {
                // schedule() bounds the offsets, but a clock near its end could still overflow.
                let due = start
                    .checked_add(*offset)
                    .context("the replay's send times overflow the clock")?;
                tokio::time::sleep_until(due).await;
                send_patiently(bus, *frame).await?;
            }
            if !args.repeat {
                tracing::info!(frames = plan.len(), "replay finished");
                return Ok(ExitCode::SUCCESS);
            }
        }
    }

    /// Send, retrying while the interface's queue is full (a replay should not lose frames
    /// to a momentarily busy bus).
    async fn send_patiently(bus: &SocketCanBus, frame: CanFrame) -> anyhow::Result<()> {
        let deadline = Instant::now() + QUEUE_FULL_PATIENCE;
        loop {
            match bus.send(frame).await {
                Ok(()) => return Ok(()),
                Err(BusError::TxQueueFull { .. }) if Instant::now() < deadline => {
                    tokio::time::sleep(Duration::from_millis(1)).await;
                }
                Err(error) => {
                    return Err(anyhow::Error::new(error).context(format!("cannot send {frame}")))
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(micros: u64, id: u16) -> LogEntry {
        LogEntry {
            timestamp: Duration::from_micros(micros),
            iface: "vcan0".into(),
            frame: CanFrame::standard(id, &[]).unwrap(),
        }
    }

    #[test]
    fn schedule_keeps_gaps_scaled_by_speed() {
        let entries = [
            entry(1_000_000, 1),
            entry(1_010_000, 2),
            entry(1_030_000, 3),
        ];
        let at = |plan: Vec<(Duration, CanFrame)>| -> Vec<u128> {
            plan.iter().map(|(offset, _)| offset.as_micros()).collect()
        };
        assert_eq!(
            at(schedule(&entries, 1.0).unwrap()),
            vec![0, 10_000, 30_000]
        );
        assert_eq!(at(schedule(&entries, 2.0).unwrap()), vec![0, 5_000, 15_000]);
        assert_eq!(
            at(schedule(&entries, 0.5).unwrap()),
            vec![0, 20_000, 60_000]
        );
        assert!(schedule(&[], 1.0).unwrap().is_empty());
    }

    #[test]
    fn backwards_timestamps_do_not_wrap() {
        let plan = schedule(&[entry(5_000, 1), entry(4_000, 2)], 1.0).unwrap();
        assert_eq!(plan[1].0, Duration::ZERO);
    }

    #[test]
    fn absurd_speed_or_gap_is_an_error_not_a_panic() {
        let entries = [entry(0, 1), entry(1_000_000, 2)];
        let error = schedule(&entries, 1e-300).unwrap_err().to_string();
        assert!(error.contains("--speed 1e-300"), "{error}");
        assert!(error.contains("frame 2"), "{error}");
        let huge = [entry(0, 1), entry(u64::MAX, 2)];
        assert!(schedule(&huge, 1.0).is_err());
        // Just over a year is refused, just under is kept.
        let year_us = MAX_OFFSET.as_micros() as u64;
        assert!(schedule(&[entry(0, 1), entry(year_us + 1_000_000, 2)], 1.0).is_err());
        assert!(schedule(&[entry(0, 1), entry(year_us - 1_000_000, 2)], 1.0).is_ok());
    }
}
