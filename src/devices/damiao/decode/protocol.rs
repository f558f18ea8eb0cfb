//! Damiao (DM) frames both ways, named with their fields in units (docs/protocols/damiao.md):
//! the host's commands (the special commands, MIT, position-velocity, velocity,
//! force-position, register read/write/save, refresh) and the motors' replies (feedback,
//! register replies).
//!
//! Written from the protocol note, apart from both codecs (`sim::damiao::codec` and
//! `driver::damiao::codec` are never called here): the identifiers, the bit packing and the
//! scaling are this file's own, checked against the shared vectors in `fixtures/damiao/`
//! (`tests/integration/decode_cli.rs`). The models' ranges and the register names and types
//! are the driver's tables (`driver::damiao::{Model, Register}`), as the RobStride decoder
//! takes its parameter table from the driver.
//!
//! One 11-bit identifier can mean different things on different buses (a motor's MST_ID may
//! be another's ESC_ID, and MIT frames carry no model), so a frame is decoded for the motors
//! the decoder is told about ([`DamiaoWireMotor`]); register requests on 0x7FF name their
//! motor themselves and are decoded for any.

use bus::CanFrame;
use driver::damiao::{Model, RangeTable, Register, RegisterKind};

use crate::devices::WireMotor;
use crate::interop::{num, text, DecodedFrame, Field};

/// Position-velocity commands: `POS_VEL + ESC_ID` (note §2).
const POS_VEL: u16 = 0x100;
/// Velocity commands: `VELOCITY + ESC_ID`.
const VELOCITY: u16 = 0x200;
/// Force-position commands: `FORCE_POS + ESC_ID`.
const FORCE_POS: u16 = 0x300;
/// Register requests and refresh, for every motor.
const REGISTER: u16 = 0x7FF;
/// The register operations (D2, note §6.1).
const READ: u8 = 0x33;
const WRITE: u8 = 0x55;
const SAVE: u8 = 0xAA;
const REFRESH: u8 = 0xCC;
/// MIT gains map over 0..=500 (kp) and 0..=5 (kd) on every model (note §3.1).
const KP_MAX: f64 = 500.0;
const KD_MAX: f64 = 5.0;

/// One Damiao motor whose frames a capture holds: the identifier it takes commands on, the
/// one it answers on, and its model (whose ranges scale MIT commands and feedback).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DamiaoWireMotor {
    /// Command identifier (ESC_ID).
    pub esc_id: u16,
    /// Feedback identifier (MST_ID).
    pub mst_id: u16,
    /// Model.
    pub model: Model,
}

impl DamiaoWireMotor {
    /// The motor `armhil sim damiao` serves by default: ESC_ID 1, a DM4310, answering on 0x11.
    pub const DEFAULT: Self = Self {
        esc_id: 1,
        mst_id: 0x11,
        model: Model::DM4310,
    };
}

impl DamiaoWireMotor {
    /// `--motor ID:MODEL[:FEEDBACK_ID]` as a Damiao motor: the ESC_ID, a model of the driver's
    /// table (any case, `-48V` or `_48V`) and the MST_ID (ESC_ID + 0x10, the OpenArm's
    /// convention, when not given); ids 11 bits, below the register identifier 0x7FF. An error
    /// starts with the flag as given.
    pub fn resolve(motor: &WireMotor) -> Result<Self, String> {
        let flag = motor.flag();
        let esc_id = id(motor.id).map_err(|e| format!("{flag}: ESC_ID {e}"))?;
        let model = Model::parse(&motor.model).ok_or_else(|| {
            let known: Vec<String> = Model::ALL.iter().map(|m| format!("{m:?}")).collect();
            let names: Vec<&str> = known.iter().map(String::as_str).collect();
            format!(
                "{flag}: unknown Damiao model `{}`; expected one of: {}{}",
                motor.model,
                known.join(", "),
                sim::yaml_words::suggestion(&motor.model.to_ascii_uppercase(), &names)
            )
        })?;
        let mst_id = match motor.feedback_id {
            Some(mst) => id(mst).map_err(|e| format!("{flag}: MST_ID {e}"))?,
            None => esc_id
                .checked_add(0x10)
                .filter(|&m| m < REGISTER)
                .ok_or_else(|| {
                    format!("{flag}: ESC_ID 0x{esc_id:X} + 0x10 is past 0x7FE: give the MST_ID (ID:MODEL:MST_ID)")
                })?,
        };
        Ok(Self {
            esc_id,
            mst_id,
            model,
        })
    }
}

/// An 11-bit identifier below the register identifier 0x7FF (which carries every motor's
/// register requests).
fn id(value: u32) -> Result<u16, String> {
    match u16::try_from(value) {
        Ok(id) if id < REGISTER => Ok(id),
        _ => Err(format!("0x{value:X} out of range, expected 0..=0x7FE")),
    }
}

/// Decodes one frame of a Damiao bus holding `motors`: `Ok(Some)` names it and its fields,
/// `Ok(None)` is a frame of none of them (or of another protocol), `Err` says why a frame on
/// one of their identifiers does not decode (too short for its layout).
pub fn decode_damiao(
    frame: &CanFrame,
    motors: &[DamiaoWireMotor],
) -> Result<Option<DecodedFrame>, String> {
    if frame.is_extended() {
        return Ok(None);
    }
    // Standard identifiers are 11 bits: the cast is exact.
    let id = frame.raw_id() as u16;
    let d = frame.data();
    if id == REGISTER {
        return register_request(d).map(Some);
    }
    for m in motors {
        if id == m.mst_id {
            // Another motor's feedback on a shared MST_ID (its ESC_ID nibble in D0) is left
            // to that motor.
            if let Some(reply) = reply(m, d)? {
                return Ok(Some(reply));
            }
        } else if id == m.esc_id {
            return special_or_mit(m, d).map(Some);
        } else if id == m.esc_id + POS_VEL {
            let d = exactly::<8>("position-velocity command", d)?;
            return Ok(Some(named(
                "pos_vel",
                m,
                vec![
                    num("p", f64::from(f32_le(d, 0)), 4, "rad"),
                    num("v", f64::from(f32_le(d, 4)), 4, "rad/s"),
                ],
            )));
        } else if id == m.esc_id + VELOCITY {
            if d.len() < 4 {
                return Err(short("velocity command", 4, d.len()));
            }
            return Ok(Some(named(
                "velocity",
                m,
                vec![num("v", f64::from(f32_le(d, 0)), 4, "rad/s")],
            )));
        } else if id == m.esc_id + FORCE_POS {
            let d = exactly::<8>("force-position command", d)?;
            let v_raw = u16::from_le_bytes([d[4], d[5]]);
            let i_raw = u16::from_le_bytes([d[6], d[7]]);
            return Ok(Some(named(
                "force_pos",
                m,
                vec![
                    num("p", f64::from(f32_le(d, 0)), 4, "rad"),
                    num("v", f64::from(v_raw) / 100.0, 2, "rad/s"),
                    num("i", f64::from(i_raw) / 10_000.0, 4, ""),
                ],
            )));
        }
    }
    Ok(None)
}

/// A frame of `len` bytes is too short for `what`, which needs `need`.
fn short(what: &str, need: usize, len: usize) -> String {
    format!("a {what} needs {need} bytes, got {len}")
}

/// The payload as exactly `N` bytes (the layouts of note §3–§5 are 8).
fn exactly<'a, const N: usize>(what: &str, d: &'a [u8]) -> Result<&'a [u8; N], String> {
    d.try_into().map_err(|_| {
        if d.len() < N {
            short(what, N, d.len())
        } else {
            format!("a {what} has {N} bytes, got {}", d.len())
        }
    })
}

/// The f32 little-endian at `at` (the caller checked the length).
fn f32_le(d: &[u8], at: usize) -> f32 {
    f32::from_le_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]])
}

/// `u`, an unsigned `bits`-bit code, over `[min, max]`: `u·(max − min)/(2^bits − 1) + min`.
fn scaled(u: u16, min: f64, max: f64, bits: u32) -> f64 {
    f64::from(u) * (max - min) / f64::from((1u32 << bits) - 1) + min
}

/// A decoded frame of motor `m`: `motor` (its ESC_ID) first.
fn named(name: &str, m: &DamiaoWireMotor, mut fields: Vec<Field>) -> DecodedFrame {
    fields.insert(0, motor_field(m.esc_id));
    DecodedFrame {
        name: name.to_owned(),
        fields,
    }
}

fn motor_field(esc_id: u16) -> Field {
    num("motor", f64::from(esc_id), 0, "")
}

/// On ESC_ID: `FF ×7` and a known code is a special command; any other 8 bytes an MIT command.
fn special_or_mit(m: &DamiaoWireMotor, d: &[u8]) -> Result<DecodedFrame, String> {
    let d = exactly::<8>("command on ESC_ID", d)?;
    if d[..7] == [0xFF; 7] {
        let special = match d[7] {
            0xFC => Some("enable"),
            0xFD => Some("disable"),
            0xFE => Some("set_zero"),
            0xFB => Some("clear_error"),
            _ => None,
        };
        if let Some(name) = special {
            return Ok(named(name, m, Vec::new()));
        }
    }
    let r = m.model.ranges(RangeTable::Current);
    let (pmax, vmax, tmax) = (f64::from(r.pmax), f64::from(r.vmax), f64::from(r.tmax));
    let p = u16::from_be_bytes([d[0], d[1]]);
    let v = (u16::from(d[2]) << 4) | u16::from(d[3] >> 4);
    let kp = (u16::from(d[3] & 0x0F) << 8) | u16::from(d[4]);
    let kd = (u16::from(d[5]) << 4) | u16::from(d[6] >> 4);
    let t = (u16::from(d[6] & 0x0F) << 8) | u16::from(d[7]);
    Ok(named(
        "mit",
        m,
        vec![
            num("p", scaled(p, -pmax, pmax, 16), 4, "rad"),
            num("v", scaled(v, -vmax, vmax, 12), 4, "rad/s"),
            num("kp", scaled(kp, 0.0, KP_MAX, 12), 4, ""),
            num("kd", scaled(kd, 0.0, KD_MAX, 12), 4, ""),
            num("t", scaled(t, -tmax, tmax, 12), 4, "N.m"),
        ],
    ))
}

/// The name of a feedback frame's state nibble (note §5).
fn state_name(nibble: u8) -> String {
    match nibble {
        0x0 => "disabled".to_owned(),
        0x1 => "enabled".to_owned(),
        0x8 => "over_voltage".to_owned(),
        0x9 => "under_voltage".to_owned(),
        0xA => "over_current".to_owned(),
        0xB => "mos_over_temperature".to_owned(),
        0xC => "rotor_over_temperature".to_owned(),
        0xD => "communication_lost".to_owned(),
        0xE => "overload".to_owned(),
        other => format!("0x{other:X}"),
    }
}

/// On MST_ID: a register reply (D0..D1 the ESC_ID, D2 0x33 or 0x55) or a feedback frame with
/// the ESC_ID's low nibble in D0; `None` for another motor's feedback.
fn reply(m: &DamiaoWireMotor, d: &[u8]) -> Result<Option<DecodedFrame>, String> {
    let d = exactly::<8>("reply on MST_ID", d)?;
    let [lo, hi] = m.esc_id.to_le_bytes();
    if d[0] == lo && d[1] == hi && (d[2] == READ || d[2] == WRITE) {
        let name = if d[2] == READ {
            "register_read_reply"
        } else {
            "register_write_reply"
        };
        return Ok(Some(named(name, m, register_fields(d[3], Some(&d[4..])))));
    }
    if u16::from(d[0] & 0x0F) != m.esc_id & 0x0F {
        return Ok(None);
    }
    let r = m.model.ranges(RangeTable::Current);
    let (pmax, vmax, tmax) = (f64::from(r.pmax), f64::from(r.vmax), f64::from(r.tmax));
    let p = u16::from_be_bytes([d[1], d[2]]);
    let v = (u16::from(d[3]) << 4) | u16::from(d[4] >> 4);
    let t = (u16::from(d[4] & 0x0F) << 8) | u16::from(d[5]);
    Ok(Some(named(
        "feedback",
        m,
        vec![
            text("state", state_name(d[0] >> 4)),
            num("p", scaled(p, -pmax, pmax, 16), 4, "rad"),
            num("v", scaled(v, -vmax, vmax, 12), 4, "rad/s"),
            num("t", scaled(t, -tmax, tmax, 12), 4, "N.m"),
            num("mos", f64::from(d[6]), 0, "degC"),
            num("rotor", f64::from(d[7]), 0, "degC"),
        ],
    )))
}

/// `reg` (its name, or its RID when the table has none) and, when given, `value` read as the
/// register's type.
fn register_fields(rid: u8, value: Option<&[u8]>) -> Vec<Field> {
    let register = Register::from_rid(rid);
    let mut fields = vec![text(
        "reg",
        register.map_or_else(|| rid.to_string(), |r| r.name().to_owned()),
    )];
    if let Some(&[a, b, c, d]) = value {
        let bytes = [a, b, c, d];
        let shown = match RegisterKind::of_rid(rid) {
            RegisterKind::U32 => u32::from_le_bytes(bytes).to_string(),
            RegisterKind::F32 => f32::from_le_bytes(bytes).to_string(),
        };
        fields.push(text("value", shown));
    }
    fields
}

/// A request on 0x7FF: D0..D1 the motor's ESC_ID, D2 the operation, D3 the RID, D4..D7 the
/// value of a write.
fn register_request(d: &[u8]) -> Result<DecodedFrame, String> {
    if d.len() < 3 {
        return Err(short("register request", 3, d.len()));
    }
    let esc_id = u16::from_le_bytes([d[0], d[1]]);
    let op = d[2];
    let need = match op {
        READ => 4,
        WRITE => 8,
        _ => 3,
    };
    if d.len() < need {
        return Err(short("register request", need, d.len()));
    }
    let (name, fields) = match op {
        READ => ("register_read", register_fields(d[3], None)),
        WRITE => ("register_write", register_fields(d[3], Some(&d[4..8]))),
        SAVE => ("register_save", Vec::new()),
        REFRESH => ("refresh", Vec::new()),
        other => (
            "register_request",
            vec![text("op", format!("0x{other:02X}"))],
        ),
    };
    let mut all = vec![motor_field(esc_id)];
    all.extend(fields);
    Ok(DecodedFrame {
        name: name.to_owned(),
        fields: all,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const MOTORS: [DamiaoWireMotor; 2] = [
        DamiaoWireMotor::DEFAULT,
        DamiaoWireMotor {
            esc_id: 3,
            mst_id: 0x13,
            model: Model::DM4340,
        },
    ];

    fn decode(id: u16, data: &[u8]) -> Result<Option<DecodedFrame>, String> {
        decode_damiao(&CanFrame::standard(id, data).unwrap(), &MOTORS)
    }

    /// `name  field=value unit …`, as `armhil decode` prints it.
    fn line(id: u16, data: &[u8]) -> String {
        let d = decode(id, data).unwrap().expect("decoded");
        let mut out = d.name;
        for f in d.fields {
            out.push_str(&format!(" {}={}", f.name, f.value));
            if !f.unit.is_empty() {
                out.push_str(&format!(" {}", f.unit));
            }
        }
        out
    }

    #[test]
    fn commands_and_replies_read_by_the_note() {
        // fixtures/damiao: enable, mit_positive, mit_dm4340 (VMAX 10), pos_vel, velocity_dlc4,
        // force_pos, reg_read_ctrl_mode and its reply, fb_enabled, fb_dm4340.
        assert_eq!(
            line(0x001, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC]),
            "enable motor=1"
        );
        assert_eq!(
            line(0x001, &[0x8A, 0x3C, 0x89, 0x51, 0x99, 0x3D, 0x69, 0x32]),
            "mit motor=1 p=0.9997 rad v=2.1905 rad/s kp=49.9389 kd=1.1990 t=1.4969 N.m"
        );
        let dm4340 = line(0x003, &[0x85, 0x1E, 0xBF, 0xF2, 0x3D, 0x6B, 0x78, 0xDA]);
        assert!(dm4340.contains(" v=4.9988 rad/s"), "{dm4340}");
        assert_eq!(
            line(0x101, &[0x00, 0x00, 0xC0, 0x3F, 0x00, 0x00, 0x00, 0x40]),
            "pos_vel motor=1 p=1.5000 rad v=2.0000 rad/s"
        );
        assert_eq!(
            line(0x201, &[0x00, 0x00, 0xA0, 0x40]),
            "velocity motor=1 v=5.0000 rad/s"
        );
        assert_eq!(
            line(0x301, &[0x00, 0x00, 0x80, 0x3F, 0xF4, 0x01, 0x88, 0x13]),
            "force_pos motor=1 p=1.0000 rad v=5.00 rad/s i=0.5000"
        );
        assert_eq!(
            line(0x7FF, &[0x01, 0x00, 0x33, 0x0A, 0, 0, 0, 0]),
            "register_read motor=1 reg=CTRL_MODE"
        );
        assert_eq!(
            line(0x011, &[0x01, 0x00, 0x33, 0x0A, 0x01, 0, 0, 0]),
            "register_read_reply motor=1 reg=CTRL_MODE value=1"
        );
        assert_eq!(
            line(0x7FF, &[0x01, 0x00, 0x55, 0x01, 0x85, 0xEB, 0x71, 0x3F]),
            "register_write motor=1 reg=KT_Value value=0.945"
        );
        assert_eq!(
            line(0x7FF, &[0x01, 0x00, 0xCC, 0, 0, 0, 0, 0]),
            "refresh motor=1"
        );
        assert_eq!(
            line(0x011, &[0x11, 0x9C, 0x40, 0xBB, 0x89, 0xC4, 0x20, 0x1E]),
            "feedback motor=1 state=enabled p=2.7590 rad v=13.9560 rad/s t=2.2100 N.m \
             mos=32 degC rotor=30 degC"
        );
        let fb = line(0x013, &[0x13, 0x8C, 0xA0, 0xDA, 0xC3, 0xE8, 0x28, 0x26]);
        assert!(
            fb.contains("motor=3 state=enabled p=1.2331 rad v=7.0940 rad/s"),
            "{fb}"
        );
    }

    #[test]
    fn other_motors_frames_and_short_frames_are_told_apart() {
        // Feedback of ESC_ID 2 on motor 1's MST_ID: not motor 1's (its nibble).
        assert_eq!(decode(0x011, &[0x12, 0, 0, 0, 0, 0, 25, 25]), Ok(None));
        // An id no listed motor uses, and a 29-bit frame.
        assert_eq!(decode(0x002, &[0xFF; 8]), Ok(None));
        let ext = CanFrame::extended(0x001, &[0xFF; 8]).unwrap();
        assert_eq!(decode_damiao(&ext, &MOTORS), Ok(None));
        // On a motor's identifiers, a short payload says what it lacks.
        assert_eq!(
            decode(0x001, &[0xFF; 3]),
            Err("a command on ESC_ID needs 8 bytes, got 3".into())
        );
        assert_eq!(
            decode(0x7FF, &[0x01, 0x00, 0x55, 0x0A]),
            Err("a register request needs 8 bytes, got 4".into())
        );
        assert_eq!(
            decode(0x201, &[0, 0]),
            Err("a velocity command needs 4 bytes, got 2".into())
        );
        // Unnamed registers and operations, and undocumented states, are shown by number.
        assert_eq!(
            line(0x7FF, &[0x02, 0x00, 0x33, 37]),
            "register_read motor=2 reg=37"
        );
        assert_eq!(
            line(0x7FF, &[0x02, 0x00, 0x12]),
            "register_request motor=2 op=0x12"
        );
        let odd = line(0x011, &[0x51, 0, 0, 0, 0, 0, 0, 0]);
        assert!(odd.contains("state=0x5"), "{odd}");
    }

    #[test]
    fn motors_resolve_with_an_optional_mst_id() {
        let resolve = |text: &str| {
            let motor: WireMotor = text.parse().map_err(|e: String| e)?;
            DamiaoWireMotor::resolve(&motor)
        };
        assert_eq!(resolve("1:DM4310"), Ok(DamiaoWireMotor::DEFAULT));
        assert_eq!(
            resolve("0x1A:dm4340-48v:0x30"),
            Ok(DamiaoWireMotor {
                esc_id: 0x1A,
                mst_id: 0x30,
                model: Model::DM4340_48V,
            })
        );
        for bad in [
            "1",
            "1:DM9999",
            "0x800:DM4310",
            "0x7FF:DM4310",
            "0x7F0:DM4310",
            "1:DM4310:x",
            "1:DM4310:0x7FF",
        ] {
            assert!(resolve(bad).is_err(), "{bad}");
        }
        let e = resolve("1:DM431").unwrap_err();
        assert!(
            e.starts_with(
                "`--motor 1:DM431`: unknown Damiao model `DM431`; expected one of: DM3507"
            ) && e.ends_with("did you mean `DM4310`?"),
            "{e}"
        );
    }
}
