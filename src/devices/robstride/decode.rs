//! A RobStride bus's frames named for the report's frame table.

use bus::CanFrame;
use driver::robstride::Model;

use super::Settings;
use crate::devices::FrameDecoder;
use crate::interop::{decode_robstride, decode_robstride_command, DecodedFrame};

/// The RobStride driver's host ID (the address motors reply to).
const HOST_ID: u8 = 0xFD;

/// Decodes the private protocol's extended (29-bit) frames of the motors on this bus, replies
/// and the host's commands, each with its own motor's model's ranges; frames of other motors
/// or other protocols are not this device's.
pub(crate) struct RobstrideFrames {
    /// The bus's motors: CAN ID and model.
    motors: Vec<(u8, Model)>,
}

impl RobstrideFrames {
    /// A decoder for the motors of `settings`.
    pub(crate) fn new(settings: &Settings) -> Self {
        Self::of_motors(settings.motors.iter().map(|m| (m.can_id, m.model)))
    }

    /// A decoder for these motors (CAN ID and the emulator's model), wherever they are
    /// listed: a RobStride bus, an actuator group, a robot.
    pub(crate) fn of_motors(motors: impl IntoIterator<Item = (u8, sim::robstride::Model)>) -> Self {
        Self {
            motors: motors
                .into_iter()
                .filter_map(|(id, model)| Some((id, Model::parse(model.name())?)))
                .collect(),
        }
    }
}

impl FrameDecoder for RobstrideFrames {
    fn decode(&self, frame: &CanFrame) -> Option<DecodedFrame> {
        if !frame.is_extended() {
            return None;
        }
        let model_of = |id: u8| self.motors.iter().find(|(m, _)| *m == id).map(|(_, m)| *m);
        // Motor replies carry the motor's CAN ID in bits 8..16, the host's commands in bits
        // 0..8.
        let replier = ((frame.raw_id() >> 8) & 0xFF) as u8;
        let addressee = (frame.raw_id() & 0xFF) as u8;
        model_of(replier)
            .and_then(|model| decode_robstride(frame, HOST_ID, model))
            .or_else(|| {
                model_of(addressee)
                    .and_then(|model| decode_robstride_command(frame, HOST_ID, model))
            })
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use bus::CanFrame;

    use super::RobstrideFrames;
    use crate::devices::piper::decode::PiperFrames;
    use crate::devices::{DeviceKind, FrameDecoder};
    use crate::harness::parse_scenario;

    fn bus_of_motor_1() -> RobstrideFrames {
        let text = "bench:\n  devices:\n    m: {kind: robstride, motors: [{id: 1, model: RS03}]}\nsteps:\n  - wait_ms: 1\n";
        let s = parse_scenario(Path::new("ok.yaml"), text).expect("valid");
        let DeviceKind::Robstride(settings) = &s.bench.devices[0].kind else {
            panic!("not a robstride bus");
        };
        RobstrideFrames::new(settings)
    }

    #[test]
    fn a_motors_status_frame_is_named_and_other_frames_are_left_to_their_devices() {
        let decoder = bus_of_motor_1();
        // Type 2 status from motor 1 to host 0xFD, at rest mid-range (0x8000 = 0 rad).
        let status = CanFrame::extended(
            0x0200_01FD,
            &[0x80, 0x00, 0x80, 0x00, 0x80, 0x00, 0x01, 0x2C],
        )
        .unwrap();
        let named = decoder.decode(&status).expect("motor 1's status");
        assert_eq!(named.name, "Status");
        // Motor 2 is not on this bus; an 11-bit frame is no private-protocol frame. Before each
        // device decoded its own frames, the report named every 11-bit frame as a Piper's,
        // whatever the bench held.
        let other_motor = CanFrame::extended(
            0x0200_02FD,
            &[0x80, 0x00, 0x80, 0x00, 0x80, 0x00, 0x01, 0x2C],
        )
        .unwrap();
        assert!(decoder.decode(&other_motor).is_none());
        let eleven_bit = CanFrame::standard(0x2A1, &[0; 8]).unwrap();
        assert!(decoder.decode(&eleven_bit).is_none());
        assert!(PiperFrames.decode(&status).is_none());
    }
}
