//! A RobStride bus's frames named for the report's frame table.

use bus::CanFrame;
use driver::robstride::Model;

use super::Settings;
use crate::devices::FrameDecoder;
use crate::interop::{decode_robstride, DecodedFrame};

/// The RobStride driver's host ID (the address motors reply to).
const HOST_ID: u8 = 0xFD;

/// Decodes the private protocol's extended (29-bit) frames of the motors on this bus, each with
/// its own model's ranges; frames of other motors or other protocols are not this device's.
pub(crate) struct RobstrideFrames {
    /// The bus's motors: CAN ID and model.
    motors: Vec<(u8, Model)>,
}

impl RobstrideFrames {
    /// A decoder for the motors of `settings`.
    pub(crate) fn new(settings: &Settings) -> Self {
        Self {
            motors: settings
                .motors
                .iter()
                .filter_map(|m| Some((m.can_id, Model::parse(m.model.name())?)))
                .collect(),
        }
    }
}

impl FrameDecoder for RobstrideFrames {
    fn decode(&self, frame: &CanFrame) -> Option<DecodedFrame> {
        if !frame.is_extended() {
            return None;
        }
        // Motor replies carry the motor's CAN ID in bits 8..16.
        let motor = ((frame.raw_id() >> 8) & 0xFF) as u8;
        let (_, model) = self.motors.iter().find(|(id, _)| *id == motor)?;
        decode_robstride(frame, HOST_ID, *model)
    }
}
