//! The one async interface every bus implementation offers.

use std::time::Duration;

use async_trait::async_trait;

use crate::{BusError, CanFrame, ReceivedFrame};

/// A CAN endpoint: send frames, receive every frame other nodes send, close.
///
/// Implementations are `Send + Sync` so one endpoint can be shared (`Arc<dyn CanBus>`) between
/// a task that receives and any number of tasks that send. Frames are received in the order
/// they completed on the wire. An endpoint does not receive its own frames unless it was
/// created with own-loopback enabled (SocketCAN's `recv_own_msgs`).
#[async_trait]
pub trait CanBus: Send + Sync {
    /// Queue a frame for transmission. Returns once the frame is accepted by the transmit queue;
    /// a full queue is [`BusError::TxQueueFull`], never a silent drop.
    async fn send(&self, frame: CanFrame) -> Result<(), BusError>;

    /// Queue a frame that may start on the wire no earlier than `delay` from now: a
    /// firmware's answer, which leaves its turnaround after the request arrived. The frame
    /// holds its place in the transmit queue meanwhile. Buses that do not model the wire
    /// (SocketCAN, socketcand) send at once, where the path to the real wire takes about as
    /// long.
    async fn send_after(&self, frame: CanFrame, delay: Duration) -> Result<(), BusError> {
        let _ = delay;
        self.send(frame).await
    }

    /// How long ago `received`, a frame this endpoint returned from [`CanBus::recv`], finished
    /// on the wire, by this bus's clock. Zero on buses that do not model the wire (SocketCAN,
    /// socketcand), whose timestamps are another clock's and whose answers leave at once
    /// anyway.
    fn since_received(&self, received: &ReceivedFrame) -> Duration {
        let _ = received;
        Duration::ZERO
    }

    /// The delay to give [`CanBus::send_after`] for an answer to `request` that a firmware
    /// sends `turnaround` after the request's last bit: the turnaround counts from there, so
    /// an emulator that got round to the request late answers no later for it (the time it
    /// took is part of the turnaround, not added to it), and one later than the whole
    /// turnaround answers at once.
    fn answer_delay(&self, request: &ReceivedFrame, turnaround: Duration) -> Duration {
        turnaround.saturating_sub(self.since_received(request))
    }

    /// Wait for the next frame from the bus, with its timestamp.
    async fn recv(&self) -> Result<ReceivedFrame, BusError>;

    /// Stop using the endpoint: pending and later `recv` calls return [`BusError::Closed`].
    async fn close(&self);

    /// A short human-readable name (interface or node name) for logs.
    fn name(&self) -> &str;
}
