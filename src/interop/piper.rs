//! The Piper signal table and the DBC text generated from it (`docs/dbc/piper.dbc`).
//!
//! Layouts follow `docs/protocols/piper.md` §4 (feedback) and §5 (commands): every multi-byte
//! field is big-endian (Motorola). Enumerated fields get DBC value tables whose labels are
//! read from the driver's codec by probing it with each raw value, so the DBC and
//! `armhil decode` print the same names.

use std::fmt::Write as _;

use bus::CanFrame;
use driver::piper::codec;
use serde_json::Value;

use super::units::unit_of;

/// One signal: where it sits in the payload and which field of the driver's decoded message
/// carries it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SignalSpec {
    /// DBC signal name.
    pub name: String,
    /// First byte (the most significant one: big-endian).
    pub byte: usize,
    /// Length in bits: 8, 16 or 32.
    pub bits: u8,
    /// Two's-complement signed.
    pub signed: bool,
    /// Field name in the driver's decoded message (its suffix gives the unit).
    pub field: &'static str,
}

/// One message of the table.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MessageSpec {
    /// 11-bit CAN identifier.
    pub id: u16,
    /// DBC message name.
    pub name: String,
    /// Payload length.
    pub dlc: u8,
    /// `true` for frames the arm sends, `false` for host commands.
    pub from_arm: bool,
    /// Signals in payload order.
    pub signals: Vec<SignalSpec>,
}

fn sig(name: &str, byte: usize, bits: u8, signed: bool, field: &'static str) -> SignalSpec {
    SignalSpec {
        name: name.to_owned(),
        byte,
        bits,
        signed,
        field,
    }
}

fn msg(id: u16, name: &str, from_arm: bool, signals: Vec<SignalSpec>) -> MessageSpec {
    MessageSpec {
        id,
        name: name.to_owned(),
        dlc: 8,
        from_arm,
        signals,
    }
}

fn joint_pair(id: u16, prefix: &str, first: u16, from_arm: bool) -> MessageSpec {
    let a = format!("J{first}_angle");
    let b = format!("J{}_angle", first + 1);
    msg(
        id,
        &format!("{prefix}{first}{}", first + 1),
        from_arm,
        vec![
            sig(&a, 0, 32, true, "a_mdeg"),
            sig(&b, 4, 32, true, "b_mdeg"),
        ],
    )
}

/// The messages the DBC describes: the arm's periodic feedback and the joint targets.
pub fn piper_messages() -> Vec<MessageSpec> {
    let mut out = vec![
        msg(
            codec::ids::ARM_STATUS,
            "ArmStatus",
            true,
            vec![
                sig("ctrl_mode", 0, 8, false, "ctrl_mode"),
                sig("arm_status", 1, 8, false, "arm_status"),
                sig("mode_feed", 2, 8, false, "mode_feed"),
                sig("teach_status", 3, 8, false, "teach_status"),
                sig("motion_status", 4, 8, false, "motion_status"),
                sig("trajectory_num", 5, 8, false, "trajectory_num"),
                sig("angle_limit_exceeded", 6, 8, false, "angle_limit_exceeded"),
                sig("comm_error", 7, 8, false, "comm_error"),
            ],
        ),
        msg(
            codec::ids::END_POSE_1,
            "EndPoseXY",
            true,
            vec![sig("x", 0, 32, true, "x_um"), sig("y", 4, 32, true, "y_um")],
        ),
        msg(
            codec::ids::END_POSE_2,
            "EndPoseZRX",
            true,
            vec![
                sig("z", 0, 32, true, "z_um"),
                sig("rx", 4, 32, true, "rx_mdeg"),
            ],
        ),
        msg(
            codec::ids::END_POSE_3,
            "EndPoseRYRZ",
            true,
            vec![
                sig("ry", 0, 32, true, "ry_mdeg"),
                sig("rz", 4, 32, true, "rz_mdeg"),
            ],
        ),
    ];
    for (k, first) in [1u16, 3, 5].into_iter().enumerate() {
        let k = k as u16;
        out.push(joint_pair(
            codec::ids::JOINTS_12 + k,
            "JointFeedback",
            first,
            true,
        ));
    }
    out.push(msg(
        codec::ids::GRIPPER,
        "GripperFeedback",
        true,
        vec![
            sig("stroke", 0, 32, true, "stroke_um"),
            sig("torque", 4, 16, true, "torque_mnm"),
            sig("status", 6, 8, false, "status"),
        ],
    ));
    for j in 1..=6u16 {
        out.push(msg(
            0x250 + j,
            &format!("DriverHighSpeed{j}"),
            true,
            vec![
                sig("speed", 0, 16, true, "speed_mrad_s"),
                sig("current", 2, 16, true, "current_ma"),
                sig("position", 4, 32, true, "position_mrad"),
            ],
        ));
    }
    for j in 1..=6u16 {
        out.push(msg(
            0x260 + j,
            &format!("DriverLowSpeed{j}"),
            true,
            vec![
                sig("bus_voltage", 0, 16, false, "bus_voltage_dv"),
                sig("driver_temp", 2, 16, true, "driver_temp_c"),
                sig("motor_temp", 4, 8, true, "motor_temp_c"),
                sig("status", 5, 8, false, "status"),
                sig("bus_current", 6, 16, false, "bus_current_ma"),
            ],
        ));
    }
    for (k, first) in [1u16, 3, 5].into_iter().enumerate() {
        let k = k as u16;
        out.push(joint_pair(
            codec::ids::JOINT_CMD_12 + k,
            "JointCtrl",
            first,
            false,
        ));
    }
    out
}

/// The first value called `field` anywhere in `value` (the driver's messages serialize as
/// nested objects: `{"Joints": {"first_joint": 1, "a_mdeg": …}}`).
pub fn probe_field<'a>(value: &'a Value, field: &str) -> Option<&'a Value> {
    match value {
        Value::Object(map) => map
            .get(field)
            .or_else(|| map.values().find_map(|v| probe_field(v, field))),
        Value::Array(items) => items.iter().find_map(|v| probe_field(v, field)),
        _ => None,
    }
}

/// The driver's decoded message for `id` with payload `data`, as JSON.
fn driver_json(id: u16, data: &[u8]) -> Option<Value> {
    let frame = CanFrame::standard(id, data).ok()?;
    let message = codec::decode(&frame).ok()??;
    serde_json::to_value(message).ok()
}

/// Labels the driver gives the raw values of an 8-bit signal (empty when it is a number).
fn value_table(message: &MessageSpec, signal: &SignalSpec) -> Vec<(u8, String)> {
    if signal.bits != 8 || signal.signed {
        return Vec::new();
    }
    (0..=255u8)
        .filter_map(|raw| {
            let mut data = vec![0u8; usize::from(message.dlc)];
            data[signal.byte] = raw;
            let json = driver_json(message.id, &data)?;
            match probe_field(&json, signal.field)? {
                Value::String(label) => Some((raw, label.clone())),
                _ => None,
            }
        })
        .collect()
}

fn range_of(signal: &SignalSpec, scale: f64) -> (f64, f64) {
    let bits = i32::from(signal.bits);
    let (lo, hi) = if signal.signed {
        (-(2f64.powi(bits - 1)), 2f64.powi(bits - 1) - 1.0)
    } else {
        (0.0, 2f64.powi(bits) - 1.0)
    };
    (lo * scale, hi * scale)
}

/// The DBC text of [`piper_messages`] (what `docs/dbc/piper.dbc` holds).
pub fn piper_dbc() -> String {
    let messages = piper_messages();
    let mut out = String::new();
    out.push_str("VERSION \"armhil piper 1\"\n\nNS_ :\n\nBS_:\n\nBU_: Piper Host\n");
    let mut tables = Vec::new();
    for m in &messages {
        let sender = if m.from_arm { "Piper" } else { "Host" };
        let receiver = if m.from_arm { "Host" } else { "Piper" };
        let _ = write!(out, "\nBO_ {} {}: {} {sender}\n", m.id, m.name, m.dlc);
        for s in &m.signals {
            let unit = unit_of(s.field);
            let (min, max) = range_of(s, unit.scale);
            // Motorola byte order: the start bit is the MSB, bit 7 of the first byte.
            let start = s.byte * 8 + 7;
            let sign = if s.signed { '-' } else { '+' };
            let _ = writeln!(
                out,
                " SG_ {} : {start}|{}@0{sign} ({},0) [{min}|{max}] \"{}\" {receiver}",
                s.name, s.bits, unit.scale, unit.unit
            );
            let table = value_table(m, s);
            if !table.is_empty() {
                tables.push((m.id, s.name.clone(), table));
            }
        }
    }
    out.push('\n');
    let _ = writeln!(
        out,
        "CM_ \"Piper CAN protocol (docs/protocols/piper.md), generated by armhil from the \
         driver's codec; regenerate with ARMHIL_BLESS=1 cargo test -p armhil --test integration dbc\";"
    );
    for (id, name, table) in tables {
        let _ = write!(out, "VAL_ {id} {name}");
        for (raw, label) in table {
            let _ = write!(out, " {raw} \"{label}\"");
        }
        out.push_str(" ;\n");
    }
    out
}
