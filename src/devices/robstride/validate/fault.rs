//! A RobStride emulator fault in a scenario's `faults:` list.

use crate::devices::robstride::model::RsFault;
use crate::devices::robstride::raw::RawFault;
use crate::scenario::error::Pos;
use crate::scenario::{Ctx, Res};

/// A RobStride emulator fault on one motor, made by the emulator's one fault builder
/// ([`sim::robstride::Fault::build`]) so that scenario files, the web view and Python accept the
/// same and say the same; an error points at the argument it is about.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RsFault> {
    let built = raw.args.build(ctx, at, |args| raw.kind.build(args))?;
    Ok(RsFault {
        motor: built.motor,
        fault: built.fault,
    })
}
