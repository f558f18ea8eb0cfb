//! Motion parameters (docs/protocols/realman.md §8, §9): `set_param` / `get_param` by name
//! (units in the names), `reset_params` (`set_arm_init`), `reset_dh` (`set_DH_data_default`),
//! `set_zero_offset` and `joint_enable`. Values are not range-checked here: refusing them is
//! the driver's and the controller's job, and scenarios show how they refuse.

use super::super::model::{Param, RmCommand, PARAMS};
use super::super::raw::RawRmStep;
use super::{int_in, joints};
use crate::scenario::error::Pos;
use crate::scenario::Near;
use crate::scenario::{pos, Ctx, Res};

/// Default tolerance of a `get_param` expectation (one wire unit of most parameters).
const DEFAULT_TOLERANCE: f64 = 0.001;

/// The parameter `name:` names and its `joint:` (required exactly for per-joint parameters).
fn param(ctx: &Ctx<'_>, a: &RawRmStep, command: &str, at: Pos) -> Res<(Param, Option<u8>)> {
    let name = ctx.required(&a.name, "name", command, at)?;
    let table: Vec<(Param, &str)> = PARAMS.iter().map(|(p, n, _)| (*p, *n)).collect();
    let param = ctx.choice(name, "name", &table)?;
    let joint = match (&a.joint, param.per_joint()) {
        (Some(j), true) => Some(int_in(ctx, j, "joint", 1, 7)? as u8),
        (None, true) => {
            return Err(ctx.err(
                pos(name),
                format!(
                    "`{}` belongs to one joint: say which with `joint:`",
                    param.name()
                ),
            ))
        }
        (Some(j), false) => {
            return Err(ctx.err(
                pos(j),
                format!("`{}` is not per joint: drop `joint:`", param.name()),
            ))
        }
        (None, false) => None,
    };
    Ok((param, joint))
}

/// A parameter step.
pub(super) fn command(ctx: &Ctx<'_>, a: &RawRmStep, name: &str, at: Pos) -> Res<RmCommand> {
    Ok(match name {
        "set_param" => {
            let (param, joint) = param(ctx, a, name, at)?;
            let v = ctx.required(&a.value, "value", name, at)?;
            let value = ctx.finite(v, "value")?;
            let bad = match param {
                Param::CollisionStage => value.fract() != 0.0,
                Param::SelfCollision => value != 0.0 && value != 1.0,
                _ => false,
            };
            if bad {
                let wants = if param == Param::SelfCollision {
                    "0 or 1"
                } else {
                    "a whole number"
                };
                return Err(ctx.err(
                    pos(v),
                    format!("`{}` takes {wants}, got {value}", param.name()),
                ));
            }
            RmCommand::SetParam {
                param,
                joint,
                value,
            }
        }
        "get_param" => {
            let (param, joint) = param(ctx, a, name, at)?;
            let expect = match &a.expect {
                Some(e) => Some(Near {
                    value: ctx.finite(e, "expect")?,
                    tolerance: a
                        .tolerance
                        .as_ref()
                        .map_or(Ok(DEFAULT_TOLERANCE), |t| ctx.non_negative(t, "tolerance"))?,
                }),
                None => None,
            };
            RmCommand::GetParam {
                param,
                joint,
                expect,
            }
        }
        "reset_params" => RmCommand::ResetParams,
        "reset_dh" => RmCommand::ResetDh,
        "set_zero_offset" => {
            let j = ctx.required(&a.joints_deg, "joints_deg", name, at)?;
            let dof = j.value.len().clamp(6, 7);
            RmCommand::SetZeroOffset(joints(ctx, j, "joints_deg", dof)?)
        }
        _ => RmCommand::JointEnable {
            joint: int_in(
                ctx,
                ctx.required(&a.joint, "joint", name, at)?,
                "joint",
                1,
                7,
            )? as u8,
            on: ctx.required(&a.on, "on", name, at)?.value,
        },
    })
}
