//! The host's side of a RobStride bus: private-protocol commands (host → motor) named with
//! their fields in units, so that a capture reads both ways. Replies are
//! [`decode_robstride`](super::decode_robstride)'s. Built on the driver's own wire
//! constants, scaling and parameter table (the emulator's codec is never used here).

use bus::CanFrame;
use driver::robstride::codec::{comm, from_u16};
use driver::robstride::{Model, Param, ParamType, ParamValue, RangeTable};

use super::decode::{num, text, DecodedFrame};

/// A command frame to a motor (not addressed to `host_id`), decoded with `model`'s ranges;
/// `None` for anything else (a reply, an 11-bit frame, a type this protocol does not send).
pub fn decode_robstride_command(
    frame: &CanFrame,
    host_id: u8,
    model: Model,
) -> Option<DecodedFrame> {
    if !frame.is_extended() {
        return None;
    }
    let raw = frame.raw_id();
    let comm_type = ((raw >> 24) & 0x1F) as u8;
    let data2 = ((raw >> 8) & 0xFFFF) as u16;
    let motor = (raw & 0xFF) as u8;
    let data: [u8; 8] = frame.data().try_into().ok()?;
    if motor == host_id {
        return None;
    }
    let r = model.ranges(RangeTable::Manual);
    let be = |i: usize| u16::from_be_bytes([data[i], data[i + 1]]);
    let index = u16::from_le_bytes([data[0], data[1]]);
    let param_name = || {
        text(
            "param",
            Param::from_index(index)
                .map_or_else(|| format!("0x{index:04X}"), |p| p.name().to_owned()),
        )
    };
    let (name, mut fields) = match comm_type {
        comm::GET_ID => ("GetDeviceId", vec![]),
        comm::OP_CONTROL => (
            "OpControl",
            vec![
                num(
                    "angle",
                    f64::from(from_u16(be(0), -r.angle_rad, r.angle_rad)),
                    4,
                    "rad",
                ),
                num(
                    "speed",
                    f64::from(from_u16(be(2), -r.speed_rad_s, r.speed_rad_s)),
                    4,
                    "rad/s",
                ),
                num("kp", f64::from(from_u16(be(4), 0.0, r.kp_max)), 3, ""),
                num("kd", f64::from(from_u16(be(6), 0.0, r.kd_max)), 3, ""),
                num(
                    "torque",
                    f64::from(from_u16(data2, -r.torque_nm, r.torque_nm)),
                    4,
                    "N.m",
                ),
            ],
        ),
        comm::STATUS => ("StatusPoll", vec![]),
        comm::ENABLE => ("Enable", vec![]),
        comm::STOP if data[1] == 0xC4 => ("VersionRead", vec![]),
        comm::STOP => (
            "Stop",
            vec![text("clear_faults", (data[0] == 1).to_string())],
        ),
        comm::SET_ZERO => ("SetZero", vec![]),
        comm::SET_CAN_ID => (
            "SetCanId",
            vec![num("new_id", f64::from(data2 >> 8), 0, "")],
        ),
        comm::READ_PARAM => ("ReadParamRequest", vec![param_name()]),
        comm::WRITE_PARAM => {
            let value_bytes = [data[4], data[5], data[6], data[7]];
            let ty = Param::from_index(index).map_or(ParamType::F32, Param::ty);
            let value = match ParamValue::from_bytes(ty, value_bytes) {
                ParamValue::F32(v) => format!("{v}"),
                other => format!("{}", other.as_f64()),
            };
            ("WriteParam", vec![param_name(), text("value", value)])
        }
        comm::SAVE => ("Save", vec![]),
        comm::BAUD => ("SetBaud", vec![num("code", f64::from(data[6]), 0, "")]),
        comm::ACTIVE_REPORT => ("ActiveReport", vec![text("on", (data[6] == 1).to_string())]),
        comm::PROTOCOL => ("SetProtocol", vec![num("code", f64::from(data[6]), 0, "")]),
        _ => return None,
    };
    let mut all = vec![num("motor", f64::from(motor), 0, "")];
    if comm_type != comm::OP_CONTROL {
        // Every command but operation control carries the host's ID in bits 15..8.
        all.push(num("host", f64::from(data2 & 0xFF), 0, ""));
    }
    all.append(&mut fields);
    Some(DecodedFrame {
        name: name.to_owned(),
        fields: all,
    })
}

#[cfg(test)]
mod tests {
    use driver::robstride::codec::{op_control_frame, request, OpControl};

    use super::*;

    const HOST: u8 = 0xFD;

    fn field<'a>(d: &'a DecodedFrame, name: &str) -> &'a str {
        &d.fields.iter().find(|f| f.name == name).expect(name).value
    }

    /// The driver's own encoder is the test vector: what it sends reads back in units.
    #[test]
    fn the_driver_s_commands_read_back_with_their_values() {
        let model = Model::RS03;
        let r = model.ranges(RangeTable::Manual);
        let cmd = OpControl {
            angle_rad: 1.25,
            speed_rad_s: -2.0,
            kp: 40.0,
            kd: 1.5,
            torque_nm: 6.0,
        };
        let frame = op_control_frame(11, &cmd, &r).unwrap();
        let d = decode_robstride_command(&frame, HOST, model).expect("an op-control command");
        assert_eq!(d.name, "OpControl");
        assert_eq!(field(&d, "motor"), "11");
        // 16-bit scaling truncates: within one step of each range (RS03: ±4π rad, ±60 N·m,
        // kp 0..5000 — a step of 0.076), and a wrong range would miss by far more.
        let step = |span: f32| f64::from(span) / 65535.0;
        let close = |name: &str, want: f64, span: f32| {
            let got: f64 = field(&d, name).parse().unwrap();
            assert!(
                (got - want).abs() <= step(span) + 1e-4,
                "{name}: {got} for {want}"
            );
        };
        close("angle", 1.25, 2.0 * r.angle_rad);
        close("speed", -2.0, 2.0 * r.speed_rad_s);
        close("kp", 40.0, r.kp_max);
        close("kd", 1.5, r.kd_max);
        close("torque", 6.0, 2.0 * r.torque_nm);

        let [lo, hi] = Param::LocRef.index().to_le_bytes();
        let v = 0.5f32.to_le_bytes();
        let write = request(
            comm::WRITE_PARAM,
            u16::from(HOST),
            11,
            [lo, hi, 0, 0, v[0], v[1], v[2], v[3]],
        )
        .unwrap();
        let d = decode_robstride_command(&write, HOST, model).unwrap();
        assert_eq!(
            (d.name.as_str(), field(&d, "param"), field(&d, "value")),
            ("WriteParam", "loc_ref", "0.5")
        );
        assert_eq!(field(&d, "host"), "253");

        let stop = request(comm::STOP, u16::from(HOST), 11, [1, 0, 0, 0, 0, 0, 0, 0]).unwrap();
        let d = decode_robstride_command(&stop, HOST, model).unwrap();
        assert_eq!(
            (d.name.as_str(), field(&d, "clear_faults")),
            ("Stop", "true")
        );
    }

    #[test]
    fn replies_and_11_bit_frames_are_not_commands() {
        // A status reply from motor 11 is addressed to the host.
        let reply =
            CanFrame::extended(0x0200_0BFD, &[0x80, 0, 0x80, 0, 0x80, 0, 0x01, 0x2C]).unwrap();
        assert!(decode_robstride_command(&reply, HOST, Model::RS03).is_none());
        let piper = CanFrame::standard(0x155, &[0; 8]).unwrap();
        assert!(decode_robstride_command(&piper, HOST, Model::RS03).is_none());
    }
}
