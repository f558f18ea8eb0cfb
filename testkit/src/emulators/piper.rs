//! A Piper emulator on a fresh virtual bus with a host node beside it, and ways to look at what
//! the host received.

use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame};
use sim::piper::{PiperConfig, PiperEmulator, PiperHandle};

/// A Piper emulator with `config` on a new default virtual bus, and a host node beside it.
pub fn spawn_emulator(config: PiperConfig) -> (VirtualBus, VirtualNode, PiperHandle) {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emu_node = bus.attach("piper");
    let host = bus.attach("host");
    let emu = PiperEmulator::spawn(Arc::new(emu_node), config).expect("the emulator starts");
    (bus, host, emu)
}

/// Every frame the host receives during `dur` of virtual time.
pub async fn collect(host: &VirtualNode, dur: Duration) -> Vec<CanFrame> {
    let mut out = Vec::new();
    let deadline = tokio::time::Instant::now() + dur;
    while let Ok(Ok(rf)) = tokio::time::timeout_at(deadline, host.recv()).await {
        out.push(rf.frame);
    }
    out
}

/// The payload of the last frame with `id` among `frames`.
pub fn last(frames: &[CanFrame], id: u32) -> Option<Vec<u8>> {
    frames
        .iter()
        .rev()
        .find(|f| f.raw_id() == id)
        .map(|f| f.data().to_vec())
}
