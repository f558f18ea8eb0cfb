//! The Piper's frames named for the report's frame table.

use bus::CanFrame;

use crate::devices::FrameDecoder;
use crate::interop::{decode_piper, DecodedFrame};

/// Decodes the Piper's standard (11-bit) frames; extended frames are never a Piper's.
pub(crate) struct PiperFrames;

impl FrameDecoder for PiperFrames {
    fn decode(&self, _bus: Option<&str>, frame: &CanFrame) -> Option<DecodedFrame> {
        if frame.is_extended() {
            return None;
        }
        decode_piper(frame).ok().flatten()
    }
}
