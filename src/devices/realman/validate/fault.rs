//! The `fault:` entries of a Realman scenario: the arguments as written, handed to the
//! emulator's one fault builder ([`RealmanFaultKind::build`]), whose refusal is shown at the
//! line and column of the argument it is about (or of the fault, for a missing one).

use sim::fault_args::{FaultArgValue, FaultArgs};
#[cfg(doc)]
use sim::realman::RealmanFaultKind;

use crate::devices::realman::model::RmFault;
use crate::devices::realman::raw::{RawFault, RawFaultArgs};
use crate::scenario::error::Pos;
use crate::scenario::{pos, Ctx, Res, S};

/// Every argument a Realman fault can be written with, by name.
fn written(args: &RawFaultArgs) -> [(&'static str, Option<&S<i64>>); 6] {
    [
        ("delay_ms", args.delay_ms.as_ref()),
        ("count", args.count.as_ref()),
        ("permille", args.permille.as_ref()),
        ("joint", args.joint.as_ref()),
        ("code", args.code.as_ref()),
        ("bits", args.bits.as_ref()),
    ]
}

/// A Realman emulator fault with its arguments.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RmFault> {
    let written = written(&raw.args);
    let mut args = FaultArgs::new();
    for (name, value) in &written {
        if let Some(value) = value {
            // Every accepted value is far below 2^53, so the conversion is exact for them.
            args.push(*name, FaultArgValue::Number(value.value as f64));
        }
    }
    raw.kind.build(&args).map(RmFault).map_err(|e| {
        let place = e
            .arg
            .as_deref()
            .and_then(|arg| written.iter().find(|(name, _)| *name == arg))
            .and_then(|(_, value)| *value)
            .map_or(at, pos);
        ctx.err(place, e.message)
    })
}
