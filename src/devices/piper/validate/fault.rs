//! Layer 2 of a Piper emulator fault: the scenario front end of the emulator's one fault
//! builder ([`FaultKind::build`](sim::piper::FaultKind::build)), through the reader every kind
//! shares (`scenario::fault_args`): the builder's error is shown at the argument it is about.

use sim::piper::PiperFault;

use super::super::raw::RawFault;
use crate::scenario::{Ctx, Pos, Res};

/// A Piper emulator fault (`fpos`: where the fault is written).
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, fpos: Pos) -> Res<PiperFault> {
    raw.args.build(ctx, fpos, |args| raw.kind.build(args))
}
