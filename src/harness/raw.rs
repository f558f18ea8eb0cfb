//! Layer 1: the scenario file as written, checked only for shape (serde, unknown keys
//! rejected). Every value that needs a semantic check keeps its span for layer 2.

use std::collections::BTreeMap;

use crate::scenario::onekey::one_key_enum;
use crate::scenario::read_in::{kinded_struct, KindSet, ReadIn};
pub(crate) use crate::scenario::S;
use serde::Deserialize;

kinded_struct! {
    /// A scenario file; its steps and faults are read with its bench's kinds.
    pub(crate) struct RawScenario {
        pub name: Option<S<String>> = plain,
        pub description: Option<String> = plain,
        pub tags: Option<Vec<S<String>>> = plain,
        pub matrix: Option<S<RawMatrix>> = plain,
        pub bench: S<RawBench> = plain,
        pub record: Option<S<RawRecord>> = plain,
        pub faults: Option<Vec<S<RawFaultEntry>>> = kinded,
        pub steps: S<Vec<S<RawStep>>> = kinded,
    }
}

/// `matrix: {parameter: [values]}` as written.
pub(crate) type RawMatrix = BTreeMap<String, S<Vec<S<String>>>>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBench {
    pub bus: Option<S<RawBus>>,
    /// Named buses (`{can0: {bitrate_bps: 1000000}, can1: {}}`).
    pub buses: Option<S<BTreeMap<String, S<RawNamedBus>>>>,
    pub devices: S<BTreeMap<String, S<crate::devices::RawDevice>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBus {
    pub bitrate_bps: Option<S<i64>>,
    pub interface: Option<S<String>>,
}

/// One of `bench.buses`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawNamedBus {
    pub bitrate_bps: Option<S<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRecord {
    pub sample_period_ms: Option<S<i64>>,
    pub signals: Option<Vec<S<String>>>,
    pub candump: Option<bool>,
    pub pcap: Option<bool>,
    pub plot: Option<bool>,
}

kinded_struct! {
    /// A fault in the schedule (`at_ms` / `after`).
    pub(crate) struct RawFaultEntry {
        pub at_ms: Option<S<i64>> = plain,
        pub after: Option<S<String>> = plain,
        pub delay_ms: Option<S<i64>> = plain,
        pub duration_ms | "for_ms": Option<S<i64>> = plain,
        pub device: Option<S<String>> = plain,
        /// The bus a bus fault acts on, on a bench of several.
        pub bus: Option<S<String>> = plain,
        pub fault: S<RawFault> = kinded,
    }
}

/// Selects frames for a bus fault: by identifier, by sending node, or all.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFrameSel {
    pub id: Option<S<i64>>,
    pub node: Option<S<String>>,
    pub probability: Option<S<f64>>,
    pub seed: Option<u64>,
    pub ms: Option<S<i64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawNodeArg {
    pub node: Option<S<String>>,
}

one_key_enum! {
    /// Every fault a scenario can inject: the bus faults here, the device kinds' after them.
    pub(crate) enum RawFault ("fault") {
        "drop" => Drop(RawFrameSel) [bare],
        "delay" => Delay(RawFrameSel),
        "corrupt" => Corrupt(RawFrameSel) [bare],
        "duplicate" => Duplicate(RawFrameSel) [bare],
        "silence" => Silence(RawNodeArg),
        "bus_off" => BusOff(RawNodeArg),
    }
    else Device(crate::devices::RawDeviceFault)
}

/// Conditions of `expect` and `wait_until`: the generic keys (device, id, wait/hold
/// durations) and the conditions of one device kind, chosen by the first condition key.
#[derive(Debug, Default)]
pub(crate) struct RawConditions {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
    pub timeout_ms: Option<S<i64>>,
    pub for_ms: Option<S<i64>>,
    /// The conditions; `None` when the step names none.
    pub conds: Option<crate::devices::RawDeviceConds>,
}

kinded_struct! {
    /// `inject` step arguments: the fault, its device and how long it lasts.
    pub(crate) struct RawInject {
        pub id: Option<S<String>> = plain,
        pub device: Option<S<String>> = plain,
        pub duration_ms | "for_ms": Option<S<i64>> = plain,
        /// The bus a bus fault acts on, on a bench of several.
        pub bus: Option<S<String>> = plain,
        pub fault: S<RawFault> = kinded,
    }
}

one_key_enum! {
    /// Every step a scenario can take: the generic ones here, the device kinds' after them.
    pub(crate) enum RawStep ("step") {
        "wait_ms" => WaitMs(S<i64>),
        "inject" => Inject(RawInject) [kinded],
        "clear_faults" => ClearFaults(RawClearFaults) [bare],
        "expect" => Expect(RawConditions) [kinded],
        "wait_until" => WaitUntil(RawConditions) [kinded],
    }
    else Device(crate::devices::RawDeviceStep)
}

/// `clear_faults` arguments.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawClearFaults {
    pub device: Option<S<String>>,
    pub id: Option<S<String>>,
}

/// The keys of `expect` / `wait_until` that every device kind shares.
const GENERIC_CONDITION_KEYS: [&str; 4] = ["device", "id", "timeout_ms", "for_ms"];

impl RawConditions {
    /// Store a generic key's value; `false` when `key` is a condition of a device kind.
    fn take_generic<'de, A: serde::de::MapAccess<'de>>(
        &mut self,
        key: &str,
        map: &mut A,
    ) -> Result<bool, A::Error> {
        match key {
            "device" => self.device = Some(map.next_value()?),
            "id" => self.id = Some(map.next_value()?),
            "timeout_ms" => self.timeout_ms = Some(map.next_value()?),
            "for_ms" => self.for_ms = Some(map.next_value()?),
            _ => return Ok(false),
        }
        Ok(true)
    }
}

/// The rest of a conditions mapping as seen by a device kind's conditions struct: the first
/// condition key (already read) comes first, and generic keys are taken out on the way.
struct CondMap<'a, A> {
    first: Option<String>,
    map: &'a mut A,
    generic: &'a mut RawConditions,
}

impl<'de, A: serde::de::MapAccess<'de>> serde::de::MapAccess<'de> for CondMap<'_, A> {
    type Error = A::Error;

    fn next_key_seed<K: serde::de::DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        use serde::de::IntoDeserializer;
        if let Some(key) = self.first.take() {
            return seed.deserialize(key.into_deserializer()).map(Some);
        }
        while let Some(key) = self.map.next_key::<String>()? {
            if !self.generic.take_generic(&key, &mut *self.map)? {
                return seed.deserialize(key.into_deserializer()).map(Some);
            }
        }
        Ok(None)
    }

    fn next_value_seed<V: serde::de::DeserializeSeed<'de>>(
        &mut self,
        seed: V,
    ) -> Result<V::Value, A::Error> {
        self.map.next_value_seed(seed)
    }
}

impl ReadIn for RawConditions {
    fn read_in<'de, D: serde::Deserializer<'de>>(
        deserializer: D,
        kinds: KindSet,
    ) -> Result<Self, D::Error> {
        struct Visit(KindSet);
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = RawConditions;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a mapping of conditions")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<RawConditions, A::Error> {
                let mut out = RawConditions::default();
                while let Some(key) = map.next_key::<String>()? {
                    if out.take_generic(&key, &mut map)? {
                        continue;
                    }
                    let Some(kind) = crate::devices::RawDeviceConds::kind_of_key(&key, self.0)
                    else {
                        let mut keys: Vec<&'static str> = GENERIC_CONDITION_KEYS.to_vec();
                        keys.extend(crate::devices::RawDeviceConds::keys(self.0));
                        return Err(crate::scenario::onekey::unknown("condition", &key, &keys));
                    };
                    let rest = CondMap {
                        first: Some(crate::devices::unqualified(&key).to_owned()),
                        map: &mut map,
                        generic: &mut out,
                    };
                    let conds = crate::devices::RawDeviceConds::read(
                        kind,
                        serde::de::value::MapAccessDeserializer::new(rest),
                    )?;
                    out.conds = Some(conds);
                    break;
                }
                Ok(out)
            }
        }
        deserializer.deserialize_map(Visit(kinds))
    }
}
