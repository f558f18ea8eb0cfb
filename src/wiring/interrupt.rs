//! Stopping a run early: the CLI fires an [`Interrupt`] on SIGINT or SIGTERM; a scenario that
//! is running ends its current step at once and still writes its outputs (so the recordings
//! and reports on disk are complete), and scenarios not started yet are not run.

use tokio::sync::watch;

/// The receiving side: cheap to clone, shared by every scenario of a run. The default never
/// fires.
#[derive(Debug, Clone, Default)]
pub struct Interrupt {
    fired: Option<watch::Receiver<Option<String>>>,
}

/// The sending side, held by whoever watches for signals.
#[derive(Debug)]
pub struct InterruptTrigger {
    fire: watch::Sender<Option<String>>,
}

impl Interrupt {
    /// A new interrupt and the trigger that fires it.
    pub fn new() -> (InterruptTrigger, Self) {
        let (fire, fired) = watch::channel(None);
        (InterruptTrigger { fire }, Self { fired: Some(fired) })
    }

    /// Why the run was interrupted (e.g. `SIGINT`), once it was.
    pub fn reason(&self) -> Option<String> {
        self.fired.as_ref().and_then(|rx| rx.borrow().clone())
    }

    /// Wait until the run is interrupted and say why; never returns for the default.
    pub async fn fired(&self) -> String {
        let Some(mut rx) = self.fired.clone() else {
            return std::future::pending().await;
        };
        let fired = rx
            .wait_for(Option::is_some)
            .await
            .ok()
            .and_then(|reason| reason.clone());
        match fired {
            Some(reason) => reason,
            // The trigger is gone without firing: nobody can interrupt any more.
            None => std::future::pending().await,
        }
    }
}

impl InterruptTrigger {
    /// Interrupt the run; `reason` names the cause (`SIGINT`, `SIGTERM`). Later calls keep the
    /// first reason.
    pub fn fire(&self, reason: &str) {
        self.fire.send_if_modified(|current| {
            if current.is_some() {
                return false;
            }
            *current = Some(reason.to_owned());
            true
        });
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    #[tokio::test]
    async fn a_fired_interrupt_wakes_every_clone_with_the_first_reason() {
        let (trigger, interrupt) = Interrupt::new();
        let other = interrupt.clone();
        assert_eq!(interrupt.reason(), None);
        let waiter = tokio::spawn(async move { other.fired().await });
        tokio::time::sleep(Duration::from_millis(5)).await;
        trigger.fire("SIGTERM");
        trigger.fire("SIGINT");
        assert_eq!(waiter.await.unwrap(), "SIGTERM");
        assert_eq!(interrupt.reason().as_deref(), Some("SIGTERM"));
        assert_eq!(
            interrupt.fired().await,
            "SIGTERM",
            "already fired: returns at once"
        );
    }

    #[tokio::test(start_paused = true)]
    async fn the_default_never_fires() {
        let never = Interrupt::default();
        let waited = tokio::time::timeout(Duration::from_secs(3600), never.fired()).await;
        assert!(waited.is_err());
        assert_eq!(never.reason(), None);
    }
}
