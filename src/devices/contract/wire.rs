//! The protocols `armhil decode --device NAME` reads captures by, and the command's options as
//! written: kind-neutral, each kind's decoder resolving them through its own tables (models,
//! identifiers) and naming the flag that does not fit.

use std::str::FromStr;

use bus::CanFrame;

use crate::interop::DecodedFrame;

/// One motor of `armhil decode --motor ID:MODEL[:FEEDBACK_ID]`, as written: the identifier it
/// is commanded on, its model's name and, where its kind has one, the identifier it answers
/// on. Identifiers are decimal or `0x` hexadecimal; which ones a kind takes, and which model
/// names, is its decoder's to say.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WireMotor {
    /// The identifier the motor is commanded on (a RobStride CAN ID, a Damiao ESC_ID).
    pub id: u32,
    /// The model, as written (`DM4310`, `RS03`).
    pub model: String,
    /// The identifier it answers on, when given (a Damiao MST_ID).
    pub feedback_id: Option<u32>,
    /// The value as given on the command line, for messages.
    pub written: String,
}

impl WireMotor {
    /// `--motor VALUE` as the messages about it start.
    pub fn flag(&self) -> String {
        format!("`--motor {}`", self.written)
    }
}

impl FromStr for WireMotor {
    type Err = String;

    /// `ID:MODEL` or `ID:MODEL:FEEDBACK_ID`, ids in decimal or `0x` hexadecimal.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = s.split(':').collect();
        let (id, model, feedback) = match parts.as_slice() {
            [id, model] => (id, model, None),
            [id, model, feedback] => (id, model, Some(feedback)),
            _ => {
                return Err(format!(
                    "expected ID:MODEL or ID:MODEL:FEEDBACK_ID (e.g. 1:DM4310, 0x01:DM4310:0x11 or 3:RS00), got {s:?}"
                ))
            }
        };
        let model = model.trim();
        if model.is_empty() {
            return Err(format!("no model in {s:?} (ID:MODEL, e.g. 1:DM4310)"));
        }
        Ok(Self {
            id: identifier(id)?,
            model: model.to_owned(),
            feedback_id: feedback.map(|f| identifier(f)).transpose()?,
            written: s.to_owned(),
        })
    }
}

/// An identifier in decimal or `0x` hexadecimal (29 bits at most: an extended CAN id).
fn identifier(text: &str) -> Result<u32, String> {
    let text = text.trim();
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => text.parse(),
    };
    match parsed {
        Ok(id) if id <= 0x1FFF_FFFF => Ok(id),
        _ => Err(format!(
            "identifier {text:?} is not a CAN identifier (decimal or 0x hexadecimal)"
        )),
    }
}

/// The options of `armhil decode` a protocol's decoder reads, as the command line gives them
/// (`None`, empty: not given). A kind's decoder resolves them through its own tables: RobStride's
/// address replies to a host (`--host-id`) and scale values by a model's ranges (`--model`, or
/// each `--motor`'s), Damiao's name each motor's identifiers and model (`--motor`). A flag a
/// protocol cannot read is refused by name rather than ignored.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct WireOptions {
    /// `--host-id`: the id replies are addressed to.
    pub host_id: Option<u8>,
    /// `--model`: one model for every frame, as written.
    pub model: Option<String>,
    /// `--motor`: the motors on the bus, as written.
    pub motors: Vec<WireMotor>,
}

impl WireOptions {
    /// `Err` naming the first of `flags` (`"--host-id"`, `"--model"`, `"--motor"`) that was
    /// given, which `protocol` does not read; `why` says what it reads instead.
    pub fn refuse(&self, protocol: &str, flags: &[&str], why: &str) -> Result<(), String> {
        let given = |flag: &str| match flag {
            "--host-id" => self.host_id.is_some(),
            "--model" => self.model.is_some(),
            "--motor" => !self.motors.is_empty(),
            _ => false,
        };
        match flags.iter().copied().find(|flag| given(flag)) {
            Some(flag) => Err(format!(
                "`{flag}` is not read by `--device {protocol}`: {why}"
            )),
            None => Ok(()),
        }
    }
}

/// Decodes a capture's frames by one protocol: `Ok(Some(_))` names a frame and its fields,
/// `Ok(None)` is a frame the protocol does not know, `Err` says why a frame of the protocol
/// does not decode (`armhil decode` prints it beside the frame's bytes).
pub type WireDecode = Box<dyn Fn(&CanFrame) -> Result<Option<DecodedFrame>, String>>;

/// A protocol `armhil decode --device NAME` reads a capture by, when no scenario says which
/// device owns which frame. Each is registered once, by the kind that owns the protocol
/// (`KindSpec::WIRE_DECODERS`); `crate::devices::wire_decoders` lists them all.
#[derive(Debug, Clone, Copy)]
pub struct WireDecoder {
    /// Its name, the value of `--device` (`robstride-mit`).
    pub name: &'static str,
    /// One line for `armhil decode --help`.
    pub help: &'static str,
    /// The decoder, given the command's options; `Err` says which option does not fit the
    /// protocol (an unknown model, an identifier out of its range, a flag it does not read).
    pub decoder: fn(&WireOptions) -> Result<WireDecode, String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motors_parse_with_an_optional_feedback_id() {
        let m: WireMotor = "0x1A:dm4340-48v:0x30".parse().unwrap();
        assert_eq!(
            (m.id, m.model.as_str(), m.feedback_id),
            (0x1A, "dm4340-48v", Some(0x30))
        );
        assert_eq!(m.flag(), "`--motor 0x1A:dm4340-48v:0x30`");
        let m: WireMotor = "3:RS00".parse().unwrap();
        assert_eq!((m.id, m.feedback_id), (3, None));
        for bad in [
            "1",
            "1:",
            "x:DM4310",
            "1:DM4310:x",
            "1:a:2:3",
            "0x20000000:RS00",
        ] {
            assert!(bad.parse::<WireMotor>().is_err(), "{bad}");
        }
    }

    #[test]
    fn a_flag_a_protocol_does_not_read_is_named() {
        let options = WireOptions {
            model: Some("RS03".into()),
            ..WireOptions::default()
        };
        assert_eq!(
            options.refuse("x", &["--host-id", "--motor"], "why"),
            Ok(())
        );
        assert_eq!(
            options.refuse("damiao", &["--host-id", "--model"], "give --motor"),
            Err("`--model` is not read by `--device damiao`: give --motor".into())
        );
    }
}
