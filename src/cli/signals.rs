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
/// a hidden temporary name (`.bus.log.tmp<pid>`) until they are complete and renamed.
fn remove_unfinished_files() {
    let spooled = armhil::harness::Recording::remove_spool_files();
    let unfinished = remove_open_temporaries(std::path::Path::new("/"));
    tracing::debug!(
        spooled,
        unfinished,
        "temporary files removed on the way out"
    );
}

/// Delete the files this process holds open under an atomic write's temporary name
/// (`.<name>.tmp<pid>`, see `harness::report::write_atomic`): an output being written when the
/// process quits. Such a file is open from its creation until it is renamed over its final
/// name, so the open descriptors name exactly the ones that would be left behind. Linux only
/// (it reads `/proc/self/fd`); elsewhere nothing is removed. Only files under `under` are
/// considered. Returns how many were deleted.
fn remove_open_temporaries(under: &std::path::Path) -> usize {
    #[cfg(target_os = "linux")]
    {
        let suffix = format!(".tmp{}", std::process::id());
        let Ok(fds) = std::fs::read_dir("/proc/self/fd") else {
            return 0;
        };
        fds.filter_map(|fd| std::fs::read_link(fd.ok()?.path()).ok())
            .filter(|path| {
                path.starts_with(under)
                    && path
                        .file_name()
                        .and_then(|name| name.to_str())
                        .is_some_and(|name| name.starts_with('.') && name.ends_with(&suffix))
            })
            .filter(|path| std::fs::remove_file(path).is_ok())
            .count()
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = under;
        0
    }
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    #[test]
    fn an_output_being_written_is_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let pid = std::process::id();
        let writing = dir.path().join(format!(".bus.log.tmp{pid}"));
        let other_process = dir
            .path()
            .join(format!(".bus.log.tmp{}", pid.wrapping_add(1)));
        let finished = dir.path().join("bus.log");
        let _open = std::fs::File::create(&writing).unwrap();
        let _other = std::fs::File::create(&other_process).unwrap();
        let _finished = std::fs::File::create(&finished).unwrap();
        // Within this test's folder: other tests of this binary may be writing outputs.
        let under = dir.path().canonicalize().unwrap();
        assert_eq!(super::remove_open_temporaries(&under), 1);
        assert!(!writing.exists(), "the unfinished output is left behind");
        assert!(other_process.exists(), "another process's file was removed");
        assert!(finished.exists(), "a finished output was removed");
    }
}
