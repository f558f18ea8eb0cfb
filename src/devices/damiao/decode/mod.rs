//! A Damiao bus's frames named for the report's frame table (`armhil decode --scenario`), and
//! the Damiao protocol for `armhil decode --device damiao`. The decoder itself
//! ([`decode_damiao`], in `protocol.rs`) is written from the protocol note, apart from both
//! Damiao codecs.

mod protocol;

use bus::CanFrame;

pub use protocol::{decode_damiao, DamiaoWireMotor};

use super::Settings;
use crate::devices::{FrameDecoder, WireDecode, WireOptions};
use crate::interop::DecodedFrame;

/// Decodes the standard (11-bit) frames of the motors on this device's bus, commands and
/// replies, each by its own motor's model; frames on other buses, of other motors or of other
/// protocols are not this device's.
pub(crate) struct DamiaoFrames {
    /// The motors: the bus they sit on (`None`: unknown) and their identifiers and model.
    motors: Vec<(Option<String>, DamiaoWireMotor)>,
}

impl DamiaoFrames {
    /// A decoder for the motors of `settings`, on the first of `buses`.
    pub(crate) fn new(settings: &Settings, buses: &[String]) -> Self {
        let bus = buses.first().cloned();
        Self::of_motors(
            settings
                .motors
                .iter()
                .map(|m| (bus.clone(), m.esc_id, m.mst_id, m.model)),
        )
    }

    /// A decoder for these motors (bus, ESC_ID, MST_ID and the emulator's model), wherever
    /// they are listed: a Damiao bus, a robot's actuators.
    pub(crate) fn of_motors(
        motors: impl IntoIterator<Item = (Option<String>, u16, u16, sim::damiao::Model)>,
    ) -> Self {
        Self {
            motors: motors
                .into_iter()
                .filter_map(|(bus, esc_id, mst_id, model)| {
                    let model = driver::damiao::Model::parse(model.name())?;
                    Some((
                        bus,
                        DamiaoWireMotor {
                            esc_id,
                            mst_id,
                            model,
                        },
                    ))
                })
                .collect(),
        }
    }
}

impl FrameDecoder for DamiaoFrames {
    fn decode(&self, bus: Option<&str>, frame: &CanFrame) -> Option<DecodedFrame> {
        if frame.is_extended() {
            return None;
        }
        // The motors of the frame's bus: an identifier means one thing per bus. When the
        // capture does not say, every bus's, but not a motor whose identifiers another bus's
        // motor shares with other ids or another model: a guess would scale its frames by the
        // wrong ranges.
        let shares = |a: &DamiaoWireMotor, b: &DamiaoWireMotor| {
            let ids = [a.esc_id, a.mst_id];
            a != b && (ids.contains(&b.esc_id) || ids.contains(&b.mst_id))
        };
        let on_bus: Vec<DamiaoWireMotor> = match bus {
            Some(bus) => self
                .motors
                .iter()
                .filter(|(on, _)| on.as_deref() == Some(bus))
                .map(|(_, m)| *m)
                .collect(),
            None => self
                .motors
                .iter()
                .filter(|(on, m)| {
                    !self
                        .motors
                        .iter()
                        .any(|(other, n)| other != on && shares(m, n))
                })
                .map(|(_, m)| *m)
                .collect(),
        };
        if on_bus.is_empty() {
            return None;
        }
        // A register request on 0x7FF names its motor: it is this device's only when that
        // motor is one of its own.
        let decoded = decode_damiao(frame, &on_bus).ok().flatten()?;
        let own_request = frame.raw_id() != 0x7FF
            || decoded.fields.first().is_some_and(|f| {
                f.name == "motor" && on_bus.iter().any(|m| f.value == m.esc_id.to_string())
            });
        own_request.then_some(decoded)
    }
}

/// `armhil decode --device damiao`: the commands and replies of the motors `--motor` lists
/// (`1:DM4310` when none is), each scaled by its own model's ranges; a frame on one of their
/// identifiers that does not decode says why. `--model` and `--host-id` are refused: a Damiao
/// bus has a model per motor and no host id.
pub(crate) fn wire(options: &WireOptions) -> Result<WireDecode, String> {
    options.refuse(
        "damiao",
        &["--model", "--host-id"],
        "give each Damiao motor as --motor ESC_ID:MODEL[:MST_ID]",
    )?;
    let motors = if options.motors.is_empty() {
        vec![DamiaoWireMotor::DEFAULT]
    } else {
        options
            .motors
            .iter()
            .map(DamiaoWireMotor::resolve)
            .collect::<Result<Vec<_>, _>>()?
    };
    Ok(Box::new(move |frame| decode_damiao(frame, &motors)))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use bus::CanFrame;

    use super::DamiaoFrames;
    use crate::devices::{DeviceKind, FrameDecoder};
    use crate::harness::parse_scenario;

    fn bench() -> DamiaoFrames {
        let text = "bench:\n  devices:\n    dm: {kind: damiao, motors: [{id: 1, model: DM4310}, {id: 3, model: DM4340, feedback_id: 0x23}]}\nsteps:\n  - wait_ms: 1\n";
        let s = parse_scenario(Path::new("ok.yaml"), text).expect("valid");
        let DeviceKind::Damiao(settings) = &s.bench.devices[0].kind else {
            panic!("not a damiao bus");
        };
        DamiaoFrames::new(settings, &["can1".to_owned()])
    }

    /// A scenario's Damiao bus names its motors' frames by (bus, id), each by its model, and
    /// leaves other buses', other motors' and other protocols' frames to their devices.
    #[test]
    fn a_motors_frames_are_named_on_its_bus_only() {
        let decoder = bench();
        let enable =
            CanFrame::standard(0x003, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC]).unwrap();
        let named = decoder.decode(Some("can1"), &enable).expect("motor 3's");
        assert_eq!(named.name, "enable");
        assert!(decoder.decode(None, &enable).is_some());
        assert!(decoder.decode(Some("can0"), &enable).is_none());
        // Motor 3 answers on 0x23 (its feedback_id), at rest mid-range.
        let feedback =
            CanFrame::standard(0x023, &[0x13, 0x80, 0x00, 0x80, 0x08, 0x00, 25, 25]).unwrap();
        let named = decoder.decode(Some("can1"), &feedback).expect("feedback");
        assert_eq!(named.name, "feedback");
        assert!(named
            .fields
            .iter()
            .any(|f| f.name == "state" && f.value == "enabled"));
        // Motor 2 is not on this bus: neither its commands nor its register requests are ours.
        let other =
            CanFrame::standard(0x002, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC]).unwrap();
        assert!(decoder.decode(Some("can1"), &other).is_none());
        let read_2 = CanFrame::standard(0x7FF, &[0x02, 0x00, 0x33, 0x0A]).unwrap();
        assert!(decoder.decode(Some("can1"), &read_2).is_none());
        let read_1 = CanFrame::standard(0x7FF, &[0x01, 0x00, 0x33, 0x0A]).unwrap();
        assert_eq!(
            decoder.decode(Some("can1"), &read_1).map(|d| d.name),
            Some("register_read".to_owned())
        );
        let extended = CanFrame::extended(0x0200_01FD, &[0; 8]).unwrap();
        assert!(decoder.decode(None, &extended).is_none());
    }

    /// A robot's ids repeat across its buses: motor 1 is a DM8009 on can0 and a DM4310 on
    /// can1. An MIT command at t = 5 N·m to can1's motor reads 5 N·m by the DM4310's TMAX
    /// (10); by the DM8009's (54) it would read 27; a frame whose bus is unknown is left
    /// undecoded rather than scaled by a guess.
    #[test]
    fn a_frame_is_decoded_by_the_model_of_the_motor_on_its_own_bus() {
        use driver::damiao::codec::mit;
        use driver::damiao::{MitCommand, Model, RangeTable};
        let decoder = DamiaoFrames::of_motors([
            (Some("can0".to_owned()), 1, 0x11, sim::damiao::Model::DM8009),
            (Some("can1".to_owned()), 1, 0x11, sim::damiao::Model::DM4310),
            (Some("can1".to_owned()), 2, 0x12, sim::damiao::Model::DM4310),
        ]);
        let command = |esc_id| {
            mit(
                esc_id,
                &MitCommand {
                    t_ff_nm: 5.0,
                    ..MitCommand::default()
                },
                &Model::DM4310.ranges(RangeTable::Current),
            )
            .expect("a frame")
        };
        let t = |bus: Option<&str>, esc_id| {
            decoder.decode(bus, &command(esc_id)).map(|d| {
                let field = d.fields.iter().find(|f| f.name == "t").expect("t");
                field.value.parse::<f64>().expect("a number").round()
            })
        };
        assert_eq!(t(Some("can1"), 1), Some(5.0));
        assert_eq!(t(Some("can0"), 1), Some(27.0));
        assert_eq!(t(None, 1), None);
        // Motor 2 is on one bus only: known wherever the capture was made.
        assert_eq!(t(None, 2), Some(5.0));
    }
}
