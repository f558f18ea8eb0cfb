//! Counts every frame on the bus and, when a recording was asked for, writes it to the
//! candump / pcap spool files as it arrives (never holding frames in memory: a long scenario
//! would otherwise grow without bound).

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Duration;

use bus::{CanBus, ReceivedFrame};
use tokio::sync::{broadcast, oneshot};
use tokio::task::JoinHandle;

use super::spool::{Recording, Spool};
use crate::harness::model::DEFAULT_BUS;

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
    /// Frames seen per bus name.
    pub by_bus: BTreeMap<String, u64>,
}

impl Capture {
    fn new(spool: Spool) -> Self {
        Self {
            spool: spool.is_recording().then_some(spool),
            ..Self::default()
        }
    }

    fn push(&mut self, frame: ReceivedFrame, bus: &str) {
        self.count += 1;
        *self.by_id.entry(frame.frame.raw_id()).or_insert(0) += 1;
        match self.by_bus.get_mut(bus) {
            Some(count) => *count += 1,
            None => {
                self.by_bus.insert(bus.to_owned(), 1);
            }
        }
        if let Some(spool) = &mut self.spool {
            spool.write(&frame, bus);
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
    /// Record from the virtual buses' taps (every frame that completed on a wire), each
    /// named as bus.log names it, into `spool`.
    pub fn from_taps(
        taps: Vec<(String, broadcast::Receiver<ReceivedFrame>)>,
        spool: Spool,
    ) -> Self {
        let (stop, stopped) = oneshot::channel::<()>();
        let task = tokio::spawn(async move {
            let mut frames = Capture::new(spool);
            let names: Vec<String> = taps.iter().map(|(name, _)| name.clone()).collect();
            let mut receivers: Vec<_> = taps.into_iter().map(|(_, tap)| tap).collect();
            let missed = match receivers.as_mut_slice() {
                // One bus: no merging, frames in wire order.
                [tap] => record_one(tap, &names[0], &mut frames, stopped).await,
                _ => record_merged(receivers, &names, &mut frames, stopped).await,
            };
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
                        Ok(frame) => frames.push(frame, DEFAULT_BUS),
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

/// Record one bus's tap until `stopped`, then drain it; returns the frames the tap missed.
async fn record_one(
    tap: &mut broadcast::Receiver<ReceivedFrame>,
    name: &str,
    frames: &mut Capture,
    mut stopped: oneshot::Receiver<()>,
) -> u64 {
    let mut missed = 0u64;
    loop {
        tokio::select! {
            biased;
            received = tap.recv() => match received {
                Ok(frame) => frames.push(frame, name),
                Err(broadcast::error::RecvError::Lagged(n)) => missed += n,
                Err(broadcast::error::RecvError::Closed) => break,
            },
            _ = &mut stopped => {
                missed += drain(tap, name, frames);
                break;
            }
        }
    }
    missed
}

/// Frames already in `tap`, into `frames`; returns how many the tap had missed.
fn drain(tap: &mut broadcast::Receiver<ReceivedFrame>, name: &str, frames: &mut Capture) -> u64 {
    let mut missed = 0;
    loop {
        match tap.try_recv() {
            Ok(frame) => frames.push(frame, name),
            Err(broadcast::error::TryRecvError::Lagged(n)) => missed += n,
            Err(_) => return missed,
        }
    }
}

/// Record several buses into one capture. One forwarding task per tap keeps each `recv` out
/// of a `select!` over a changing set; the bounded queue between them and the writer makes a
/// slow disk show as missed frames on the taps, never as memory.
async fn record_merged(
    taps: Vec<broadcast::Receiver<ReceivedFrame>>,
    names: &[String],
    frames: &mut Capture,
    stopped: oneshot::Receiver<()>,
) -> u64 {
    let (stop_all, _) = broadcast::channel::<()>(1);
    let (tx, mut rx) = tokio::sync::mpsc::channel::<(usize, ReceivedFrame)>(MERGE_QUEUE_FRAMES);
    let forwarders: Vec<JoinHandle<u64>> = taps
        .into_iter()
        .enumerate()
        .map(|(index, mut tap)| {
            let tx = tx.clone();
            let mut stop = stop_all.subscribe();
            tokio::spawn(async move {
                let mut missed = 0u64;
                loop {
                    tokio::select! {
                        biased;
                        received = tap.recv() => match received {
                            Ok(frame) => {
                                if tx.send((index, frame)).await.is_err() {
                                    break;
                                }
                            }
                            Err(broadcast::error::RecvError::Lagged(n)) => missed += n,
                            Err(broadcast::error::RecvError::Closed) => break,
                        },
                        _ = stop.recv() => {
                            // Drain what is already in the tap, as `drain` does for one bus.
                            loop {
                                match tap.try_recv() {
                                    Ok(frame) => {
                                        if tx.send((index, frame)).await.is_err() {
                                            break;
                                        }
                                    }
                                    Err(broadcast::error::TryRecvError::Lagged(n)) => missed += n,
                                    Err(_) => break,
                                }
                            }
                            break;
                        }
                    }
                }
                missed
            })
        })
        .collect();
    drop(tx);
    let stopper = tokio::spawn(async move {
        let _ = stopped.await;
        let _ = stop_all.send(());
    });
    let mut order = WireOrder::default();
    while let Some((index, frame)) = rx.recv().await {
        order.insert(index, frame);
        while let Some((index, frame)) = order.pop_settled() {
            frames.push(frame, &names[index]);
        }
    }
    while let Some((index, frame)) = order.pop_first() {
        frames.push(frame, &names[index]);
    }
    stopper.abort();
    let mut missed = 0;
    for forwarder in forwarders {
        missed += forwarder.await.unwrap_or(0);
    }
    missed
}

/// Frames queued between the buses' forwarding tasks and the writer of a several-bus bench.
const MERGE_QUEUE_FRAMES: usize = 4096;

/// How far behind the newest frame a frame is held for frames of other buses that completed
/// earlier but were forwarded later (scheduling order between the buses' tasks).
const REORDER_WINDOW: Duration = Duration::from_millis(50);

/// At most this many frames are held for reordering (then the oldest goes out regardless).
const REORDER_MAX_FRAMES: usize = 16_384;

/// Puts the frames of several buses in the order they completed on their wires, ties broken
/// by bus then arrival, so that two runs of a scenario write the same bus.log to the byte
/// (the order in which the buses' forwarding tasks run is not deterministic).
#[derive(Default)]
struct WireOrder {
    held: BTreeMap<(Duration, usize, u64), ReceivedFrame>,
    newest: Duration,
    arrivals: u64,
}

impl WireOrder {
    fn insert(&mut self, bus: usize, frame: ReceivedFrame) {
        self.newest = self.newest.max(frame.timestamp);
        self.arrivals += 1;
        self.held
            .insert((frame.timestamp, bus, self.arrivals), frame);
    }

    /// The oldest frame, once no frame of another bus can still come before it.
    fn pop_settled(&mut self) -> Option<(usize, ReceivedFrame)> {
        let (&(at, _, _), _) = self.held.first_key_value()?;
        if at + REORDER_WINDOW <= self.newest || self.held.len() > REORDER_MAX_FRAMES {
            self.pop_first()
        } else {
            None
        }
    }

    fn pop_first(&mut self) -> Option<(usize, ReceivedFrame)> {
        self.held
            .pop_first()
            .map(|((_, bus, _), frame)| (bus, frame))
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use bus::CanFrame;

    use super::*;

    async fn capture(keep: bool) -> Capture {
        let (tx, rx) = broadcast::channel(4096);
        let recorder = Recorder::from_taps(
            vec![(DEFAULT_BUS.to_owned(), rx)],
            Spool::create(keep, false, u64::MAX, &[DEFAULT_BUS.to_owned()]).unwrap(),
        );
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

    #[tokio::test]
    async fn several_buses_are_logged_in_wire_order_with_their_names() {
        let (tx0, rx0) = broadcast::channel(64);
        let (tx1, rx1) = broadcast::channel(64);
        let recorder = Recorder::from_taps(
            vec![("can0".to_owned(), rx0), ("can1".to_owned(), rx1)],
            Spool::create(true, false, u64::MAX, &[DEFAULT_BUS.to_owned()]).unwrap(),
        );
        let at = |ms: u64, id: u16| ReceivedFrame {
            frame: CanFrame::standard(id, &[]).unwrap(),
            timestamp: Duration::from_millis(ms),
        };
        // can1's frames reach the recorder first though can0's completed earlier.
        tx1.send(at(2, 0x201)).unwrap();
        tx1.send(at(4, 0x202)).unwrap();
        tx0.send(at(1, 0x101)).unwrap();
        tx0.send(at(3, 0x102)).unwrap();
        let (capture, missed) = recorder.finish().await;
        assert_eq!((capture.count, missed), (4, 0));
        let text = std::fs::read_to_string(capture.recording.candump.as_deref().unwrap()).unwrap();
        let lines: Vec<&str> = text.lines().map(|l| l.split_once(' ').unwrap().1).collect();
        assert_eq!(lines, ["can0 101#", "can1 201#", "can0 102#", "can1 202#"]);
    }
}
