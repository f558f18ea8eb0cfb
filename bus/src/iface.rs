//! The one async interface every bus implementation offers.

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

    /// Wait for the next frame from the bus, with its timestamp.
    async fn recv(&self) -> Result<ReceivedFrame, BusError>;

    /// Stop using the endpoint: pending and later `recv` calls return [`BusError::Closed`].
    async fn close(&self);

    /// A short human-readable name (interface or node name) for logs.
    fn name(&self) -> &str;
}
