//! One-key mappings as enums: `- move_j: {...}` or, for actions without arguments, `- estop`.
//!
//! serde's derived externally-tagged enums reject the bare form for variants with optional
//! arguments, so the dispatch is written by hand; the arguments keep serde-saphyr's spans.
//! A one-key enum may end with a fallback variant holding another [`OneKey`] type: that is how
//! the generic step and fault grammars hand the keys they do not know to the device kinds.

use serde::de::{Deserializer, Error, MapAccess};

use super::read_in::KindSet;

/// A type read from a one-key mapping (or a bare key), dispatched on the key. `kinds` are the
/// device kinds on the bench: the grammars that hand keys on to device kinds resolve them
/// among those only; every other one-key type ignores it.
pub(crate) trait OneKey: Sized {
    /// What one value is called in messages ("step", "fault").
    const WHAT: &'static str;
    /// Every key this type accepts.
    fn keys(kinds: KindSet) -> Vec<&'static str>;
    /// The value of a bare `key`; `None` when the key is not this type's.
    fn bare<E: Error>(key: &str, kinds: KindSet) -> Option<Result<Self, E>>;
    /// Read the value of `key` from `map`; `None` (nothing read) when the key is not this type's.
    fn entry<'de, A: MapAccess<'de>>(
        key: &str,
        map: &mut A,
        kinds: KindSet,
    ) -> Option<Result<Self, A::Error>>;
}

/// The "unknown key" error, with the accepted keys and a "did you mean".
pub(crate) fn unknown<E: Error>(what: &str, key: &str, keys: &[&'static str]) -> E {
    E::custom(format!(
        "unknown {what} `{key}`; expected one of: {}{}",
        keys.join(", "),
        crate::scenario::error::suggestion(key, keys)
    ))
}

/// Read a `T` written as a bare key or a one-key mapping, its keys resolved among `kinds`.
pub(crate) fn read_one_key<'de, T: OneKey, D: Deserializer<'de>>(
    de: D,
    kinds: KindSet,
) -> Result<T, D::Error> {
    struct Visit<T>(KindSet, std::marker::PhantomData<fn() -> T>);
    impl<'de, T: OneKey> serde::de::Visitor<'de> for Visit<T> {
        type Value = T;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "{} (one of: {})", T::WHAT, T::keys(self.0).join(", "))
        }
        fn visit_str<E: Error>(self, text: &str) -> Result<T, E> {
            T::bare(text, self.0).unwrap_or_else(|| Err(unknown(T::WHAT, text, &T::keys(self.0))))
        }
        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<T, A::Error> {
            let Some(key) = map.next_key::<String>()? else {
                return Err(A::Error::custom(format!(
                    "empty mapping; expected a {} (one of: {})",
                    T::WHAT,
                    T::keys(self.0).join(", ")
                )));
            };
            let value = T::entry(&key, &mut map, self.0)
                .unwrap_or_else(|| Err(unknown(T::WHAT, &key, &T::keys(self.0))))?;
            if let Some(extra) = map.next_key::<String>()? {
                return Err(A::Error::custom(format!(
                    "one {} per list item, found a second key `{}` (indent its arguments under `{}:`)",
                    T::WHAT,
                    extra,
                    key
                )));
            }
            Ok(value)
        }
    }
    de.deserialize_any(Visit(kinds, std::marker::PhantomData))
}

/// Define an enum whose YAML form is a one-key mapping `name: args` (or a bare `name` for
/// variants marked `bare`, which take their arguments' `Default`), optionally with a fallback
/// variant (`else Variant(Type)`) for keys another [`OneKey`] type knows. Arguments marked
/// `kinded` are read with the bench's kinds ([`ReadIn`](super::read_in::ReadIn)).
macro_rules! one_key_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident ($what:literal) {
            $( $key:literal => $variant:ident($ty:ty) $([$flag:ident])? ),* $(,)?
        }
        $( else $fb:ident($fty:ty) )?
    ) => {
        $(#[$meta])*
        #[derive(Debug)]
        // Parse-time values, one per list item and short-lived: their size does not matter.
        #[allow(clippy::large_enum_variant)]
        $vis enum $name {
            $( #[doc = concat!("`", $key, "`")] $variant($ty), )*
            $( #[doc = "A key of another vocabulary."] $fb($fty), )?
        }

        impl $crate::scenario::onekey::OneKey for $name {
            const WHAT: &'static str = $what;

            fn keys(kinds: $crate::scenario::read_in::KindSet) -> Vec<&'static str> {
                let _ = kinds;
                #[allow(unused_mut)]
                let mut keys = vec![$($key),*];
                $( keys.extend(<$fty as $crate::scenario::onekey::OneKey>::keys(kinds)); )?
                keys
            }

            fn bare<E: serde::de::Error>(
                key: &str,
                kinds: $crate::scenario::read_in::KindSet,
            ) -> Option<Result<Self, E>> {
                let _ = kinds;
                match key {
                    $( $key => Some(one_key_enum!(@bare E, $name, $variant, $key $(, $flag)?)), )*
                    #[allow(unused_variables)]
                    other => {
                        $( return <$fty as $crate::scenario::onekey::OneKey>::bare(other, kinds)
                            .map(|r| r.map($name::$fb)); )?
                        #[allow(unreachable_code)]
                        None
                    }
                }
            }

            fn entry<'de, A: serde::de::MapAccess<'de>>(
                key: &str,
                map: &mut A,
                kinds: $crate::scenario::read_in::KindSet,
            ) -> Option<Result<Self, A::Error>> {
                let _ = kinds;
                match key {
                    $( $key => Some((|| {
                        let args: Option<$ty> = one_key_enum!(@read map, kinds, $ty $(, $flag)?)?;
                        match args {
                            Some(args) => Ok($name::$variant(args)),
                            None => one_key_enum!(@bare A::Error, $name, $variant, $key $(, $flag)?),
                        }
                    })()), )*
                    #[allow(unused_variables)]
                    other => {
                        $( return <$fty as $crate::scenario::onekey::OneKey>::entry(other, map, kinds)
                            .map(|r| r.map($name::$fb)); )?
                        #[allow(unreachable_code)]
                        None
                    }
                }
            }
        }

        impl $crate::scenario::read_in::ReadIn for $name {
            fn read_in<'de, D: serde::Deserializer<'de>>(
                de: D,
                kinds: $crate::scenario::read_in::KindSet,
            ) -> Result<Self, D::Error> {
                $crate::scenario::onekey::read_one_key(de, kinds)
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                $crate::scenario::onekey::read_one_key(deserializer, $crate::scenario::read_in::KindSet::ALL)
            }
        }
    };
    (@read $map:ident, $kinds:ident, $ty:ty, kinded) => {
        $map.next_value_seed($crate::scenario::read_in::In::<Option<$ty>>::new($kinds))
    };
    (@read $map:ident, $kinds:ident, $ty:ty $(, bare)?) => {
        $map.next_value::<Option<$ty>>()
    };
    (@bare $err:ty, $name:ident, $variant:ident, $key:literal, bare) => {
        Ok::<$name, $err>($name::$variant(Default::default()))
    };
    (@bare $err:ty, $name:ident, $variant:ident, $key:literal $(, kinded)?) => {
        Err::<$name, $err>(<$err as serde::de::Error>::custom(format!(
            "`{}` needs arguments: write `{}: {{ ... }}`",
            $key, $key
        )))
    };
}

pub(crate) use one_key_enum;

/// A vocabulary whose names come from elsewhere (an emulator's fault table): every value, its
/// scenario name, and the value of a name. Implemented for each emulator's fault kind so that
/// the emulator's table is the one description of its faults.
pub(crate) trait NamedKind: Copy + Sized + 'static {
    /// Every value, in the table's order.
    fn all() -> &'static [Self];
    /// The scenario name of `self`.
    fn name(self) -> &'static str;
    /// The value named `name`, if any.
    fn from_name(name: &str) -> Option<Self>;
}

/// `name: {args}` (or a bare `name`, taking `A::default()`) where `name` is one of a
/// [`NamedKind`]'s names: how a device kind reads its emulator's faults.
#[derive(Debug)]
pub(crate) struct NamedEntry<K, A> {
    /// Which one.
    pub kind: K,
    /// Its arguments as written.
    pub args: A,
}

impl<K, A> OneKey for NamedEntry<K, A>
where
    K: NamedKind,
    A: Default + for<'de> serde::Deserialize<'de>,
{
    const WHAT: &'static str = "fault";

    fn keys(_: KindSet) -> Vec<&'static str> {
        K::all().iter().map(|k| k.name()).collect()
    }

    fn bare<E: Error>(key: &str, _: KindSet) -> Option<Result<Self, E>> {
        let kind = K::from_name(key)?;
        Some(Ok(Self {
            kind,
            args: A::default(),
        }))
    }

    fn entry<'de, M: MapAccess<'de>>(
        key: &str,
        map: &mut M,
        _: KindSet,
    ) -> Option<Result<Self, M::Error>> {
        let kind = K::from_name(key)?;
        Some(map.next_value::<Option<A>>().map(|args| Self {
            kind,
            args: args.unwrap_or_default(),
        }))
    }
}
