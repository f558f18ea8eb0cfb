//! One frame in, named fields with units out, through the driver's codecs.

use std::time::Duration;

use bus::{CanFrame, CanId};
use driver::piper::codec;
use driver::robstride::codec as rs_codec;
use driver::robstride::mit_codec;
use driver::robstride::{Model, RangeTable};
use serde_json::Value;

use super::piper::{piper_messages, probe_field};
use super::units::unit_of;

/// One decoded field.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    /// Name (the DBC signal name for frames the DBC describes).
    pub name: String,
    /// The value as printed: a number in `unit`, or an enumeration label.
    pub value: String,
    /// Unit, empty for plain numbers and labels.
    pub unit: &'static str,
}

/// A decoded frame: message name and fields.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedFrame {
    /// Message name.
    pub name: String,
    /// Fields in payload order.
    pub fields: Vec<Field>,
}

/// Decimal places that show every digit a wire unit of `scale` can carry.
fn decimals(scale: f64) -> usize {
    let mut places = 0;
    let mut s = scale;
    while places < 6 && (s - s.round()).abs() > 1e-9 {
        s *= 10.0;
        places += 1;
    }
    places
}

/// A JSON leaf as a field: numbers scaled by the unit their name carries.
fn field_of(name: &str, field: &str, value: &Value) -> Field {
    let unit = unit_of(field);
    match value {
        Value::Number(n) => {
            let raw = n.as_f64().unwrap_or(f64::NAN);
            let scaled = raw * unit.scale;
            let text = if n.is_f64() {
                format!("{scaled:.4}")
            } else {
                format!("{scaled:.*}", decimals(unit.scale))
            };
            Field {
                name: name.to_owned(),
                value: text,
                unit: unit.unit,
            }
        }
        Value::String(label) => Field {
            name: name.to_owned(),
            value: label.clone(),
            unit: "",
        },
        // A wire enum's value the spec does not define: `{"Unknown": raw}`.
        Value::Object(map) if map.len() == 1 => {
            let inner = map.values().next().unwrap_or(&Value::Null);
            field_of(name, field, inner)
        }
        other => Field {
            name: name.to_owned(),
            value: other.to_string(),
            unit: "",
        },
    }
}

fn strip_unit(field: &str) -> &str {
    const SUFFIXES: [&str; 11] = [
        "_mrad_s2", "_mrad_s", "_mm_s2", "_mm_s", "_mrad", "_mdeg", "_mnm", "_um", "_ma", "_dv",
        "_c",
    ];
    SUFFIXES
        .iter()
        .find_map(|s| field.strip_suffix(s))
        .unwrap_or(field)
}

/// Every leaf of a JSON object as fields (for messages the DBC does not describe).
fn flatten(value: &Value, out: &mut Vec<Field>) {
    if let Value::Object(map) = value {
        for (key, v) in map {
            match v {
                Value::Object(inner) if inner.len() > 1 || !inner.contains_key("Unknown") => {
                    flatten(v, out)
                }
                Value::Array(items) => {
                    for (i, item) in items.iter().enumerate() {
                        let name = format!("{}{}", strip_unit(key), i + 1);
                        out.push(field_of(&name, key, item));
                    }
                }
                _ => out.push(field_of(strip_unit(key), key, v)),
            }
        }
    }
}

/// Decodes a Piper frame with the driver's codec. `Ok(None)` for frames the driver does not
/// interpret (host commands other than the echoed ones, unknown ids).
pub fn decode_piper(frame: &CanFrame) -> Result<Option<DecodedFrame>, codec::DecodeError> {
    let Some(message) = codec::decode(frame)? else {
        return Ok(None);
    };
    let Ok(json) = serde_json::to_value(&message) else {
        return Ok(None);
    };
    let id = match frame.id() {
        CanId::Standard(id) => id,
        CanId::Extended(_) => return Ok(None),
    };
    if let Some(spec) = piper_messages().into_iter().find(|m| m.id == id) {
        let fields = spec
            .signals
            .iter()
            .map(|s| {
                let value = probe_field(&json, s.field).unwrap_or(&Value::Null);
                field_of(&s.name, s.field, value)
            })
            .collect();
        return Ok(Some(DecodedFrame {
            name: spec.name,
            fields,
        }));
    }
    let (name, body) = match &json {
        Value::Object(map) if map.len() == 1 => map
            .iter()
            .next()
            .map_or(("?".to_owned(), &json), |(k, v)| (k.clone(), v)),
        _ => ("?".to_owned(), &json),
    };
    let mut fields = Vec::new();
    flatten(body, &mut fields);
    Ok(Some(DecodedFrame { name, fields }))
}

/// A field shown as written (a label, a hex word), without a unit.
pub(crate) fn text(name: &str, value: String) -> Field {
    Field {
        name: name.to_owned(),
        value,
        unit: "",
    }
}

/// A number with `places` decimals in `unit`.
pub(crate) fn num(name: &str, value: f64, places: usize, unit: &'static str) -> Field {
    Field {
        name: name.to_owned(),
        value: format!("{value:.places$}"),
        unit,
    }
}

/// Decodes a RobStride frame sent to `host_id` with the driver's codec, scaling status
/// frames with `model`'s ranges (the manual's table). `None` for frames the driver ignores.
pub fn decode_robstride(frame: &CanFrame, host_id: u8, model: Model) -> Option<DecodedFrame> {
    let ranges = model.ranges(RangeTable::Manual);
    let incoming = rs_codec::decode(frame, host_id, Duration::ZERO, |_| Some(ranges))?;
    let motor = |id: u8| num("motor", f64::from(id), 0, "");
    let (name, fields) = match incoming {
        rs_codec::Incoming::DeviceId { motor_id, uid } => (
            "DeviceId",
            vec![
                motor(motor_id),
                Field {
                    name: "uid".to_owned(),
                    value: uid.iter().map(|b| format!("{b:02X}")).collect(),
                    unit: "",
                },
            ],
        ),
        rs_codec::Incoming::Feedback(f) => (
            match f.kind {
                rs_codec::FeedbackKind::Reply => "Status",
                rs_codec::FeedbackKind::ActiveReport => "ActiveReport",
            },
            vec![
                motor(f.motor_id),
                Field {
                    name: "mode".to_owned(),
                    value: format!("{:?}", f.mode),
                    unit: "",
                },
                num("faults", f64::from(f.faults.0), 0, ""),
                num("angle", f64::from(f.angle_rad), 4, "rad"),
                num("speed", f64::from(f.speed_rad_s), 4, "rad/s"),
                num("torque", f64::from(f.torque_nm), 4, "N.m"),
                num("temperature", f64::from(f.temperature_c), 1, "degC"),
            ],
        ),
        rs_codec::Incoming::Version { motor_id, version } => (
            "Version",
            vec![
                motor(motor_id),
                Field {
                    name: "version".to_owned(),
                    value: version.map(|v| v.to_string()).join("."),
                    unit: "",
                },
            ],
        ),
        rs_codec::Incoming::Param {
            motor_id,
            ok,
            index,
            value,
        } => (
            "ReadParam",
            vec![
                motor(motor_id),
                Field {
                    name: "ok".to_owned(),
                    value: ok.to_string(),
                    unit: "",
                },
                Field {
                    name: "index".to_owned(),
                    value: format!("0x{index:04X}"),
                    unit: "",
                },
                Field {
                    name: "value_f32".to_owned(),
                    value: format!("{}", f32::from_le_bytes(value)),
                    unit: "",
                },
            ],
        ),
        rs_codec::Incoming::Fault { motor_id, report } => (
            "Fault",
            vec![
                motor(motor_id),
                Field {
                    name: "fault_word".to_owned(),
                    value: format!("0x{:08X}", report.fault_word),
                    unit: "",
                },
                Field {
                    name: "warning_word".to_owned(),
                    value: format!("0x{:08X}", report.warning_word),
                    unit: "",
                },
            ],
        ),
    };
    Some(DecodedFrame {
        name: name.to_owned(),
        fields,
    })
}

/// Decodes a frame of the RobStride MIT variant (11-bit) sent to or from a motor of `model`
/// talking to `host_id`, with the driver's MIT codec and the model's ranges (the manual's
/// table, as the driver uses). `None` for frames the driver ignores.
///
/// Host commands and the motor's Response 2 (its UID) share the motor's identifier. The
/// commands of the form `FF FF FF FF FF FF F_CMD MARKER` are shown as `MitCommand` with their
/// two bytes; any other frame there is shown as the UID reply, which an MIT setpoint
/// (command 3, packed fields) cannot be told apart from in a capture.
pub fn decode_robstride_mit(frame: &CanFrame, host_id: u8, model: Model) -> Option<DecodedFrame> {
    let data = frame.data();
    let on_motor_id = !frame.is_extended() && frame.raw_id() >> 8 == 0;
    if on_motor_id
        && frame.raw_id() != u32::from(host_id)
        && data.len() == 8
        && data[..6] == [0xFF; 6]
    {
        let byte = |name: &str, value: u8| Field {
            name: name.to_owned(),
            value: format!("0x{value:02X}"),
            unit: "",
        };
        return Some(DecodedFrame {
            name: "MitCommand".to_owned(),
            fields: vec![
                num("motor", f64::from(frame.raw_id()), 0, ""),
                byte("f_cmd", data[6]),
                byte("marker", data[7]),
            ],
        });
    }
    let ranges = model.ranges(RangeTable::Manual);
    let incoming = mit_codec::decode(frame, host_id, |_| Some(ranges))?;
    let motor = num("motor", f64::from(incoming.motor_id()), 0, "");
    let (name, fields) = match incoming {
        mit_codec::MitIncoming::Status(s) => (
            "MitStatus",
            vec![
                motor,
                text("mode", format!("{:?}", s.mode)),
                text("fault", s.fault.to_string()),
                text("warning", s.warning.to_string()),
                num("angle", f64::from(s.angle_rad), 4, "rad"),
                num("speed", f64::from(s.speed_rad_s), 4, "rad/s"),
                num("torque", f64::from(s.torque_nm), 4, "N.m"),
                num("temperature", f64::from(s.temperature_c), 1, "degC"),
            ],
        ),
        mit_codec::MitIncoming::FaultWord { word, .. } => (
            "MitFaultWord",
            vec![motor, text("fault_word", format!("0x{word:08X}"))],
        ),
        mit_codec::MitIncoming::Uid { uid, .. } => (
            "MitUid",
            vec![
                motor,
                text("uid", uid.iter().map(|b| format!("{b:02X}")).collect()),
            ],
        ),
        mit_codec::MitIncoming::Param {
            write,
            index,
            value,
            ..
        } => (
            if write {
                "MitWriteParam"
            } else {
                "MitReadParam"
            },
            vec![
                motor,
                text("index", format!("0x{index:04X}")),
                text("value_f32", format!("{}", f32::from_le_bytes(value))),
            ],
        ),
    };
    Some(DecodedFrame {
        name: name.to_owned(),
        fields,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mit_status_prints_scaled_fields_and_host_commands_are_not_decoded() {
        // Response 1 from motor 127 (RS03: ±4π rad, ±20 rad/s, ±60 N·m): angle code 0xC000,
        // three quarters up the 16-bit range (2π + 8π·(49152/65535 − 3/4) = 6.28347 rad),
        // speed and torque mid-range, run mode, 25.0 °C.
        let frame =
            CanFrame::standard(0xFD, &[0x7F, 0xC0, 0x00, 0x80, 0x08, 0x00, 0x80, 0xFA]).unwrap();
        let decoded = decode_robstride_mit(&frame, 0xFD, Model::RS03).unwrap();
        assert_eq!(decoded.name, "MitStatus");
        let value = |name: &str| {
            let field = decoded.fields.iter().find(|f| f.name == name).unwrap();
            format!("{} {}", field.value, field.unit)
        };
        assert_eq!(value("motor"), "127 ");
        assert_eq!(value("mode"), "Run ");
        assert_eq!(value("angle"), "6.2835 rad");
        assert_eq!(value("temperature"), "25.0 degC");
        // The host's enable command (marker FC) on the motor's identifier.
        let mut enable = [0xFF; 8];
        enable[7] = 0xFC;
        let command = CanFrame::standard(0x7F, &enable).unwrap();
        let decoded = decode_robstride_mit(&command, 0xFD, Model::RS03).unwrap();
        assert_eq!(decoded.name, "MitCommand");
        assert_eq!(decoded.fields[2].value, "0xFC");
        // A 29-bit frame of the private protocol is not an MIT frame.
        let ext = CanFrame::extended(0x0200_7FFD, &[0; 8]).unwrap();
        assert!(decode_robstride_mit(&ext, 0xFD, Model::RS03).is_none());
    }

    #[test]
    fn joint_feedback_prints_degrees_with_dbc_names() {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&12_345i32.to_be_bytes());
        data[4..].copy_from_slice(&(-90_000i32).to_be_bytes());
        let frame = CanFrame::standard(0x2A5, &data).unwrap();
        let decoded = decode_piper(&frame).unwrap().unwrap();
        assert_eq!(decoded.name, "JointFeedback12");
        assert_eq!(decoded.fields[0].name, "J1_angle");
        assert_eq!(decoded.fields[0].value, "12.345");
        assert_eq!(decoded.fields[0].unit, "deg");
        assert_eq!(decoded.fields[1].value, "-90.000");
    }

    #[test]
    fn arm_status_prints_the_driver_labels() {
        let frame = CanFrame::standard(0x2A1, &[1, 0, 1, 0, 0, 3, 0, 0]).unwrap();
        let decoded = decode_piper(&frame).unwrap().unwrap();
        let ctrl = &decoded.fields[0];
        assert_eq!(ctrl.name, "ctrl_mode");
        assert!(
            ctrl.value.chars().all(|c| c.is_ascii_alphabetic()),
            "{ctrl:?}"
        );
        assert_eq!(decoded.fields[5].value, "3");
    }

    #[test]
    fn malformed_frames_are_errors_not_panics() {
        let frame = CanFrame::standard(0x2A5, &[1, 2]).unwrap();
        assert!(decode_piper(&frame).is_err());
        let ext = CanFrame::extended(0x0200_01FD, &[0; 8]).unwrap();
        assert!(decode_robstride(&ext, 0xFD, Model::RS03).is_some());
        assert!(decode_robstride(&ext, 0xAA, Model::RS03).is_none());
    }
}
