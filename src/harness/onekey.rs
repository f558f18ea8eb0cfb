//! One-key mappings as enums: `- move_j: {...}` or, for actions without arguments, `- estop`.
//!
//! serde's derived externally-tagged enums reject the bare form for variants with optional
//! arguments, so the dispatch is written by hand; the arguments keep serde-saphyr's spans.

/// Define an enum whose YAML form is a one-key mapping `name: args` (or a bare `name` for
/// variants marked `bare`, which take their arguments' `Default`).
macro_rules! one_key_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident ($what:literal) {
            $( $key:literal => $variant:ident($ty:ty) $([$bare:ident])? ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug)]
        $vis enum $name {
            $( #[doc = concat!("`", $key, "`")] $variant($ty), )*
        }

        impl $name {
            /// Every key this enum accepts, in declaration order.
            #[allow(dead_code)]
            pub const KEYS: &'static [&'static str] = &[$($key),*];
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                struct Visit;
                impl<'de> serde::de::Visitor<'de> for Visit {
                    type Value = $name;
                    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                        write!(f, "{} (one of: {})", $what, $name::KEYS.join(", "))
                    }
                    fn visit_str<E: serde::de::Error>(self, text: &str) -> Result<$name, E> {
                        match text {
                            $( $key => one_key_enum!(@bare E, $name, $variant, $key $(, $bare)?), )*
                            other => Err(E::custom(format!(
                                "unknown {} `{}`; expected one of: {}{}",
                                $what, other, $name::KEYS.join(", "),
                                $crate::harness::error::suggestion(other, $name::KEYS)
                            ))),
                        }
                    }
                    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<$name, A::Error> {
                        use serde::de::Error as _;
                        let Some(key) = map.next_key::<String>()? else {
                            return Err(A::Error::custom(format!(
                                "empty mapping; expected a {} (one of: {})",
                                $what, $name::KEYS.join(", ")
                            )));
                        };
                        let value = match key.as_str() {
                            $( $key => {
                                let args: Option<$ty> = map.next_value()?;
                                match args {
                                    Some(args) => $name::$variant(args),
                                    None => one_key_enum!(@bare A::Error, $name, $variant, $key $(, $bare)?)?,
                                }
                            } )*
                            other => {
                                return Err(A::Error::custom(format!(
                                    "unknown {} `{}`; expected one of: {}{}",
                                    $what, other, $name::KEYS.join(", "),
                                    $crate::harness::error::suggestion(other, $name::KEYS)
                                )))
                            }
                        };
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
