//! The scenario grammar core: what the harness and every device kind build their part of the
//! scenario language from, so that a kind depends on this module and never on the runner.
//!
//! - `S` and `pos`: values with their place in the file (serde-saphyr spans);
//! - [`Pos`], [`ScenarioError`], [`LoadError`]: errors that name file, line and column;
//! - `OneKey`: one-key mappings (`- move_j: {...}` or a bare `- estop`);
//! - `Ctx` and `Res`: what layer 2 (validation) knows while it walks a file, and the checks
//!   every key shares (durations, finite numbers, arrays, word choices, device names);
//! - [`vocab`]: the words every kind shares ([`Signal`], [`ErrorClass`], [`Near`]).
//!
//! The grammar itself is documented in `scenarios/README.md`.

mod ctx;
pub(crate) mod error;
pub(crate) mod fault_args;
pub(crate) mod onekey;
pub(crate) mod read_in;
pub mod vocab;

pub(crate) use ctx::{Ctx, Res, MAX_NAME_CHARS};
pub use error::{elide_long_tokens, LoadError, Pos, ScenarioError};
pub use vocab::{DeviceStep, ErrorClass, Near, Signal};

/// A value with its place in the scenario file.
pub(crate) type S<T> = serde_saphyr::Spanned<T>;

/// The position of a spanned value.
pub(crate) fn pos<T>(s: &S<T>) -> Pos {
    Pos::from_location(&s.referenced)
}
