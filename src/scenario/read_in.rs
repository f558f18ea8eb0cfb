//! Reading a scenario with the bench's device kinds in hand.
//!
//! Which kind owns a step, fault or condition key depends on the bench: `enable` is a Piper,
//! a RobStride and a Realman step, `under_voltage` a fault of two kinds. serde's derived
//! readers take no context, so the parts of the scenario grammar that reach device
//! vocabularies (steps, faults, conditions and the structs holding them) are read by
//! [`ReadIn`] instead: `Deserialize` with a [`KindSet`] passed down as a `DeserializeSeed`.
//! Everything else stays derived.

use std::marker::PhantomData;

use serde::de::{DeserializeSeed, Deserializer, Error, MapAccess, SeqAccess, Visitor};

use super::S;

/// A set of registered device kinds, by registration index (the registry in `devices` gives
/// the indices); [`KindSet::ALL`] when a value is read outside a bench.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct KindSet(u64);

impl KindSet {
    /// Every kind.
    pub(crate) const ALL: Self = Self(u64::MAX);

    /// The kinds with these registration indices.
    pub(crate) fn of(indices: impl IntoIterator<Item = usize>) -> Self {
        Self(indices.into_iter().fold(0, |set, i| set | (1 << i)))
    }

    /// Whether the kind with registration index `index` is in the set.
    pub(crate) fn has(self, index: usize) -> bool {
        self.0 & (1 << index) != 0
    }
}

/// A value read from YAML whose grammar depends on the bench's kinds.
pub(crate) trait ReadIn: Sized {
    /// Read one value, resolving device keys among `kinds`.
    fn read_in<'de, D: Deserializer<'de>>(de: D, kinds: KindSet) -> Result<Self, D::Error>;
}

/// The seed reading a `T` with `kinds`: `map.next_value_seed(In::<T>::new(kinds))`.
pub(crate) struct In<T> {
    kinds: KindSet,
    read: PhantomData<fn() -> T>,
}

impl<T> In<T> {
    /// The seed for reading a `T` among `kinds`.
    pub(crate) fn new(kinds: KindSet) -> Self {
        Self {
            kinds,
            read: PhantomData,
        }
    }
}

impl<'de, T: ReadIn> DeserializeSeed<'de> for In<T> {
    type Value = T;
    fn deserialize<D: Deserializer<'de>>(self, de: D) -> Result<T, D::Error> {
        T::read_in(de, self.kinds)
    }
}

impl<T: ReadIn> ReadIn for Option<T> {
    fn read_in<'de, D: Deserializer<'de>>(de: D, kinds: KindSet) -> Result<Self, D::Error> {
        struct Visit<T>(KindSet, PhantomData<fn() -> T>);
        impl<'de, T: ReadIn> Visitor<'de> for Visit<T> {
            type Value = Option<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("option")
            }
            fn visit_none<E: Error>(self) -> Result<Option<T>, E> {
                Ok(None)
            }
            fn visit_unit<E: Error>(self) -> Result<Option<T>, E> {
                Ok(None)
            }
            fn visit_some<D: Deserializer<'de>>(self, de: D) -> Result<Option<T>, D::Error> {
                T::read_in(de, self.0).map(Some)
            }
        }
        de.deserialize_option(Visit(kinds, PhantomData))
    }
}

impl<T: ReadIn> ReadIn for Vec<T> {
    fn read_in<'de, D: Deserializer<'de>>(de: D, kinds: KindSet) -> Result<Self, D::Error> {
        struct Visit<T>(KindSet, PhantomData<fn() -> T>);
        impl<'de, T: ReadIn> Visitor<'de> for Visit<T> {
            type Value = Vec<T>;
            // serde's own words for a `Vec`, so that messages do not depend on the reader.
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a sequence")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<T>, A::Error> {
                let mut out = Vec::new();
                while let Some(item) = seq.next_element_seed(In::<T>::new(self.0))? {
                    out.push(item);
                }
                Ok(out)
            }
        }
        de.deserialize_seq(Visit(kinds, PhantomData))
    }
}

/// The newtype name by which serde-saphyr's deserializer hands out a node's span, and the
/// fields of the map it then presents. serde-saphyr's own `Spanned<T>` reads exactly these
/// (it has no seeded form, which is why this copy of its reading exists); a change there shows
/// as every spanned scenario error losing its line and column in this crate's tests.
const SPANNED_NEWTYPE: &str = "__yaml_spanned";

impl<T: ReadIn> ReadIn for S<T> {
    fn read_in<'de, D: Deserializer<'de>>(de: D, kinds: KindSet) -> Result<Self, D::Error> {
        struct Outer<T>(KindSet, PhantomData<fn() -> T>);
        impl<'de, T: ReadIn> Visitor<'de> for Outer<T> {
            type Value = S<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a span-aware newtype wrapper")
            }
            fn visit_newtype_struct<D: Deserializer<'de>>(self, de: D) -> Result<S<T>, D::Error> {
                de.deserialize_any(Fields(self.0, PhantomData))
            }
        }
        struct Fields<T>(KindSet, PhantomData<fn() -> T>);
        impl<'de, T: ReadIn> Visitor<'de> for Fields<T> {
            type Value = S<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a span-aware map with value/referenced/defined fields")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<S<T>, A::Error> {
                let (mut value, mut referenced, mut defined) = (None, None, None);
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "value" => value = Some(map.next_value_seed(In::<T>::new(self.0))?),
                        "referenced" => referenced = Some(map.next_value()?),
                        "defined" => defined = Some(map.next_value()?),
                        _ => {
                            map.next_value::<serde::de::IgnoredAny>()?;
                        }
                    }
                }
                match (value, referenced, defined) {
                    (Some(value), Some(referenced), Some(defined)) => {
                        Ok(S::new(value, referenced, defined))
                    }
                    (None, _, _) => Err(A::Error::missing_field("value")),
                    _ => Err(A::Error::custom(
                        "the YAML reader gave a value without its place in the file",
                    )),
                }
            }
        }
        de.deserialize_newtype_struct(SPANNED_NEWTYPE, Outer(kinds, PhantomData))
    }
}

/// How a field of a [`kinded_struct!`] is read: with the kinds (`kinded`) or by its own
/// `Deserialize` (`plain`).
macro_rules! read_field {
    ($map:ident, $kinds:ident, $ty:ty, kinded) => {
        $map.next_value_seed($crate::scenario::read_in::In::<$ty>::new($kinds))
    };
    ($map:ident, $kinds:ident, $ty:ty, plain) => {
        $map.next_value::<$ty>()
    };
}

/// A field left out: `None` for an optional field, serde's "missing field" otherwise.
pub(crate) trait Missing: Sized {
    /// The value of a field the mapping does not have.
    fn missing<E: Error>(field: &'static str) -> Result<Self, E>;
}

impl<T> Missing for Option<T> {
    fn missing<E: Error>(_: &'static str) -> Result<Self, E> {
        Ok(None)
    }
}

impl<T> Missing for S<T> {
    fn missing<E: Error>(field: &'static str) -> Result<Self, E> {
        Err(E::missing_field(field))
    }
}

/// A struct read from a mapping with unknown keys refused, as `#[derive(Deserialize)]` with
/// `#[serde(deny_unknown_fields)]` would, where some fields (`= kinded`) are read with the
/// bench's kinds. Every field is an `Option` (optional) or an `S` (required); a field may
/// take one alias (`duration_ms | "for_ms"`).
macro_rules! kinded_struct {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $( $(#[$fmeta:meta])* $fvis:vis $field:ident $(| $alias:literal)? : $ty:ty = $how:ident ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug)]
        $vis struct $name {
            $( $(#[$fmeta])* $fvis $field: $ty, )*
        }

        impl $crate::scenario::read_in::ReadIn for $name {
            fn read_in<'de, D: serde::Deserializer<'de>>(
                de: D,
                kinds: $crate::scenario::read_in::KindSet,
            ) -> Result<Self, D::Error> {
                // Aliases listed after their field, as serde's derive lists them.
                const FIELDS: &[&str] = &[$(stringify!($field) $(, $alias)?),*];
                struct Visit($crate::scenario::read_in::KindSet);
                impl<'de> serde::de::Visitor<'de> for Visit {
                    type Value = $name;
                    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                        f.write_str(concat!("struct ", stringify!($name)))
                    }
                    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<$name, A::Error> {
                        use serde::de::Error as _;
                        #[allow(unused_variables)]
                        let kinds = self.0;
                        $( let mut $field: Option<$ty> = None; )*
                        while let Some(key) = map.next_key::<String>()? {
                            match key.as_str() {
                                $( stringify!($field) $(| $alias)? => {
                                    if $field.is_some() {
                                        return Err(A::Error::duplicate_field(stringify!($field)));
                                    }
                                    $field = Some($crate::scenario::read_in::read_field!(map, kinds, $ty, $how)?);
                                } )*
                                other => return Err(A::Error::unknown_field(other, FIELDS)),
                            }
                        }
                        Ok($name {
                            $( $field: match $field {
                                Some(value) => value,
                                None => <$ty as $crate::scenario::read_in::Missing>::missing(stringify!($field))?,
                            }, )*
                        })
                    }
                }
                de.deserialize_struct(stringify!($name), FIELDS, Visit(kinds))
            }
        }
    };
}

pub(crate) use {kinded_struct, read_field};
