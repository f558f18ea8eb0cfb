//! Motion steps: enabling, modes, MOVE J/P/L/C, MIT, the gripper, stopping.

use super::{action, Common, Labeled};
use crate::devices::piper::model::*;
use crate::devices::piper::raw::*;
use crate::devices::piper::validate::*;
use crate::scenario::{pos, Ctx, Pos, Res};

/// A motion step: its label and action.
pub(super) fn step(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<Labeled> {
    use PiperAction as P;
    Ok(match raw {
        RawStep::Enable(a) => {
            let joints = a
                .joints
                .as_ref()
                .map(|j| ctx.joints_list(j, "joints"))
                .transpose()?
                .unwrap_or_default();
            (
                "enable",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::Enable {
                        joints,
                        gripper: a.gripper.unwrap_or(false),
                    },
                )?,
            )
        }
        RawStep::Disable(a) => {
            if a.gripper.is_some() {
                return Err(ctx.err(
                    at,
                    "`disable` takes no `gripper` (use `gripper: {enable: false, ...}`)",
                ));
            }
            let joints = a
                .joints
                .as_ref()
                .map(|j| ctx.joints_list(j, "joints"))
                .transpose()?
                .unwrap_or_default();
            (
                "disable",
                action(ctx, common!(a), at, P::Disable { joints })?,
            )
        }
        RawStep::Mode(a) => {
            let ctrl = match &a.ctrl {
                None => CtrlMode::Can,
                Some(c) => ctx.choice(
                    c,
                    "ctrl",
                    &[(CtrlMode::Can, "can"), (CtrlMode::Standby, "standby")],
                )?,
            };
            let move_mode = match &a.move_mode {
                None => MoveMode::J,
                Some(m) => ctx.choice(
                    m,
                    "move",
                    &[
                        (MoveMode::P, "p"),
                        (MoveMode::J, "j"),
                        (MoveMode::L, "l"),
                        (MoveMode::C, "c"),
                        (MoveMode::M, "m"),
                    ],
                )?,
            };
            let install = a
                .install
                .as_ref()
                .map(|i| {
                    ctx.choice(
                        i,
                        "install",
                        &[
                            (Install::Upright, "upright"),
                            (Install::Left, "left"),
                            (Install::Right, "right"),
                        ],
                    )
                })
                .transpose()?;
            let speed_pct = ctx.pct(&a.speed_pct)?;
            let mit = a.mit.unwrap_or(move_mode == MoveMode::M);
            (
                "mode",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::Mode {
                        ctrl,
                        move_mode,
                        speed_pct,
                        mit,
                        install,
                    },
                )?,
            )
        }
        RawStep::MoveJ(a) => {
            let j = ctx.required(&a.joints_deg, "joints_deg", "move_j", at)?;
            let joints_deg = ctx.array::<PIPER_JOINTS>(j, "joints_deg")?;
            (
                "move_j",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::MoveJ {
                        joints_deg,
                        speed_pct: ctx.pct(&a.speed_pct)?,
                        every_ms: ctx.every_ms(&a.every_ms)?,
                    },
                )?,
            )
        }
        RawStep::MoveP(a) => {
            let pose = pose(ctx, &a.position_mm, &a.orientation_deg, "move_p", at)?;
            (
                "move_p",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::MoveP {
                        pose,
                        speed_pct: ctx.pct(&a.speed_pct)?,
                        every_ms: ctx.every_ms(&a.every_ms)?,
                    },
                )?,
            )
        }
        RawStep::MoveL(a) => {
            let pose = pose(ctx, &a.position_mm, &a.orientation_deg, "move_l", at)?;
            (
                "move_l",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::MoveL {
                        pose,
                        speed_pct: ctx.pct(&a.speed_pct)?,
                        every_ms: ctx.every_ms(&a.every_ms)?,
                    },
                )?,
            )
        }
        RawStep::MoveC(a) => {
            let start = raw_pose(ctx, &a.start, "start", at)?;
            let middle = raw_pose(ctx, &a.middle, "middle", at)?;
            let end = raw_pose(ctx, &a.end, "end", at)?;
            (
                "move_c",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::MoveC {
                        start,
                        middle,
                        end,
                        speed_pct: ctx.pct(&a.speed_pct)?,
                        every_ms: ctx.every_ms(&a.every_ms)?,
                    },
                )?,
            )
        }
        RawStep::Mit(a) => {
            let joint = ctx.joint_required(&a.joint, "mit", at, false)?;
            let num = |v: &Option<S<f64>>, key: &str, default: f64| -> Res<f64> {
                v.as_ref().map_or(Ok(default), |v| ctx.finite(v, key))
            };
            let kp = num(&a.kp, "kp", 10.0)?;
            let kd = num(&a.kd, "kd", 0.8)?;
            if !(0.0..=500.0).contains(&kp) {
                return Err(ctx.err(
                    a.kp.as_ref().map_or(at, pos),
                    format!("`kp` must be 0..=500, got {kp}"),
                ));
            }
            if !(-5.0..=5.0).contains(&kd) {
                return Err(ctx.err(
                    a.kd.as_ref().map_or(at, pos),
                    format!("`kd` must be -5..=5, got {kd}"),
                ));
            }
            (
                "mit",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::Mit {
                        joint,
                        position_deg: num(&a.position_deg, "position_deg", 0.0)?,
                        velocity_deg_s: num(&a.velocity_deg_s, "velocity_deg_s", 0.0)?,
                        kp,
                        kd,
                        torque_nm: num(&a.torque_nm, "torque_nm", 0.0)?,
                    },
                )?,
            )
        }
        RawStep::Gripper(a) => {
            let stroke = ctx.required(&a.stroke_mm, "stroke_mm", "gripper", at)?;
            let stroke_mm = ctx.non_negative(stroke, "stroke_mm")?;
            let torque_nm = match &a.torque_nm {
                Some(t) => {
                    let v = ctx.non_negative(t, "torque_nm")?;
                    if v > 5.0 {
                        return Err(ctx.err(pos(t), format!("`torque_nm` must be 0..=5, got {v}")));
                    }
                    v
                }
                None => 1.0,
            };
            (
                "gripper",
                action(
                    ctx,
                    common!(a),
                    at,
                    P::Gripper {
                        stroke_mm,
                        torque_nm,
                        enable: a.enable.unwrap_or(true),
                        clear_error: a.clear_error.unwrap_or(false),
                        every_ms: ctx.every_ms(&a.every_ms)?,
                    },
                )?,
            )
        }
        RawStep::GripperZero(a) => ("gripper_zero", action(ctx, common!(a), at, P::GripperZero)?),
        RawStep::Estop(a) => ("estop", action(ctx, common!(a), at, P::Estop)?),
        RawStep::Reset(a) => ("reset", action(ctx, common!(a), at, P::Reset)?),
        _ => unreachable!("validate::step routes only these steps here"),
    })
}
