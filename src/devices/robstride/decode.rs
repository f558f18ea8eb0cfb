//! A RobStride bus's frames named for the report's frame table, and RobStride's protocols for
//! `armhil decode --device robstride|robstride-mit`.

use bus::CanFrame;
use driver::robstride::Model;

use super::Settings;
use crate::devices::{FrameDecoder, WireDecode, WireMotor, WireOptions};
use crate::interop::{
    decode_robstride, decode_robstride_command, decode_robstride_mit, DecodedFrame,
};

/// The RobStride driver's host ID (the address motors reply to).
const HOST_ID: u8 = 0xFD;

/// Decodes the private protocol's extended (29-bit) frames of the motors on this device's
/// buses, replies and the host's commands, each with its own motor's model's ranges; frames of
/// other motors or other protocols are not this device's.
pub(crate) struct RobstrideFrames {
    /// The motors: the bus they sit on (`None`: unknown), CAN ID and model.
    motors: Vec<(Option<String>, u8, Model)>,
    /// The host ID replies are addressed to (the driver's, [`HOST_ID`], unless told).
    host_id: u8,
}

impl RobstrideFrames {
    /// A decoder for the motors of `settings`, on the first of `buses`.
    pub(crate) fn new(settings: &Settings, buses: &[String]) -> Self {
        let bus = buses.first().cloned();
        Self::of_motors(
            settings
                .motors
                .iter()
                .map(|m| (bus.clone(), m.can_id, m.model)),
        )
    }

    /// A decoder for these motors (bus, CAN ID and the emulator's model), wherever they are
    /// listed: a RobStride bus, an actuator group, a robot.
    pub(crate) fn of_motors(
        motors: impl IntoIterator<Item = (Option<String>, u8, sim::robstride::Model)>,
    ) -> Self {
        Self {
            motors: motors
                .into_iter()
                .filter_map(|(bus, id, model)| Some((bus, id, Model::parse(model.name())?)))
                .collect(),
            host_id: HOST_ID,
        }
    }

    /// The model of motor `id` on `bus` (on any bus when `None`); `None` when no such motor
    /// is listed, or when the bus is unknown and motors of that ID on different buses are of
    /// different models: a guess would scale the frame by the wrong ranges.
    fn model_of(&self, bus: Option<&str>, id: u8) -> Option<Model> {
        let mut candidates = self
            .motors
            .iter()
            .filter(|(on, m, _)| *m == id && (bus.is_none() || on.as_deref() == bus))
            .map(|(_, _, model)| *model);
        let first = candidates.next()?;
        candidates.all(|m| m == first).then_some(first)
    }
}

impl FrameDecoder for RobstrideFrames {
    fn decode(&self, bus: Option<&str>, frame: &CanFrame) -> Option<DecodedFrame> {
        if !frame.is_extended() {
            return None;
        }
        // Motor replies carry the motor's CAN ID in bits 8..16, the host's commands in bits
        // 0..8.
        let replier = ((frame.raw_id() >> 8) & 0xFF) as u8;
        let addressee = (frame.raw_id() & 0xFF) as u8;
        self.model_of(bus, replier)
            .and_then(|model| decode_robstride(frame, self.host_id, model))
            .or_else(|| {
                self.model_of(bus, addressee)
                    .and_then(|model| decode_robstride_command(frame, self.host_id, model))
            })
    }
}

/// The model `--model` names (RS03 when not given), resolved through the driver's table.
fn wire_model(options: &WireOptions) -> Result<Model, String> {
    let Some(name) = &options.model else {
        return Ok(Model::RS03);
    };
    Model::parse(name).ok_or_else(|| {
        let damiao = driver::damiao::Model::parse(name).is_some();
        format!(
            "`--model {name}`: {}{}",
            unknown_model(name),
            if damiao {
                " (`--model` is RobStride's: a Damiao motor is given as --motor ID:MODEL with --device damiao)"
            } else {
                ""
            }
        )
    })
}

/// "unknown RobStride model `X`; expected one of: RS00, …", with the nearest name.
fn unknown_model(name: &str) -> String {
    let known: Vec<&str> = sim::robstride::Model::ALL
        .iter()
        .map(|m| m.name())
        .collect();
    format!(
        "unknown RobStride model `{name}`; expected one of: {}{}",
        known.join(", "),
        sim::yaml_words::suggestion(&name.to_ascii_uppercase(), &known)
    )
}

/// One `--motor ID:MODEL` as a RobStride motor: a CAN ID 1..=127 and a model of the driver's
/// table; RobStride motors answer on their own ID, so a feedback id is refused.
fn wire_motor(motor: &WireMotor) -> Result<(Option<String>, u8, sim::robstride::Model), String> {
    let flag = motor.flag();
    if motor.feedback_id.is_some() {
        return Err(format!(
            "{flag}: a RobStride motor has no feedback id (it answers under its own CAN ID): give ID:MODEL"
        ));
    }
    let id = u8::try_from(motor.id)
        .ok()
        .filter(|id| (1..=0x7F).contains(id))
        .ok_or_else(|| format!("{flag}: CAN ID {} out of range, expected 1..=127", motor.id))?;
    let model = sim::robstride::Model::from_name(&motor.model)
        .ok_or_else(|| format!("{flag}: {}", unknown_model(&motor.model)))?;
    Ok((None, id, model))
}

/// `armhil decode --device robstride`: the private protocol both ways, the motors' replies to
/// `--host-id` (0xFD unless given) and the host's commands, scaled by `--model`'s ranges (RS03
/// unless given); with `--motor ID:MODEL` only the listed motors' frames, each by its own
/// model's ranges.
pub(crate) fn wire_private(options: &WireOptions) -> Result<WireDecode, String> {
    let host_id = options.host_id.unwrap_or(HOST_ID);
    if !options.motors.is_empty() {
        if let Some(model) = &options.model {
            return Err(format!(
                "`--model {model}` and `--motor` both given: `--motor ID:MODEL` names each motor's model"
            ));
        }
        let motors = options
            .motors
            .iter()
            .map(wire_motor)
            .collect::<Result<Vec<_>, _>>()?;
        let mut frames = RobstrideFrames::of_motors(motors);
        frames.host_id = host_id;
        return Ok(Box::new(move |frame| Ok(frames.decode(None, frame))));
    }
    let model = wire_model(options)?;
    Ok(Box::new(move |frame| {
        Ok(decode_robstride(frame, host_id, model)
            .or_else(|| decode_robstride_command(frame, host_id, model)))
    }))
}

/// `armhil decode --device robstride-mit`: the MIT variant's 11-bit frames, scaled by
/// `--model`'s ranges (RS03 unless given).
pub(crate) fn wire_mit(options: &WireOptions) -> Result<WireDecode, String> {
    options.refuse(
        "robstride-mit",
        &["--motor"],
        "its frames are scaled by one `--model`",
    )?;
    let host_id = options.host_id.unwrap_or(HOST_ID);
    let model = wire_model(options)?;
    Ok(Box::new(move |frame| {
        Ok(decode_robstride_mit(frame, host_id, model))
    }))
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
        RobstrideFrames::new(settings, &["vcan0".to_owned()])
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
        let named = decoder.decode(None, &status).expect("motor 1's status");
        assert_eq!(named.name, "Status");
        // Motor 2 is not on this bus; an 11-bit frame is no private-protocol frame. Before each
        // device decoded its own frames, the report named every 11-bit frame as a Piper's,
        // whatever the bench held.
        let other_motor = CanFrame::extended(
            0x0200_02FD,
            &[0x80, 0x00, 0x80, 0x00, 0x80, 0x00, 0x01, 0x2C],
        )
        .unwrap();
        assert!(decoder.decode(None, &other_motor).is_none());
        let eleven_bit = CanFrame::standard(0x2A1, &[0; 8]).unwrap();
        assert!(decoder.decode(None, &eleven_bit).is_none());
        assert!(PiperFrames.decode(None, &status).is_none());
    }

    /// A robot's IDs repeat across its buses: motor 1 is an RS04 on can0 and an RS00 on can1.
    /// A command to can1's motor at kp 100 reads kp 100 by can1's ranges (by the RS04's, as
    /// before the decoder knew buses, it read kp 1000), and a frame whose bus is unknown is
    /// left undecoded rather than scaled by a guess.
    #[test]
    fn a_frame_is_decoded_by_the_model_of_the_motor_on_its_own_bus() {
        use driver::robstride::codec::{op_control_frame, OpControl};
        use driver::robstride::{Model as DriverModel, RangeTable};
        let decoder = RobstrideFrames::of_motors([
            (Some("can0".to_owned()), 1, sim::robstride::Model::RS04),
            (Some("can1".to_owned()), 1, sim::robstride::Model::RS00),
        ]);
        let command = op_control_frame(
            1,
            &OpControl {
                angle_rad: 0.5,
                speed_rad_s: 0.0,
                kp: 100.0,
                kd: 2.0,
                torque_nm: 0.0,
            },
            &DriverModel::RS00.ranges(RangeTable::Manual),
        )
        .expect("a frame");
        let kp = |bus: Option<&str>| {
            decoder.decode(bus, &command).map(|d| {
                let field = d.fields.iter().find(|f| f.name == "kp").expect("kp");
                field.value.parse::<f64>().expect("a number").round()
            })
        };
        assert_eq!(kp(Some("can1")), Some(100.0));
        assert_eq!(kp(Some("can0")), Some(1000.0));
        assert_eq!(kp(None), None);
    }
}
