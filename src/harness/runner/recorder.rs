//! Collects every frame on the bus for the candump / pcap writers.

use std::sync::Arc;

use bus::{CanBus, ReceivedFrame};
use tokio::sync::{broadcast, oneshot};
use tokio::task::JoinHandle;

/// A running recorder.
pub(crate) struct Recorder {
    stop: Option<oneshot::Sender<()>>,
    task: JoinHandle<(Vec<ReceivedFrame>, u64)>,
}

impl Recorder {
    /// Record from a virtual bus tap (every frame that completed on the wire).
    pub fn from_tap(mut tap: broadcast::Receiver<ReceivedFrame>) -> Self {
        let (stop, mut stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let mut frames = Vec::new();
            let mut missed = 0u64;
            loop {
                tokio::select! {
                    biased;
                    received = tap.recv() => match received {
                        Ok(frame) => frames.push(frame),
                        Err(broadcast::error::RecvError::Lagged(n)) => missed += n,
                        Err(broadcast::error::RecvError::Closed) => break,
                    },
                    _ = &mut stopped => {
                        // Drain what is already in the tap, then stop.
                        loop {
                            match tap.try_recv() {
                                Ok(frame) => frames.push(frame),
                                Err(broadcast::error::TryRecvError::Lagged(n)) => missed += n,
                                Err(_) => break,
                            }
                        }
                        break;
                    }
                }
            }
            (frames, missed)
        });
        Self {
            stop: Some(stop),
            task,
        }
    }

    /// Record from a bus endpoint that receives every frame (a second SocketCAN socket).
    pub fn from_bus(bus: Arc<dyn CanBus>) -> Self {
        let (stop, mut stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let mut frames = Vec::new();
            loop {
                tokio::select! {
                    biased;
                    _ = &mut stopped => break,
                    received = bus.recv() => match received {
                        Ok(frame) => frames.push(frame),
                        Err(_) => break,
                    },
                }
            }
            bus.close().await;
            (frames, 0)
        });
        Self {
            stop: Some(stop),
            task,
        }
    }

    /// Stop and return the frames and how many the tap missed.
    pub async fn finish(mut self) -> (Vec<ReceivedFrame>, u64) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        self.task.await.unwrap_or_default()
    }
}
