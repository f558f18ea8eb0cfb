//! Configuration steps: limits, collision levels, gripper parameters, zeroing, payload, role
//! (what the arm keeps in its flash).

use super::{action, Common, Labeled};
use crate::devices::piper::model::*;
use crate::devices::piper::raw::*;
use crate::devices::piper::validate::*;
use crate::scenario::{pos, Ctx, Pos, Res};

/// A configuration step: its label and action.
pub(super) fn step(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<Labeled> {
    use PiperAction as P;
    Ok(match raw {
        RawStep::SetJointLimits(a) => {
            let joint = ctx.joint_required(&a.joint, "set_joint_limits", at, false)?;
            let min_deg = a
                .min_deg
                .as_ref()
                .map(|v| ctx.finite(v, "min_deg"))
                .transpose()?;
            let max_deg = a
                .max_deg
                .as_ref()
                .map(|v| ctx.finite(v, "max_deg"))
                .transpose()?;
            if let (Some(lo), Some(hi)) = (min_deg, max_deg) {
                if lo > hi {
                    return Err(ctx.err(at, format!("`min_deg` ({lo}) is above `max_deg` ({hi})")));
                }
            }
            let max_speed_rad_s = a
                .max_speed_rad_s
                .as_ref()
                .map(|v| ctx.non_negative(v, "max_speed_rad_s"))
                .transpose()?;
            (
                "set_joint_limits",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::SetJointLimits {
                        joint,
                        min_deg,
                        max_deg,
                        max_speed_rad_s,
                    },
                )?,
            )
        }
        RawStep::SetJointAcc(a) => {
            let joint = ctx.joint_required(&a.joint, "set_joint_max_acc", at, true)?;
            let v = ctx.required(&a.max_acc_rad_s2, "max_acc_rad_s2", "set_joint_max_acc", at)?;
            let max_acc_rad_s2 = ctx.non_negative(v, "max_acc_rad_s2")?;
            if max_acc_rad_s2 > 5.0 {
                return Err(ctx.err(
                    pos(v),
                    format!("`max_acc_rad_s2` must be 0..=5, got {max_acc_rad_s2}"),
                ));
            }
            (
                "set_joint_max_acc",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::SetJointAcc {
                        joint,
                        max_acc_rad_s2,
                    },
                )?,
            )
        }
        RawStep::SetEndLimits(a) => {
            let nn = |v: &Option<S<f64>>, k: &str| {
                v.as_ref().map(|v| ctx.non_negative(v, k)).transpose()
            };
            let values = [
                nn(&a.linear_m_s, "linear_m_s")?,
                nn(&a.angular_rad_s, "angular_rad_s")?,
                nn(&a.linear_acc_m_s2, "linear_acc_m_s2")?,
                nn(&a.angular_acc_rad_s2, "angular_acc_rad_s2")?,
            ];
            (
                "set_end_limits",
                action(ctx, common!(a), at, P::SetEndLimits { values })?,
            )
        }
        RawStep::SetCollision(a) => {
            let l = ctx.required(&a.levels, "levels", "set_collision_levels", at)?;
            (
                "set_collision_levels",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::SetCollision {
                        levels: levels(ctx, l)?,
                    },
                )?,
            )
        }
        RawStep::SetGripperParams(a) => (
            "set_gripper_params",
            action(
                ctx,
                common!(a),
                at,
                P::SetGripperParams {
                    max_stroke_mm: small_uint(ctx, &a.max_stroke_mm, "max_stroke_mm", 0..=255)?,
                    teach_coefficient_pct: small_uint(
                        ctx,
                        &a.teach_coefficient_pct,
                        "teach_coefficient_pct",
                        100..=200,
                    )?,
                    friction: small_uint(ctx, &a.friction, "friction", 1..=10)?,
                },
            )?,
        ),
        RawStep::SetZero(a) => {
            let joint = ctx.joint_required(&a.joint, "set_zero", at, true)?;
            (
                "set_zero",
                action(ctx, common!(a), at, P::SetZero { joint })?,
            )
        }
        RawStep::ClearJointError(a) => {
            let joint = ctx.joint_required(&a.joint, "clear_joint_error", at, true)?;
            (
                "clear_joint_error",
                action(ctx, common!(a), at, P::ClearJointError { joint })?,
            )
        }
        RawStep::ResetParams(a) => ("reset_params", action(ctx, common!(a), at, P::ResetParams)?),
        RawStep::SetPayload(a) => {
            let p = ctx.required(&a.payload, "payload", "set_payload", at)?;
            let payload = ctx.choice(
                p,
                "payload",
                &[
                    (Payload::Empty, "empty"),
                    (Payload::Half, "half"),
                    (Payload::Full, "full"),
                ],
            )?;
            (
                "set_payload",
                action(ctx, common!(a), at, P::SetPayload { payload })?,
            )
        }
        RawStep::SetRole(a) => {
            let r = ctx.required(&a.role, "role", "set_role", at)?;
            let role = ctx.choice(
                r,
                "role",
                &[(Role::Leader, "leader"), (Role::Follower, "follower")],
            )?;
            (
                "set_role",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::SetRole {
                        role,
                        feedback_offset: offset(ctx, &a.feedback_offset, "feedback_offset")?,
                        control_offset: offset(ctx, &a.control_offset, "control_offset")?,
                        target_offset: offset(ctx, &a.target_offset, "target_offset")?,
                    },
                )?,
            )
        }
        _ => unreachable!("validate::step routes only these steps here"),
    })
}
