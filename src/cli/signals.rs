//! SIGINT (Ctrl-C) and SIGTERM as one stream of stop requests, so every long-running
//! subcommand stops the same way and finishes its files whichever signal arrives.

use anyhow::Context;

/// Stop requests from the operating system. Create it once, before the work starts: a
/// signal is only seen by listeners that exist when it arrives.
pub struct StopSignals {
    #[cfg(unix)]
    interrupt: tokio::signal::unix::Signal,
    #[cfg(unix)]
    terminate: tokio::signal::unix::Signal,
}

impl StopSignals {
    /// Start listening (needs a tokio runtime with its I/O driver).
    pub fn listen() -> anyhow::Result<Self> {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{signal, SignalKind};
            Ok(Self {
                interrupt: signal(SignalKind::interrupt()).context("cannot watch SIGINT")?,
                terminate: signal(SignalKind::terminate()).context("cannot watch SIGTERM")?,
            })
        }
        #[cfg(not(unix))]
        {
            Ok(Self {})
        }
    }

    /// Wait for the next stop request and name it (`SIGINT`, `SIGTERM`).
    pub async fn next(&mut self) -> &'static str {
        #[cfg(unix)]
        {
            tokio::select! {
                _ = self.interrupt.recv() => "SIGINT",
                _ = self.terminate.recv() => "SIGTERM",
            }
        }
        #[cfg(not(unix))]
        {
            match tokio::signal::ctrl_c().await {
                Ok(()) => "Ctrl-C",
                Err(_) => std::future::pending().await,
            }
        }
    }
}

/// Watch for stop requests on a thread of its own and fire `trigger` at the first one; a
/// second request ends the process at once (exit 130) for a user who does not want to wait
/// for the outputs to be written. `process::exit` runs no destructors, so the files that are
/// only temporary are deleted first ([`remove_unfinished_files`]): no half-written output
/// and no spool file stays behind (D18).
pub fn interrupt_on_signals(trigger: armhil::harness::InterruptTrigger) -> anyhow::Result<()> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the signal watcher")?;
    let mut signals = runtime.block_on(async { StopSignals::listen() })?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            runtime.block_on(async move {
                let first = signals.next().await;
                eprintln!("{first}: stopping after writing the outputs of the running scenarios (again to quit at once)");
                trigger.fire(first);
                let second = signals.next().await;
                eprintln!("{second}: quitting without waiting");
                remove_unfinished_files();
                std::process::exit(130);
            });
        })
        .context("cannot start the signal watcher")?;
    Ok(())
}

/// Delete the temporary files of a run that is being abandoned: the bus-recording spool files
/// (in the temporary folder) and the outputs being written at this moment, which exist under
/// a hidden temporary name (`.bus.log.tmp<pid>`) until they are complete and renamed. Both
/// are listed by the code that creates them, so this works on every platform.
fn remove_unfinished_files() {
    let spooled = armhil::harness::Recording::remove_spool_files_before_exit();
    let unfinished = armhil::harness::report::remove_unfinished_outputs_before_exit();
    tracing::debug!(
        spooled,
        unfinished,
        "temporary files removed on the way out"
    );
}
