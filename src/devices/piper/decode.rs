//! The Piper's frames named for the report's frame table and `armhil decode --device piper`.

use bus::CanFrame;

use crate::devices::{FrameDecoder, WireDecode, WireOptions};
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

/// `armhil decode --device piper`: every frame by the Piper's protocol (the driver's codec);
/// a frame of it that does not decode says why. Its frames need none of the options, and one
/// given is refused by name (a RobStride or Damiao capture read without `--device`).
pub(crate) fn wire(options: &WireOptions) -> Result<WireDecode, String> {
    options.refuse(
        "piper",
        &["--host-id", "--model", "--motor"],
        "the Piper's frames carry every value they need (is the capture another device's?)",
    )?;
    Ok(Box::new(|frame| {
        decode_piper(frame).map_err(|e| e.to_string())
    }))
}
