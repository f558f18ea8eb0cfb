//! Making the death of an emulator's task observable.
//!
//! An emulator runs on tokio tasks. When one of them panics or gives up (its state file cannot
//! be written), tokio keeps the panic inside the task's `JoinHandle` and nobody awaits that
//! handle until shutdown: the process keeps its port open and serves a dead bus (D4). A task
//! started through the emulator's supervisor publishes how it ended, and whoever holds a
//! [`DeathWatch`] (the `armhil sim` command) learns of it at once.

use std::future::Future;
use std::sync::Arc;

use tokio::sync::watch;
use tokio::task::JoinHandle;

/// Why an emulator stopped serving on its own.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EmulatorDied {
    /// A task panicked (a bug in the emulator).
    #[error("the emulator's {task} task panicked: {message}")]
    Panicked {
        /// Which task.
        task: &'static str,
        /// The panic's message.
        message: String,
    },
    /// A task stopped on an error it cannot serve through (its state file cannot be written).
    #[error("the emulator's {task} task stopped: {message}")]
    Failed {
        /// Which task.
        task: &'static str,
        /// The error.
        message: String,
    },
}

/// A cloneable view of whether an emulator's tasks are alive.
#[derive(Debug, Clone)]
pub struct DeathWatch {
    died: watch::Receiver<Option<EmulatorDied>>,
}

impl DeathWatch {
    /// How the emulator died, if it has.
    pub fn now(&self) -> Option<EmulatorDied> {
        self.died.borrow().clone()
    }

    /// Wait until a task dies and say how (never returns while the emulator runs, nor after a
    /// clean shutdown).
    pub async fn died(&mut self) -> EmulatorDied {
        loop {
            if let Some(died) = self.died.borrow_and_update().clone() {
                return died;
            }
            if self.died.changed().await.is_err() {
                // The emulator is gone without a death: nothing will ever be reported.
                return std::future::pending().await;
            }
        }
    }
}

/// The emulator's side of a [`DeathWatch`]: starts supervised tasks and reports failures.
#[derive(Debug, Clone)]
pub(crate) struct Supervisor {
    died: Arc<watch::Sender<Option<EmulatorDied>>>,
}

/// Aborts the supervised task when the supervising one is aborted or dropped (an emulator
/// handle that aborts its tasks on drop must stop the real work, not just the watcher).
struct AbortOnDrop(Option<JoinHandle<()>>);

impl AbortOnDrop {
    /// The handle, to await rather than abort.
    fn take(mut self) -> Option<JoinHandle<()>> {
        self.0.take()
    }
}

impl Drop for AbortOnDrop {
    fn drop(&mut self) {
        if let Some(task) = &self.0 {
            task.abort();
        }
    }
}

impl Supervisor {
    /// A supervisor and the watch it reports to.
    pub(crate) fn new() -> (Self, DeathWatch) {
        let (tx, rx) = watch::channel(None);
        (Self { died: Arc::new(tx) }, DeathWatch { died: rx })
    }

    /// Record a death; the first one reported is the one kept (later ones are consequences).
    pub(crate) fn report(&self, died: EmulatorDied) {
        self.died.send_if_modified(|slot| {
            if slot.is_none() {
                tracing::error!(%died, "emulator task died");
                *slot = Some(died);
                true
            } else {
                false
            }
        });
    }

    /// Spawn `work` on `runtime` as the task named `task`: a panic or an `Err` it returns is
    /// reported. The handle returned ends when `work` does; aborting it aborts `work`.
    pub(crate) fn spawn<F>(
        &self,
        runtime: &tokio::runtime::Handle,
        task: &'static str,
        work: F,
    ) -> JoinHandle<()>
    where
        F: Future<Output = Result<(), String>> + Send + 'static,
    {
        let (done_tx, done_rx) = tokio::sync::oneshot::channel();
        let inner = runtime.spawn(async move {
            let _ = done_tx.send(work.await);
        });
        let me = self.clone();
        // Made here, not in the task: a task aborted before its first poll drops what it
        // captured, and the guard must be among it.
        let guard = AbortOnDrop(Some(inner));
        runtime.spawn(async move {
            let outcome = done_rx.await;
            match outcome {
                Ok(Ok(())) => {}
                Ok(Err(message)) => me.report(EmulatorDied::Failed { task, message }),
                Err(_) => {
                    // The work ended without sending its outcome: it panicked, or was aborted.
                    let Some(inner) = guard.take() else { return };
                    if let Err(e) = inner.await {
                        if e.is_panic() {
                            me.report(EmulatorDied::Panicked {
                                task,
                                message: panic_text(e.into_panic()),
                            });
                        }
                    }
                }
            }
        })
    }
}

/// A panic payload as text.
fn panic_text(payload: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    #[tokio::test]
    async fn a_panic_and_an_error_are_reported_and_a_clean_end_is_not() {
        let runtime = tokio::runtime::Handle::current();
        let (supervisor, mut watch) = Supervisor::new();
        supervisor
            .spawn(&runtime, "quiet", async { Ok(()) })
            .await
            .unwrap();
        assert_eq!(watch.now(), None);
        let task = supervisor.spawn(&runtime, "core", async {
            let (min, max) = std::hint::black_box((1.0_f64, 0.0_f64));
            // What a min-above-max state file did to the Piper's core (D4).
            let _ = std::hint::black_box(0.5_f64.clamp(min, max));
            Ok(())
        });
        let died = tokio::time::timeout(Duration::from_secs(5), watch.died())
            .await
            .expect("the panic is reported");
        assert!(
            matches!(&died, EmulatorDied::Panicked { task: "core", message } if message.contains("min")),
            "{died:?}"
        );
        task.await.unwrap();

        let (supervisor, mut watch) = Supervisor::new();
        let _task = supervisor.spawn(&runtime, "core", async {
            Err("state file x.json: read-only".into())
        });
        let died = tokio::time::timeout(Duration::from_secs(5), watch.died())
            .await
            .expect("the error is reported");
        assert!(died.to_string().contains("x.json"), "{died}");
    }

    #[tokio::test]
    async fn aborting_the_handle_stops_the_work() {
        let runtime = tokio::runtime::Handle::current();
        let (supervisor, watch) = Supervisor::new();
        let (alive_tx, mut alive) = tokio::sync::mpsc::channel::<()>(1);
        let task = supervisor.spawn(&runtime, "core", async move {
            let _alive = alive_tx;
            std::future::pending::<()>().await;
            Ok(())
        });
        task.abort();
        // The work's sender is dropped only if the work itself was aborted.
        let gone = tokio::time::timeout(Duration::from_secs(5), alive.recv()).await;
        assert_eq!(gone, Ok(None));
        assert_eq!(watch.now(), None, "an abort is not a death");
    }
}
