//! Query steps: firmware identity, joint and end-effector limits, collision levels, gripper
//! parameters, each with the reply a scenario may expect.

use super::{action, Common, Labeled};
use crate::devices::piper::model::*;
use crate::devices::piper::raw::*;
use crate::devices::piper::validate::*;
use crate::scenario::{Ctx, Pos, Res};

/// A query step: its label and action.
pub(super) fn step(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<Labeled> {
    use PiperAction as P;
    Ok(match raw {
        RawStep::QueryFirmware(a) => (
            "query_firmware",
            action(
                ctx,
                common!(a),
                at,
                P::QueryFirmware {
                    expect: a.expect.as_ref().map(|e| e.value.clone()),
                },
            )?,
        ),
        RawStep::QueryJointLimits(a) => {
            let joint = ctx.joint_required(&a.joint, "query_joint_limits", at, false)?;
            let e = a.expect.as_ref().map(|e| &e.value);
            let tol_deg = 0.1;
            let tol_speed = 0.01;
            let (min_deg, max_deg, max_speed_rad_s) = match e {
                Some(e) => (
                    near(ctx, &e.min_deg, "min_deg", tol_deg)?,
                    near(ctx, &e.max_deg, "max_deg", tol_deg)?,
                    near(ctx, &e.max_speed_rad_s, "max_speed_rad_s", tol_speed)?,
                ),
                None => (None, None, None),
            };
            (
                "query_joint_limits",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::QueryJointLimits {
                        joint,
                        min_deg,
                        max_deg,
                        max_speed_rad_s,
                    },
                )?,
            )
        }
        RawStep::QueryJointAcc(a) => {
            let joint = ctx.joint_required(&a.joint, "query_joint_max_acc", at, false)?;
            let max_acc_rad_s2 = match &a.expect {
                Some(e) => near(ctx, &e.value.max_acc_rad_s2, "max_acc_rad_s2", 0.01)?,
                None => None,
            };
            (
                "query_joint_max_acc",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::QueryJointAcc {
                        joint,
                        max_acc_rad_s2,
                    },
                )?,
            )
        }
        RawStep::QueryEndLimits(a) => {
            let expect = match &a.expect {
                Some(e) => [
                    near(ctx, &e.value.linear_m_s, "linear_m_s", 0.001)?,
                    near(ctx, &e.value.angular_rad_s, "angular_rad_s", 0.001)?,
                    near(ctx, &e.value.linear_acc_m_s2, "linear_acc_m_s2", 0.001)?,
                    near(
                        ctx,
                        &e.value.angular_acc_rad_s2,
                        "angular_acc_rad_s2",
                        0.001,
                    )?,
                ],
                None => [None; 4],
            };
            (
                "query_end_limits",
                action(ctx, common!(a), at, P::QueryEndLimits { expect })?,
            )
        }
        RawStep::QueryCollision(a) => {
            let expect = match a.expect.as_ref().and_then(|e| e.value.levels.as_ref()) {
                Some(l) => Some(levels(ctx, l)?),
                None => None,
            };
            (
                "query_collision_levels",
                action(ctx, common!(a), at, P::QueryCollision { expect })?,
            )
        }
        RawStep::QueryGripperParams(a) => {
            let expect = match &a.expect {
                Some(e) => [
                    small_uint(ctx, &e.value.max_stroke_mm, "max_stroke_mm", 0..=255)?,
                    small_uint(
                        ctx,
                        &e.value.teach_coefficient_pct,
                        "teach_coefficient_pct",
                        0..=255,
                    )?,
                    small_uint(ctx, &e.value.friction, "friction", 0..=255)?,
                ],
                None => [None; 3],
            };
            (
                "query_gripper_params",
                action(ctx, common!(a), at, P::QueryGripperParams { expect })?,
            )
        }
        _ => unreachable!("validate::step routes only these steps here"),
    })
}
