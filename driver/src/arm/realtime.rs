//! Realtime state delivery: a broadcast of [`ArmRealtimeState`] fed by each backend at the
//! arm's rate, subscriptions on it, and the API's callback form on top.

use std::sync::{Arc, Mutex};

use tokio::sync::broadcast;
use tokio::task::JoinHandle;

use super::error::{AbcErrorCode, ArmError, ArmResult};
use super::types::ArmRealtimeState;

/// How many samples a slow subscriber may fall behind before it loses the oldest.
const BACKLOG: usize = 512;

/// A callback that receives every realtime state.
pub type RealtimeCallback = Box<dyn Fn(ArmRealtimeState) + Send + Sync + 'static>;

/// One subscriber's stream of realtime states.
pub struct RealtimeSubscription {
    rx: broadcast::Receiver<Arc<ArmRealtimeState>>,
    missed: u64,
}

impl RealtimeSubscription {
    /// The next state. A subscriber that fell behind skips to the oldest state still held
    /// (counted in [`Self::missed`]); `ARM_DATA_RECEIVE_FAILED` once the arm is gone.
    pub async fn recv(&mut self) -> ArmResult<Arc<ArmRealtimeState>> {
        loop {
            match self.rx.recv().await {
                Ok(s) => return Ok(s),
                Err(broadcast::error::RecvError::Lagged(n)) => self.missed += n,
                Err(broadcast::error::RecvError::Closed) => {
                    return Err(ArmError::new(
                        AbcErrorCode::ArmDataReceiveFailed,
                        "the realtime state stream ended",
                    ))
                }
            }
        }
    }

    /// A state already received, if any, without waiting.
    pub fn try_recv(&mut self) -> Option<Arc<ArmRealtimeState>> {
        loop {
            match self.rx.try_recv() {
                Ok(s) => return Some(s),
                Err(broadcast::error::TryRecvError::Lagged(n)) => self.missed += n,
                Err(_) => return None,
            }
        }
    }

    /// States skipped because this subscriber fell behind.
    pub fn missed(&self) -> u64 {
        self.missed
    }
}

/// The publishing side each backend owns: the broadcast and the registered callback.
pub struct RealtimeHub {
    tx: broadcast::Sender<Arc<ArmRealtimeState>>,
    callback: Mutex<Option<JoinHandle<()>>>,
}

impl Default for RealtimeHub {
    fn default() -> Self {
        Self {
            tx: broadcast::channel(BACKLOG).0,
            callback: Mutex::new(None),
        }
    }
}

impl Drop for RealtimeHub {
    fn drop(&mut self) {
        if let Some(h) = self.callback.get_mut().ok().and_then(Option::take) {
            h.abort();
        }
    }
}

impl RealtimeHub {
    /// Publishes one state to every subscriber.
    pub fn publish(&self, state: ArmRealtimeState) {
        // No subscriber is not an error: states are simply not kept.
        let _ = self.tx.send(Arc::new(state));
    }

    /// A new subscription (states published from now on).
    pub fn subscribe(&self) -> RealtimeSubscription {
        RealtimeSubscription {
            rx: self.tx.subscribe(),
            missed: 0,
        }
    }

    /// Registers `callback` for every state from now on, replacing any earlier one (the API
    /// keeps one callback per arm). The callback runs on a task of the current tokio runtime;
    /// outside a runtime this is `INVALID_STATE`.
    pub fn set_callback(&self, callback: RealtimeCallback) -> ArmResult<()> {
        let runtime = tokio::runtime::Handle::try_current()
            .map_err(|e| ArmError::caused_by(AbcErrorCode::InvalidState, e))?;
        let mut sub = self.subscribe();
        let task = runtime.spawn(async move {
            while let Ok(state) = sub.recv().await {
                callback(ArmRealtimeState::clone(&state));
            }
        });
        let old = self
            .callback
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .replace(task);
        if let Some(h) = old {
            h.abort();
        }
        Ok(())
    }

    /// Removes the callback, if any.
    pub fn clear_callback(&self) {
        if let Some(h) = self
            .callback
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take()
        {
            h.abort();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::types::{ArmCurrentStatus, ArmForceSensor, JointState, Pose};
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn state(n: f64) -> ArmRealtimeState {
        ArmRealtimeState {
            name: "a".into(),
            timestamp: std::time::SystemTime::UNIX_EPOCH,
            since_connect: std::time::Duration::ZERO,
            joint_status: JointState {
                joint_position: vec![n],
                ..JointState::default()
            },
            force_sensor: ArmForceSensor::default(),
            arm_current_status: ArmCurrentStatus::Idle,
            gripper_state: None,
            ee_pose: Pose::default(),
        }
    }

    #[tokio::test]
    async fn subscribers_and_the_callback_see_every_state_in_order() {
        let hub = RealtimeHub::default();
        let mut sub = hub.subscribe();
        let seen = Arc::new(AtomicUsize::new(0));
        let s2 = seen.clone();
        hub.set_callback(Box::new(move |st| {
            assert_eq!(
                st.joint_status.joint_position[0] as usize,
                s2.load(Ordering::SeqCst)
            );
            s2.fetch_add(1, Ordering::SeqCst);
        }))
        .unwrap();
        for i in 0..10 {
            hub.publish(state(i as f64));
        }
        for i in 0..10 {
            assert_eq!(
                sub.recv().await.unwrap().joint_status.joint_position[0],
                i as f64
            );
        }
        for _ in 0..100 {
            if seen.load(Ordering::SeqCst) == 10 {
                break;
            }
            tokio::task::yield_now().await;
        }
        assert_eq!(seen.load(Ordering::SeqCst), 10);
        hub.clear_callback();
        hub.publish(state(10.0));
        tokio::task::yield_now().await;
        assert_eq!(seen.load(Ordering::SeqCst), 10);
    }

    #[test]
    fn a_callback_needs_a_runtime() {
        let hub = RealtimeHub::default();
        let e = hub.set_callback(Box::new(|_| {})).unwrap_err();
        assert_eq!(e.code, AbcErrorCode::InvalidState);
    }

    #[tokio::test]
    async fn a_lagging_subscriber_counts_what_it_missed() {
        let hub = RealtimeHub::default();
        let mut sub = hub.subscribe();
        for i in 0..(BACKLOG + 5) {
            hub.publish(state(i as f64));
        }
        let first = sub.recv().await.unwrap();
        assert_eq!(first.joint_status.joint_position[0], 5.0);
        assert_eq!(sub.missed(), 5);
    }
}
