//! A RobStride emulator fault in a scenario's `faults:` list.

use sim::fault_args::{FaultArgValue, FaultArgs};

use crate::devices::robstride::model::RsFault;
use crate::devices::robstride::raw::RawFault;
use crate::scenario::error::Pos;
use crate::scenario::{pos, Ctx, Res};

/// A RobStride emulator fault on one motor, made by the emulator's one fault builder
/// ([`sim::robstride::Fault::build`]) so that scenario files, the web view and Python accept the
/// same and say the same; an error points at `motor` when it is about it.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RsFault> {
    let mut args = FaultArgs::new();
    if let Some(m) = &raw.args.motor {
        // A CAN ID is a small integer: exact as f64 (a huge one is refused by its range).
        args.push("motor", FaultArgValue::Number(m.value as f64));
    }
    let built = raw.kind.build(&args).map_err(|e| {
        let span = match (e.arg.as_deref(), &raw.args.motor) {
            (Some("motor"), Some(m)) => pos(m),
            _ => at,
        };
        ctx.err(span, e.message)
    })?;
    Ok(RsFault {
        motor: built.motor,
        fault: built.fault,
    })
}
