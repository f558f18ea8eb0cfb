//! Device kinds: one folder per kind, registered once, in `device_kinds!` below.
//!
//! What a kind provides is the `KindSpec` trait in [`contract`] (its scenario vocabulary,
//! how it is built on a bench, its URDF and frame decoder for the views, the protocols
//! `armhil decode --device` reads by) and the [`Device`] it builds; the registry generates the
//! enums the harness holds (`DeviceKind`, `Action`, `Check`, `DeviceFault`), the list of
//! protocols ([`wire_decoders`]) and dispatches every call through the trait. The folder layout of a
//! kind is in `docs/architecture.md`.

use std::sync::Arc;

use serde::de::{Deserialize, Deserializer, Error as _, MapAccess, Visitor};

use crate::scenario::onekey::OneKey;
use crate::scenario::read_in::KindSet;
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};

pub mod contract;
pub(crate) use contract::{named_bus, one_bus, within, FirstOf, KindSpec, RawKindStep, Wiring};
pub use contract::{
    BaseColumns, BusUse, Device, DeviceError, Drawing, FrameDecoder, JointColumn, Posing, Reply,
    TraceColumn, WireDecode, WireDecoder, WireMotor, WireOptions,
};

pub mod actuator_group;
pub mod arm;
pub mod damiao;
pub mod piper;
pub mod realman;
pub mod robstride;

/// `Err` naming the first quantity of an emulator's physical state that is not finite: the
/// physics diverged (NaN, which the wire carries as zeros, an arm seemingly at rest at 0°).
/// Each kind's [`Device::emulator_health`] passes its emulator's state through this.
pub(crate) fn finite_state<'a>(
    quantities: impl IntoIterator<Item = (String, f64)> + 'a,
) -> Result<(), String> {
    match quantities.into_iter().find(|(_, v)| !v.is_finite()) {
        None => Ok(()),
        Some((name, value)) => Err(format!(
            "the emulator's physics diverged ({name} is {value}); its state is no longer valid (a fault value far beyond what the model can take?)"
        )),
    }
}

/// Register device kinds: `"name" => Variant(module)`. Everything below is generated from this
/// list; nothing else in the crate lists device kinds.
macro_rules! device_kinds {
    ($( $name:literal => $variant:ident($module:ident) ),* $(,)?) => {
        // Each registration line's name is its kind's `KindSpec::NAME`.
        $( const _: () = assert!(
            same_text($name, <$module::Kind as KindSpec>::NAME),
            concat!("`", $name, "` is registered under another name than its KindSpec::NAME")
        ); )*

        /// The scenario names of every device kind.
        pub const KIND_NAMES: &[&str] = &[$($name),*];

        /// Every kind's `KindSpec::WIRE_DECODERS`, in registration order.
        const WIRE_DECODER_LISTS: &[&[WireDecoder]] = &[$( <$module::Kind as KindSpec>::WIRE_DECODERS, )*];

        // Each protocol is registered once: by the kind that owns it.
        const _: () = assert!(
            distinct_wire_names(WIRE_DECODER_LISTS),
            "two `decode --device` protocols of the same name (a kind that speaks another's protocol registers none)"
        );

        /// A device's kind and validated settings.
        #[derive(Debug, Clone, PartialEq)]
        pub enum DeviceKind {
            $( #[doc = concat!("`kind: ", $name, "`")] $variant($module::Settings), )*
        }

        /// A validated device action (a step addressed to one device).
        #[derive(Debug, Clone, PartialEq)]
        pub enum Action {
            $( #[doc = concat!("A ", $name, " action.")] $variant($module::Action), )*
        }

        /// A validated condition on a device's state.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Check {
            $( #[doc = concat!("A ", $name, " condition.")] $variant($module::Check), )*
        }

        /// A validated emulator fault of a device.
        #[derive(Debug, Clone, PartialEq)]
        pub enum DeviceFault {
            $( #[doc = concat!("A ", $name, " emulator fault.")] $variant($module::Fault), )*
        }

        impl DeviceKind {
            /// The kind's name as written in scenarios.
            pub fn name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }

            /// What this device's settings need from the in-process emulator.
            pub fn in_process_requirements(&self, device: &str) -> Vec<String> {
                match self { $( Self::$variant(s) => <$module::Kind as KindSpec>::in_process_requirements(s, device), )* }
            }

            /// The names of the device's parts that steps address (a group's joints).
            pub fn parts(&self) -> Vec<String> {
                match self { $( Self::$variant(s) => <$module::Kind as KindSpec>::parts(s), )* }
            }

            /// The actuator behind each part, in `parts` order (`KindSpec::part_actuators`).
            pub fn part_actuators(&self) -> Vec<sim::actuator::ActuatorModel> {
                match self { $( Self::$variant(s) => <$module::Kind as KindSpec>::part_actuators(s), )* }
            }

            /// The CAN buses the device sits on (`KindSpec::buses`); `at` is its entry.
            pub fn buses(&self, at: Pos) -> Vec<BusUse> {
                match self { $( Self::$variant(s) => <$module::Kind as KindSpec>::buses(s, at), )* }
            }

            /// How the 3D views draw this device (`KindSpec::drawing`).
            pub fn drawing(&self) -> Option<Drawing> {
                match self { $( Self::$variant(s) => <$module::Kind as KindSpec>::drawing(s), )* }
            }

            /// A decoder of this device's CAN frames for reports, if it speaks CAN; `buses`
            /// names its buses on the bench, in the order [`Self::buses`] lists them.
            pub fn frame_decoder(&self, buses: &[String]) -> Option<Arc<dyn FrameDecoder>> {
                match self { $( Self::$variant(s) => <$module::Kind as KindSpec>::frame_decoder(s, buses), )* }
            }

            /// Start the device (emulator when in-process, and driver).
            pub(crate) async fn build(
                &self,
                device: &str,
                wiring: &Wiring<'_>,
            ) -> Result<Arc<dyn Device>, String> {
                match self { $( Self::$variant(s) => <$module::Kind as KindSpec>::build(device, s, wiring).await, )* }
            }
        }

        impl Action {
            /// The device kind this action belongs to.
            pub fn kind_name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }

            /// Why this action needs the in-process emulator, if it does.
            pub fn needs_emulator(&self) -> Option<String> {
                match self { $( Self::$variant(a) => <$module::Kind as KindSpec>::action_needs_emulator(a), )* }
            }
        }

        impl Check {
            /// The device kind this condition belongs to.
            pub fn kind_name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }

            /// What the condition wants, for reports.
            pub fn describe(&self) -> String {
                match self { $( Self::$variant(c) => <$module::Kind as KindSpec>::describe_check(c), )* }
            }
        }

        impl DeviceFault {
            /// The device kind this fault belongs to.
            pub fn kind_name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }

            /// Short description for logs and reports.
            pub fn describe(&self) -> String {
                match self { $( Self::$variant(f) => <$module::Kind as KindSpec>::describe_fault(f), )* }
            }
        }

        /// A device entry of the bench as written: `kind:` first, then the kind's settings.
        #[derive(Debug)]
        pub(crate) enum RawDevice {
            $( $variant(Box<<$module::Kind as KindSpec>::RawSettings>), )*
        }

        impl RawDevice {
            /// The kind's name.
            pub(crate) fn kind_name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }
        }

        fn read_settings<'de, A: MapAccess<'de>>(kind: &str, map: A) -> Result<RawDevice, A::Error> {
            let rest = serde::de::value::MapAccessDeserializer::new(map);
            match kind {
                $( $name => Ok(RawDevice::$variant(Box::new(Deserialize::deserialize(rest)?))), )*
                other => Err(crate::scenario::onekey::unknown("device kind", other, KIND_NAMES)),
            }
        }

        /// A step of some device kind (the key decides which: the first kind that knows it).
        #[derive(Debug)]
        pub(crate) enum RawDeviceStep {
            $( $variant(Box<<$module::Kind as KindSpec>::RawStep>), )*
        }

        impl OneKey for RawDeviceStep {
            const WHAT: &'static str = "step";
            fn keys(kinds: KindSet) -> Vec<&'static str> {
                let mut keys = Vec::new();
                $( if on_bench($name, kinds) { keys.extend(<<$module::Kind as KindSpec>::RawStep as OneKey>::keys(kinds)); } )*
                keys
            }
            fn bare<E: serde::de::Error>(key: &str, kinds: KindSet) -> Option<Result<Self, E>> {
                $( if let Some(key) = for_kind($name, key, kinds) {
                    if let Some(r) = <<$module::Kind as KindSpec>::RawStep as OneKey>::bare(key, kinds) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
            fn entry<'de, A: MapAccess<'de>>(key: &str, map: &mut A, kinds: KindSet) -> Option<Result<Self, A::Error>> {
                $( if let Some(key) = for_kind($name, key, kinds) {
                    if let Some(r) = <<$module::Kind as KindSpec>::RawStep as OneKey>::entry(key, map, kinds) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
        }

        impl RawDeviceStep {
            /// The step's `id:`.
            pub(crate) fn id(&self) -> Option<&S<String>> {
                match self { $( Self::$variant(s) => RawKindStep::id(s.as_ref()), )* }
            }
        }

        /// An emulator fault of some device kind, as written.
        #[derive(Debug)]
        pub(crate) enum RawDeviceFault {
            $( $variant(Box<<$module::Kind as KindSpec>::RawFault>), )*
        }

        impl OneKey for RawDeviceFault {
            const WHAT: &'static str = "fault";
            fn keys(kinds: KindSet) -> Vec<&'static str> {
                let mut keys = Vec::new();
                $( if on_bench($name, kinds) { keys.extend(<<$module::Kind as KindSpec>::RawFault as OneKey>::keys(kinds)); } )*
                keys
            }
            fn bare<E: serde::de::Error>(key: &str, kinds: KindSet) -> Option<Result<Self, E>> {
                $( if let Some(key) = for_kind($name, key, kinds) {
                    if let Some(r) = <<$module::Kind as KindSpec>::RawFault as OneKey>::bare(key, kinds) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
            fn entry<'de, A: MapAccess<'de>>(key: &str, map: &mut A, kinds: KindSet) -> Option<Result<Self, A::Error>> {
                $( if let Some(key) = for_kind($name, key, kinds) {
                    if let Some(r) = <<$module::Kind as KindSpec>::RawFault as OneKey>::entry(key, map, kinds) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
        }

        /// Conditions of some device kind, as written.
        #[derive(Debug)]
        pub(crate) enum RawDeviceConds {
            $( $variant(Box<<$module::Kind as KindSpec>::RawConds>), )*
        }

        /// Index of a kind in registration order.
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub(crate) struct KindIndex(usize);

        impl RawDeviceConds {
            /// Every condition key of the kinds in `kinds`.
            pub(crate) fn keys(kinds: KindSet) -> Vec<&'static str> {
                let mut keys = Vec::new();
                $( if on_bench($name, kinds) { keys.extend(<$module::Kind as KindSpec>::CONDITION_KEYS); } )*
                keys
            }

            /// The first kind among `kinds` whose conditions include `key`, or the kind a
            /// qualified `kind.key` names (how a bench of two kinds that share a condition key,
            /// `motors` of RobStride and Damiao, picks the other one).
            pub(crate) fn kind_of_key(key: &str, kinds: KindSet) -> Option<KindIndex> {
                let tables: &[(&str, &[&str])] = &[$( ($name, <$module::Kind as KindSpec>::CONDITION_KEYS) ),*];
                tables
                    .iter()
                    .position(|(kind, keys)| for_kind(kind, key, kinds).is_some_and(|k| keys.contains(&k)))
                    .map(KindIndex)
            }

            /// Read the conditions of kind `kind` from `de`.
            pub(crate) fn read<'de, D: Deserializer<'de>>(kind: KindIndex, de: D) -> Result<Self, D::Error> {
                let readers: &[fn(D) -> Result<Self, D::Error>] = &[$(
                    |d| Ok(Self::$variant(Box::new(Deserialize::deserialize(d)?)))
                ),*];
                readers[kind.0](de)
            }
        }

        /// Layer 2 of a device entry.
        pub(crate) fn validate_settings(ctx: &Ctx<'_>, raw: &S<RawDevice>) -> Res<DeviceKind> {
            let at = Pos::from_location(&raw.referenced);
            match &raw.value {
                $( RawDevice::$variant(r) => Ok(DeviceKind::$variant(<$module::Kind as KindSpec>::validate_settings(ctx, r, at)?)), )*
            }
        }

        /// Layer 2 of a device step: its label and action.
        pub(crate) fn validate_step(ctx: &Ctx<'_>, raw: &RawDeviceStep, at: Pos) -> Res<(&'static str, DeviceStep<Action>)> {
            match raw {
                $( RawDeviceStep::$variant(r) => {
                    let (label, step) = <$module::Kind as KindSpec>::validate_step(ctx, r, at)?;
                    Ok((label, DeviceStep {
                        device: step.device,
                        action: Action::$variant(step.action),
                        timeout: step.timeout,
                        expect_error: step.expect_error,
                    }))
                } )*
            }
        }

        /// Layer 2 of device conditions.
        pub(crate) fn validate_checks(ctx: &Ctx<'_>, raw: &RawDeviceConds, device: usize, step: &str, at: Pos) -> Res<Vec<Check>> {
            match raw {
                $( RawDeviceConds::$variant(r) => Ok(<$module::Kind as KindSpec>::validate_checks(ctx, r, device, step, at)?
                    .into_iter().map(Check::$variant).collect()), )*
            }
        }

        /// Layer 2 of a device fault.
        pub(crate) fn validate_fault(ctx: &Ctx<'_>, raw: &RawDeviceFault, device: Option<usize>, at: Pos) -> Res<DeviceFault> {
            match raw {
                $( RawDeviceFault::$variant(r) => Ok(DeviceFault::$variant(<$module::Kind as KindSpec>::validate_fault(ctx, r, device, at)?)), )*
            }
        }
    };
}

/// `a == b` where the compiler can evaluate it: how a registry line is checked against its
/// kind's `NAME` (this one, and `armhil sim`'s served kinds).
pub const fn same_text(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Every protocol `armhil decode --device NAME` reads captures by: each registered kind's own
/// (`KindSpec::WIRE_DECODERS`), in registration order, each name once.
pub fn wire_decoders() -> impl Iterator<Item = &'static WireDecoder> {
    WIRE_DECODER_LISTS.iter().flat_map(|list| list.iter())
}

/// Whether no two protocols of `lists` share a name (checked when the crate compiles).
const fn distinct_wire_names(lists: &[&[WireDecoder]]) -> bool {
    let mut a = 0;
    while a < lists.len() {
        let mut i = 0;
        while i < lists[a].len() {
            let mut b = a;
            while b < lists.len() {
                let mut j = if b == a { i + 1 } else { 0 };
                while j < lists[b].len() {
                    if same_text(lists[a][i].name, lists[b][j].name) {
                        return false;
                    }
                    j += 1;
                }
                b += 1;
            }
            i += 1;
        }
        a += 1;
    }
    true
}

/// A condition key as its kind reads it: `motors` of a qualified `damiao.motors`.
pub(crate) fn unqualified(key: &str) -> &str {
    key.split_once('.').map_or(key, |(_, rest)| rest)
}

/// The kinds named `names` (the kinds on a bench), for reading its steps, faults and
/// conditions: keys two kinds share (`under_voltage`, `enable`) then go to the one on the bench.
pub(crate) fn kinds_named<'a>(names: impl IntoIterator<Item = &'a str>) -> KindSet {
    KindSet::of(
        names
            .into_iter()
            .filter_map(|name| KIND_NAMES.iter().position(|k| *k == name)),
    )
}

/// Whether `kind` is among `kinds`.
fn on_bench(kind: &str, kinds: KindSet) -> bool {
    KIND_NAMES
        .iter()
        .position(|k| *k == kind)
        .is_some_and(|index| kinds.has(index))
}

/// The key as `kind` sees it: `key` itself, or `name` of a qualified `kind.name` (which picks a
/// kind explicitly on a bench of several kinds); `None` when the key is for another kind.
fn for_kind<'k>(kind: &str, key: &'k str, kinds: KindSet) -> Option<&'k str> {
    match key.split_once('.') {
        Some((k, rest)) if k == kind => Some(rest),
        Some(_) => None,
        None => on_bench(kind, kinds).then_some(key),
    }
}

device_kinds! {
    "piper" => Piper(piper),
    "robstride" => Robstride(robstride),
    "realman" => Realman(realman),
    "arm" => Arm(arm),
    "actuator_group" => ActuatorGroup(actuator_group),
    "damiao" => Damiao(damiao),
}

impl<'de> Deserialize<'de> for RawDevice {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> Visitor<'de> for Visit {
            type Value = RawDevice;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "a device: `{{kind: {}, ...}}`", KIND_NAMES.join("|"))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawDevice, A::Error> {
                match map.next_key::<String>()?.as_deref() {
                    Some("kind") => {}
                    _ => {
                        return Err(A::Error::custom(format!(
                            "a device starts with its `kind:` ({})",
                            KIND_NAMES.join(", ")
                        )))
                    }
                }
                let kind: String = map.next_value()?;
                read_settings(&kind, map)
            }
        }
        deserializer.deserialize_map(Visit)
    }
}

#[cfg(test)]
mod tests {
    use bus::CanFrame;

    use super::{wire_decoders, WireDecode, WireOptions};

    /// Each protocol is registered once, by the kind that owns it: `arm` and `actuator_group`
    /// speak the Piper's and RobStride's and add none, the Realman speaks no CAN.
    #[test]
    fn the_decode_protocols_are_those_of_the_kinds_that_own_them() {
        let names: Vec<&str> = wire_decoders().map(|d| d.name).collect();
        assert_eq!(names, ["piper", "robstride", "robstride-mit", "damiao"]);
        assert!(wire_decoders().all(|d| !d.help.is_empty() && !d.help.contains('\n')));
    }

    fn decoder_with(name: &str, options: &WireOptions) -> Result<WireDecode, String> {
        let wire = wire_decoders()
            .find(|d| d.name == name)
            .expect("registered");
        (wire.decoder)(options)
    }

    /// A protocol's decoder names its own frames and leaves the others' undecoded.
    #[test]
    fn each_protocol_decodes_its_own_frames() {
        let decoder = |name: &str| decoder_with(name, &WireOptions::default()).expect("decoder");
        // RobStride type 2 status from motor 1 to host 0xFD.
        let status = CanFrame::extended(
            0x0200_01FD,
            &[0x80, 0x00, 0x80, 0x00, 0x80, 0x00, 0x01, 0x2C],
        )
        .unwrap();
        let named = decoder("robstride")(&status).expect("no error");
        assert_eq!(named.map(|d| d.name), Some("Status".to_owned()));
        assert_eq!(decoder("robstride-mit")(&status), Ok(None));
        // A Piper's status feedback (0x2A1), in standby.
        let feedback = CanFrame::standard(0x2A1, &[0; 8]).unwrap();
        let named = decoder("piper")(&feedback).expect("no error");
        assert_eq!(named.map(|d| d.name), Some("ArmStatus".to_owned()));
        assert_eq!(decoder("robstride")(&feedback), Ok(None));
        assert_eq!(decoder("damiao")(&feedback), Ok(None));
        // The default Damiao motor's enable (ESC_ID 1).
        let enable =
            CanFrame::standard(0x001, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC]).unwrap();
        let named = decoder("damiao")(&enable).expect("no error");
        assert_eq!(named.map(|d| d.name), Some("enable".to_owned()));
        assert_eq!(decoder("robstride")(&enable), Ok(None));
    }

    /// The options are the command's words: each protocol resolves `--motor` and `--model`
    /// through its own tables and names the flag that does not fit it.
    #[test]
    fn each_protocol_resolves_the_options_and_names_the_flag_that_does_not_fit() {
        let motors = |list: &[&str]| WireOptions {
            motors: list.iter().map(|m| m.parse().expect("ID:MODEL")).collect(),
            ..WireOptions::default()
        };
        let error =
            |name: &str, options: &WireOptions| decoder_with(name, options).err().expect("refused");
        assert!(decoder_with("damiao", &motors(&["1:DM8009", "2:DM4310:0x22"])).is_ok());
        let e = error("damiao", &motors(&["1:DM9999"]));
        assert!(
            e.starts_with("`--motor 1:DM9999`: unknown Damiao model `DM9999`"),
            "{e}"
        );
        let e = error("damiao", &motors(&["0x7FF:DM4310"]));
        assert!(e.starts_with("`--motor 0x7FF:DM4310`: "), "{e}");
        let e = error(
            "damiao",
            &WireOptions {
                model: Some("DM4310".into()),
                ..WireOptions::default()
            },
        );
        assert!(
            e.starts_with("`--model` is not read by `--device damiao`"),
            "{e}"
        );
        // RobStride reads `--motor` too: each listed motor's frames by its own model.
        let rs = decoder_with("robstride", &motors(&["1:RS03"])).expect("decoder");
        let status = CanFrame::extended(
            0x0200_01FD,
            &[0x80, 0x00, 0x80, 0x00, 0x80, 0x00, 0x01, 0x2C],
        )
        .unwrap();
        assert_eq!(
            rs(&status).expect("no error").map(|d| d.name),
            Some("Status".to_owned())
        );
        let other = CanFrame::extended(0x0200_02FD, &[0x80, 0, 0x80, 0, 0x80, 0, 1, 0x2C]).unwrap();
        assert_eq!(rs(&other), Ok(None));
        let e = error("robstride", &motors(&["1:DM4310"]));
        assert!(
            e.starts_with("`--motor 1:DM4310`: unknown RobStride model"),
            "{e}"
        );
        let e = error("robstride", &motors(&["1:RS03:0x11"]));
        assert!(e.contains("feedback id"), "{e}");
        let e = error("robstride", &motors(&["300:RS03"]));
        assert!(e.contains("1..=127"), "{e}");
        let e = error(
            "robstride",
            &WireOptions {
                model: Some("DM4310".into()),
                ..WireOptions::default()
            },
        );
        assert!(
            e.starts_with("`--model DM4310`: unknown RobStride model"),
            "{e}"
        );
        assert!(
            e.contains("a Damiao motor is given as --motor ID:MODEL"),
            "{e}"
        );
        // The Piper's frames need no option: one given is a capture read without `--device`.
        let e = error("piper", &motors(&["1:RS03"]));
        assert!(
            e.starts_with("`--motor` is not read by `--device piper`"),
            "{e}"
        );
    }
}
