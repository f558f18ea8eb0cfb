//! Counts every frame on the bus, and keeps them for the candump / pcap writers only when a
//! recording was asked for (a long scenario would otherwise hold every frame in memory).

use std::collections::BTreeMap;
use std::sync::Arc;

use bus::{CanBus, ReceivedFrame};
use tokio::sync::{broadcast, oneshot};
use tokio::task::JoinHandle;

/// What a recorder saw: counts always, the frames themselves only when kept.
#[derive(Debug, Default)]
pub(crate) struct Capture {
    /// Whether frames are kept (a candump or pcap recording was asked for).
    keep: bool,
    /// The frames, when kept.
    pub frames: Vec<ReceivedFrame>,
    /// Frames seen.
    pub count: u64,
    /// Frames seen per CAN ID.
    pub by_id: BTreeMap<u32, u64>,
}

impl Capture {
    fn new(keep: bool) -> Self {
        Self {
            keep,
            ..Self::default()
        }
    }

    fn push(&mut self, frame: ReceivedFrame) {
        self.count += 1;
        *self.by_id.entry(frame.frame.raw_id()).or_insert(0) += 1;
        if self.keep {
            self.frames.push(frame);
        }
    }
}

/// A running recorder.
pub(crate) struct Recorder {
    stop: Option<oneshot::Sender<()>>,
    task: JoinHandle<(Capture, u64)>,
}

impl Recorder {
    /// Record from a virtual bus tap (every frame that completed on the wire); `keep`: hold
    /// the frames, not just their counts.
    pub fn from_tap(mut tap: broadcast::Receiver<ReceivedFrame>, keep: bool) -> Self {
        let (stop, mut stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let mut frames = Capture::new(keep);
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
    pub fn from_bus(bus: Arc<dyn CanBus>, keep: bool) -> Self {
        let (stop, mut stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let mut frames = Capture::new(keep);
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

    /// Stop and return what was captured and how many frames the tap missed.
    pub async fn finish(mut self) -> (Capture, u64) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        self.task.await.unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use bus::CanFrame;

    use super::*;

    async fn capture(keep: bool) -> Capture {
        let (tx, rx) = broadcast::channel(4096);
        let recorder = Recorder::from_tap(rx, keep);
        for i in 0..1000u16 {
            let frame = CanFrame::standard(0x100 + i % 3, &[]).unwrap();
            tx.send(ReceivedFrame {
                frame,
                timestamp: Duration::from_millis(u64::from(i)),
            })
            .unwrap();
        }
        let (capture, missed) = recorder.finish().await;
        assert_eq!(missed, 0);
        capture
    }

    #[tokio::test]
    async fn frames_are_held_only_when_a_recording_is_asked_for() {
        let counted = capture(false).await;
        assert_eq!(counted.count, 1000);
        assert_eq!(counted.by_id.get(&0x100), Some(&334));
        assert_eq!(counted.frames.len(), 0, "frames held with recordings off");
        let kept = capture(true).await;
        assert_eq!(kept.count, 1000);
        assert_eq!(kept.frames.len(), 1000);
    }
}
