//! One-key mappings as enums: `- move_j: {...}` or, for actions without arguments, `- estop`.
//!
//! serde's derived externally-tagged enums reject the bare form for variants with optional
//! arguments, so the dispatch is written by hand; the arguments keep serde-saphyr's spans.
//! A one-key enum may end with a fallback variant holding another [`OneKey`] type: that is how
//! the generic step and fault grammars hand the keys they do not know to the device kinds.

use serde::de::{Error, MapAccess};

/// A type read from a one-key mapping (or a bare key), dispatched on the key.
pub(crate) trait OneKey: Sized {
    /// Every key this type accepts.
    fn keys() -> Vec<&'static str>;
    /// The value of a bare `key`; `None` when the key is not this type's.
    fn bare<E: Error>(key: &str) -> Option<Result<Self, E>>;
    /// Read the value of `key` from `map`; `None` (nothing read) when the key is not this type's.
    fn entry<'de, A: MapAccess<'de>>(key: &str, map: &mut A) -> Option<Result<Self, A::Error>>;
}

/// The "unknown key" error, with the accepted keys and a "did you mean".
pub(crate) fn unknown<E: Error>(what: &str, key: &str, keys: &[&'static str]) -> E {
    E::custom(format!(
        "unknown {what} `{key}`; expected one of: {}{}",
        keys.join(", "),
        crate::scenario::error::suggestion(key, keys)
    ))
}

/// Define an enum whose YAML form is a one-key mapping `name: args` (or a bare `name` for
/// variants marked `bare`, which take their arguments' `Default`), optionally with a fallback
/// variant (`else Variant(Type)`) for keys another [`OneKey`] type knows.
macro_rules! one_key_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident ($what:literal) {
            $( $key:literal => $variant:ident($ty:ty) $([$bare:ident])? ),* $(,)?
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
            fn keys() -> Vec<&'static str> {
                #[allow(unused_mut)]
                let mut keys = vec![$($key),*];
                $( keys.extend(<$fty as $crate::scenario::onekey::OneKey>::keys()); )?
                keys
            }

            fn bare<E: serde::de::Error>(key: &str) -> Option<Result<Self, E>> {
                match key {
                    $( $key => Some(one_key_enum!(@bare E, $name, $variant, $key $(, $bare)?)), )*
                    #[allow(unused_variables)]
                    other => {
                        $( return <$fty as $crate::scenario::onekey::OneKey>::bare(other)
                            .map(|r| r.map($name::$fb)); )?
                        #[allow(unreachable_code)]
                        None
                    }
                }
            }

            fn entry<'de, A: serde::de::MapAccess<'de>>(
                key: &str,
                map: &mut A,
            ) -> Option<Result<Self, A::Error>> {
                match key {
                    $( $key => Some((|| {
                        let args: Option<$ty> = map.next_value()?;
                        match args {
                            Some(args) => Ok($name::$variant(args)),
                            None => one_key_enum!(@bare A::Error, $name, $variant, $key $(, $bare)?),
                        }
                    })()), )*
                    #[allow(unused_variables)]
                    other => {
                        $( return <$fty as $crate::scenario::onekey::OneKey>::entry(other, map)
                            .map(|r| r.map($name::$fb)); )?
                        #[allow(unreachable_code)]
                        None
                    }
                }
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                use $crate::scenario::onekey::OneKey;
                struct Visit;
                impl<'de> serde::de::Visitor<'de> for Visit {
                    type Value = $name;
                    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                        write!(f, "{} (one of: {})", $what, $name::keys().join(", "))
                    }
                    fn visit_str<E: serde::de::Error>(self, text: &str) -> Result<$name, E> {
                        $name::bare(text).unwrap_or_else(|| {
                            Err($crate::scenario::onekey::unknown($what, text, &$name::keys()))
                        })
                    }
                    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<$name, A::Error> {
                        use serde::de::Error as _;
                        let Some(key) = map.next_key::<String>()? else {
                            return Err(A::Error::custom(format!(
                                "empty mapping; expected a {} (one of: {})",
                                $what, $name::keys().join(", ")
                            )));
                        };
                        let value = $name::entry(&key, &mut map).unwrap_or_else(|| {
                            Err($crate::scenario::onekey::unknown($what, &key, &$name::keys()))
                        })?;
                        if let Some(extra) = map.next_key::<String>()? {
                            return Err(A::Error::custom(format!(
                                "one {} per list item, found a second key `{}` (indent its arguments under `{}:`)",
                                $what, extra, key
                            )));
                        }
                        Ok(value)
                    }
                }
                deserializer.deserialize_any(Visit)
            }
        }
    };
    (@bare $err:ty, $name:ident, $variant:ident, $key:literal, bare) => {
        Ok::<$name, $err>($name::$variant(Default::default()))
    };
    (@bare $err:ty, $name:ident, $variant:ident, $key:literal) => {
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
    fn keys() -> Vec<&'static str> {
        K::all().iter().map(|k| k.name()).collect()
    }

    fn bare<E: Error>(key: &str) -> Option<Result<Self, E>> {
        let kind = K::from_name(key)?;
        Some(Ok(Self {
            kind,
            args: A::default(),
        }))
    }

    fn entry<'de, M: MapAccess<'de>>(key: &str, map: &mut M) -> Option<Result<Self, M::Error>> {
        let kind = K::from_name(key)?;
        Some(map.next_value::<Option<A>>().map(|args| Self {
            kind,
            args: args.unwrap_or_default(),
        }))
    }
}
