//! Step jogs (`set_joint_step`, `set_pos_step`, `set_ort_step`) and teach jogs
//! (`set_joint_teach`, `set_pos_teach`, `set_ort_teach`, `set_stop_teach`), with the names and
//! arguments of docs/protocols/realman.md §3 (steps in degrees and metres).

use super::super::model::{JogTarget, RmCommand, JOG_AXES};
use super::super::raw::RawRmStep;
use super::int_in;
use crate::scenario::error::Pos;
use crate::scenario::{Ctx, Res};

/// `direction:` names as on the wire.
const DIRECTIONS: [(bool, &str); 2] = [(true, "pos"), (false, "neg")];
/// Default jog speed, %.
const DEFAULT_SPEED: i64 = 20;

/// What a jog command moves: `joint:` for the joint forms, `axis:` for the others.
fn target(ctx: &Ctx<'_>, a: &RawRmStep, name: &str, at: Pos) -> Res<JogTarget> {
    if name.starts_with("set_joint_") {
        let j = ctx.required(&a.joint, "joint", name, at)?;
        return Ok(JogTarget::Joint(int_in(ctx, j, "joint", 1, 7)? as u8));
    }
    let axis = ctx.choice(ctx.required(&a.axis, "axis", name, at)?, "axis", &JOG_AXES)?;
    Ok(if name.starts_with("set_pos_") {
        JogTarget::Position(axis)
    } else {
        JogTarget::Orientation(axis)
    })
}

/// A jog step.
pub(super) fn command(ctx: &Ctx<'_>, a: &RawRmStep, name: &str, at: Pos) -> Res<RmCommand> {
    if name == "set_stop_teach" {
        return Ok(RmCommand::StopTeach);
    }
    let target = target(ctx, a, name, at)?;
    let speed = a
        .speed
        .as_ref()
        .map_or(Ok(DEFAULT_SPEED), |s| int_in(ctx, s, "speed", 1, 100))? as u8;
    if name.ends_with("_teach") {
        let dir = ctx.required(&a.direction, "direction", name, at)?;
        return Ok(RmCommand::Teach {
            target,
            positive: ctx.choice(dir, "direction", &DIRECTIONS)?,
            speed,
        });
    }
    let amount = if name == "set_pos_step" {
        ctx.finite(ctx.required(&a.step_m, "step_m", name, at)?, "step_m")?
    } else {
        ctx.finite(ctx.required(&a.step_deg, "step_deg", name, at)?, "step_deg")?
    };
    Ok(RmCommand::Step {
        target,
        amount,
        speed,
        block: a.block.as_ref().is_none_or(|b| b.value),
    })
}
