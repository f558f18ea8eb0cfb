//! Device kinds: one folder per kind, registered once, in [`device_kinds!`] below.
//!
//! The harness (`crate::harness`) knows no device kind. Each kind's module owns its scenario
//! vocabulary (raw and validated), its bench wiring (emulator and driver, on whatever transport
//! the device speaks), its observations and trace columns, its faults and their mapping to the
//! emulator, and its [`Device`](crate::harness::Device) implementation. A kind module provides:
//!
//! - types `Settings`, `Action`, `Check`, `Fault` (validated vocabulary, `Debug + Clone +
//!   PartialEq`), with `describe_fault(&Fault) -> String` and `describe_check(&Check) -> String`;
//! - `raw::{RawSettings, RawStep, RawConds, RawFault, CONDITION_KEYS}`: the file shapes, where
//!   `RawStep` and `RawFault` are one-key enums (`OneKey`) and `RawStep::id()` gives a step id;
//! - `validate::{settings, step, checks, fault}`: layer 2, with file:line:col errors;
//! - `action_needs_emulator(&Action) -> Option<String>` and
//!   `in_process_requirements(&Settings, name) -> Vec<String>` (what `--iface` runs cannot do);
//! - `build(name, &Settings, &Wiring) -> Result<Arc<dyn Device>, String>` (async): start the
//!   emulator (in-process runs) and the driver.

use std::sync::Arc;

use serde::de::{Deserialize, Deserializer, Error as _, MapAccess, Visitor};

use crate::harness::device::Device;
use crate::harness::error::Pos;
use crate::harness::onekey::OneKey;
use crate::harness::raw::S;
use crate::harness::validate::{Ctx, Res};
use crate::harness::{Clock, RunOptions};

pub mod arm;
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

/// What a kind's `build` gets: the scenario's clock and options, and, for CAN devices, the
/// in-process virtual bus or the SocketCAN interface to open.
pub(crate) struct Wiring<'a> {
    /// The in-process virtual bus (virtual and real-time clocks).
    pub bus: Option<&'a bus::virtual_bus::VirtualBus>,
    /// Clock of the run.
    pub clock: &'a Clock,
    /// Run options (deadline scaling).
    pub options: &'a RunOptions,
    /// Bit rate of the bench's CAN bus.
    pub bitrate_bps: u32,
}

/// Register device kinds: `"name" => Variant(module)`. Everything below is generated from this
/// list; nothing else in the crate lists device kinds.
macro_rules! device_kinds {
    ($( $name:literal => $variant:ident($module:ident) ),* $(,)?) => {
        /// The scenario names of every device kind.
        pub const KIND_NAMES: &[&str] = &[$($name),*];

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
                match self { $( Self::$variant(s) => $module::in_process_requirements(s, device), )* }
            }

            /// Start the device (emulator when in-process, and driver).
            pub(crate) async fn build(
                &self,
                device: &str,
                wiring: &Wiring<'_>,
            ) -> Result<Arc<dyn Device>, String> {
                match self { $( Self::$variant(s) => $module::build(device, s, wiring).await, )* }
            }
        }

        impl Action {
            /// The device kind this action belongs to.
            pub fn kind_name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }

            /// Why this action needs the in-process emulator, if it does.
            pub fn needs_emulator(&self) -> Option<String> {
                match self { $( Self::$variant(a) => $module::action_needs_emulator(a), )* }
            }
        }

        impl Check {
            /// The device kind this condition belongs to.
            pub fn kind_name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }

            /// What the condition wants, for reports.
            pub fn describe(&self) -> String {
                match self { $( Self::$variant(c) => $module::describe_check(c), )* }
            }
        }

        impl DeviceFault {
            /// The device kind this fault belongs to.
            pub fn kind_name(&self) -> &'static str {
                match self { $( Self::$variant(_) => $name, )* }
            }

            /// Short description for logs and reports.
            pub fn describe(&self) -> String {
                match self { $( Self::$variant(f) => $module::describe_fault(f), )* }
            }
        }

        /// A device entry of the bench as written: `kind:` first, then the kind's settings.
        #[derive(Debug)]
        pub(crate) enum RawDevice {
            $( $variant(Box<$module::raw::RawSettings>), )*
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
                other => Err(crate::harness::onekey::unknown("device kind", other, KIND_NAMES)),
            }
        }

        /// A step of some device kind (the key decides which: the first kind that knows it).
        #[derive(Debug)]
        pub(crate) enum RawDeviceStep {
            $( $variant(Box<$module::raw::RawStep>), )*
        }

        impl OneKey for RawDeviceStep {
            fn keys() -> Vec<&'static str> {
                let mut keys = Vec::new();
                $( if on_bench($name) { keys.extend(<$module::raw::RawStep as OneKey>::keys()); } )*
                keys
            }
            fn bare<E: serde::de::Error>(key: &str) -> Option<Result<Self, E>> {
                $( if let Some(key) = for_kind($name, key) {
                    if let Some(r) = <$module::raw::RawStep as OneKey>::bare(key) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
            fn entry<'de, A: MapAccess<'de>>(key: &str, map: &mut A) -> Option<Result<Self, A::Error>> {
                $( if let Some(key) = for_kind($name, key) {
                    if let Some(r) = <$module::raw::RawStep as OneKey>::entry(key, map) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
        }

        impl RawDeviceStep {
            /// The step's `id:`.
            pub(crate) fn id(&self) -> Option<&S<String>> {
                match self { $( Self::$variant(s) => s.id(), )* }
            }
        }

        /// An emulator fault of some device kind, as written.
        #[derive(Debug)]
        pub(crate) enum RawDeviceFault {
            $( $variant(Box<$module::raw::RawFault>), )*
        }

        impl OneKey for RawDeviceFault {
            fn keys() -> Vec<&'static str> {
                let mut keys = Vec::new();
                $( if on_bench($name) { keys.extend(<$module::raw::RawFault as OneKey>::keys()); } )*
                keys
            }
            fn bare<E: serde::de::Error>(key: &str) -> Option<Result<Self, E>> {
                $( if let Some(key) = for_kind($name, key) {
                    if let Some(r) = <$module::raw::RawFault as OneKey>::bare(key) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
            fn entry<'de, A: MapAccess<'de>>(key: &str, map: &mut A) -> Option<Result<Self, A::Error>> {
                $( if let Some(key) = for_kind($name, key) {
                    if let Some(r) = <$module::raw::RawFault as OneKey>::entry(key, map) {
                        return Some(r.map(|v| Self::$variant(Box::new(v))));
                    }
                } )*
                None
            }
        }

        /// Conditions of some device kind, as written.
        #[derive(Debug)]
        pub(crate) enum RawDeviceConds {
            $( $variant(Box<$module::raw::RawConds>), )*
        }

        /// Index of a kind in registration order.
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub(crate) struct KindIndex(usize);

        impl RawDeviceConds {
            /// Every condition key of every kind.
            pub(crate) fn keys() -> Vec<&'static str> {
                let mut keys = Vec::new();
                $( if on_bench($name) { keys.extend($module::raw::CONDITION_KEYS); } )*
                keys
            }

            /// The first kind whose conditions include `key`.
            pub(crate) fn kind_of_key(key: &str) -> Option<KindIndex> {
                let tables: &[(&str, &[&str])] = &[$( ($name, &$module::raw::CONDITION_KEYS) ),*];
                tables
                    .iter()
                    .position(|(kind, keys)| on_bench(kind) && keys.contains(&key))
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
                $( RawDevice::$variant(r) => Ok(DeviceKind::$variant($module::validate::settings(ctx, r, at)?)), )*
            }
        }

        /// Layer 2 of a device step: its label and action.
        pub(crate) fn validate_step(ctx: &Ctx<'_>, raw: &RawDeviceStep, at: Pos) -> Res<(&'static str, crate::harness::model::StepKind)> {
            match raw {
                $( RawDeviceStep::$variant(r) => $module::validate::step(ctx, r, at), )*
            }
        }

        /// Layer 2 of device conditions.
        pub(crate) fn validate_checks(ctx: &Ctx<'_>, raw: &RawDeviceConds, step: &str, at: Pos) -> Res<Vec<Check>> {
            match raw {
                $( RawDeviceConds::$variant(r) => Ok($module::validate::checks(ctx, r, step, at)?
                    .into_iter().map(Check::$variant).collect()), )*
            }
        }

        /// Layer 2 of a device fault.
        pub(crate) fn validate_fault(ctx: &Ctx<'_>, raw: &RawDeviceFault, at: Pos) -> Res<DeviceFault> {
            match raw {
                $( RawDeviceFault::$variant(r) => Ok(DeviceFault::$variant($module::validate::fault(ctx, r, at)?)), )*
            }
        }
    };
}

thread_local! {
    /// The kinds on the bench of the scenario being parsed (`None`: every kind).
    static ON_BENCH: std::cell::RefCell<Option<Vec<&'static str>>> =
        const { std::cell::RefCell::new(None) };
}

/// Parse with step, fault and condition keys resolved among `kinds` only (the kinds on the
/// bench), so that kinds sharing a key (`under_voltage`, `enable`) do not collide.
pub(crate) fn with_bench_kinds<T>(kinds: Vec<&'static str>, parse: impl FnOnce() -> T) -> T {
    let previous = ON_BENCH.with(|k| k.replace(Some(kinds)));
    let out = parse();
    ON_BENCH.with(|k| *k.borrow_mut() = previous);
    out
}

/// Whether `kind` is on the bench being parsed.
fn on_bench(kind: &str) -> bool {
    ON_BENCH.with(|k| {
        k.borrow()
            .as_ref()
            .is_none_or(|kinds| kinds.contains(&kind))
    })
}

/// The key as `kind` sees it: `key` itself, or `name` of a qualified `kind.name` (which picks a
/// kind explicitly on a bench of several kinds); `None` when the key is for another kind.
fn for_kind<'k>(kind: &str, key: &'k str) -> Option<&'k str> {
    match key.split_once('.') {
        Some((k, rest)) if k == kind => Some(rest),
        Some(_) => None,
        None => on_bench(kind).then_some(key),
    }
}

device_kinds! {
    "piper" => Piper(piper),
    "robstride" => Robstride(robstride),
    "realman" => Realman(realman),
    "arm" => Arm(arm),
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
