//! The `fault:` entries of a Realman scenario: the arguments as written, handed to the
//! emulator's one fault builder ([`RealmanFaultKind::build`]) through the reader every kind
//! shares (`scenario::fault_args`), whose refusal is shown at the line and column of the
//! argument it is about (or of the fault, for a missing one).

#[cfg(doc)]
use sim::realman::RealmanFaultKind;

use crate::devices::realman::model::RmFault;
use crate::devices::realman::raw::RawFault;
use crate::scenario::error::Pos;
use crate::scenario::{Ctx, Res};

/// A Realman emulator fault with its arguments.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RmFault> {
    raw.args
        .build(ctx, at, |args| raw.kind.build(args))
        .map(RmFault)
}
