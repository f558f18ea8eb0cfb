//! A RobStride emulator fault in a scenario's `faults:` list.

use super::can_id;
use crate::devices::robstride::model::RsFault;
use crate::devices::robstride::raw::RawFault;
use crate::scenario::error::Pos;
use crate::scenario::{Ctx, Res};

/// A RobStride emulator fault on one motor.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RsFault> {
    let m = ctx.required(&raw.args.motor, "motor", "a robstride fault", at)?;
    Ok(RsFault {
        motor: can_id(ctx, m, "motor")?,
        fault: raw.kind,
    })
}
