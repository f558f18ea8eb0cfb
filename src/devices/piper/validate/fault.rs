//! Layer 2 of a Piper emulator fault: the scenario front end of the emulator's one fault
//! builder ([`FaultKind::build`](sim::piper::FaultKind::build)). It only turns the arguments as
//! written into [`FaultArgs`] and shows the builder's error at the argument it is about.

use sim::fault_args::{FaultArgValue, FaultArgs};
use sim::piper::PiperFault;

use super::super::raw::RawFault;
use crate::scenario::{pos, Ctx, Pos, Res};

/// A Piper emulator fault (`fpos`: where the fault is written).
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, fpos: Pos) -> Res<PiperFault> {
    let a = &raw.args;
    let mut args = FaultArgs::new();
    let mut written: Vec<(&str, Pos)> = Vec::new();
    if let Some(joint) = &a.joint {
        // Joints are whole numbers in the file; the builder checks the range.
        args.push("joint", FaultArgValue::Number(joint.value as f64));
        written.push(("joint", pos(joint)));
    }
    for (name, value) in [
        ("temp_c", &a.temp_c),
        ("voltage_v", &a.voltage_v),
        ("torque_nm", &a.torque_nm),
    ] {
        if let Some(v) = value {
            args.push(name, FaultArgValue::Number(v.value));
            written.push((name, pos(v)));
        }
    }
    if let Some(board) = &a.board {
        args.push("board", FaultArgValue::Text(board.value.clone()));
        written.push(("board", pos(board)));
    }
    raw.kind.build(&args).map_err(|e| {
        let at = e
            .arg
            .as_deref()
            .and_then(|arg| written.iter().find(|(name, _)| *name == arg))
            .map_or(fpos, |(_, at)| *at);
        ctx.err(at, e.message)
    })
}
