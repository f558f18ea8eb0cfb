//! Counts every frame on the bus and, when a recording was asked for, writes it to the
//! candump / pcap spool files as it arrives (never holding frames in memory: a long scenario
//! would otherwise grow without bound).

use std::collections::BTreeMap;
use std::sync::Arc;

use bus::{CanBus, ReceivedFrame};
use tokio::sync::{broadcast, oneshot};
use tokio::task::JoinHandle;

use super::spool::{Recording, Spool};

/// What a recorder saw: counts always, the frames themselves in the spool files when a
/// recording was asked for.
#[derive(Default)]
pub(crate) struct Capture {
    /// Where frames are written, when recorded.
    spool: Option<Spool>,
    /// The finished recording (set by [`Recorder::finish`]).
    pub recording: Recording,
    /// Frames seen.
    pub count: u64,
    /// Frames seen per CAN ID.
    pub by_id: BTreeMap<u32, u64>,
}

impl Capture {
    fn new(spool: Spool) -> Self {
        Self {
            spool: spool.is_recording().then_some(spool),
            ..Self::default()
        }
    }

    fn push(&mut self, frame: ReceivedFrame) {
        self.count += 1;
        *self.by_id.entry(frame.frame.raw_id()).or_insert(0) += 1;
        if let Some(spool) = &mut self.spool {
            spool.write(&frame);
        }
    }

    /// Close the spool files and keep the finished recording.
    fn close(mut self) -> Self {
        if let Some(spool) = self.spool.take() {
            self.recording = spool.finish();
        }
        self
    }
}

/// A running recorder.
pub(crate) struct Recorder {
    stop: Option<oneshot::Sender<()>>,
    task: JoinHandle<(Capture, u64)>,
}

impl Recorder {
    /// Record from a virtual bus tap (every frame that completed on the wire) into `spool`.
    pub fn from_tap(mut tap: broadcast::Receiver<ReceivedFrame>, spool: Spool) -> Self {
        let (stop, mut stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let mut frames = Capture::new(spool);
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
            (frames.close(), missed)
        });
        Self {
            stop: Some(stop),
            task,
        }
    }

    /// Record from a bus endpoint that receives every frame (a second SocketCAN socket) into
    /// `spool`.
    pub fn from_bus(bus: Arc<dyn CanBus>, spool: Spool) -> Self {
        let (stop, mut stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let mut frames = Capture::new(spool);
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
            (frames.close(), 0)
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
        let recorder = Recorder::from_tap(rx, Spool::create(keep, false, u64::MAX).unwrap());
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
    async fn frames_are_written_only_when_a_recording_is_asked_for() {
        let counted = capture(false).await;
        assert_eq!(counted.count, 1000);
        assert_eq!(counted.by_id.get(&0x100), Some(&334));
        assert!(
            counted.recording.candump.is_none(),
            "recorded with recordings off"
        );
        let kept = capture(true).await;
        assert_eq!(kept.count, 1000);
        let log = bus::candump::read_log(kept.recording.candump.as_deref().unwrap()).unwrap();
        assert_eq!(log.len(), 1000);
        assert_eq!(log[999].frame.raw_id(), 0x100);
    }
}
