//! The `realman:` step: which keys each command takes, and the commands of the original
//! vocabulary (moves, stops, power, push, gripper, hand); the later families live in
//! [`super::stream`], [`super::jog`] and [`super::params`].

use super::super::model::{Motion, PoseDeg, RealmanAction, RmCommand};
use super::super::raw::RawRmStep;
use super::{int_in, jog, joints, params, stream, MAX_CLIENTS};
use crate::scenario::error::Pos;
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};
use crate::scenario::{DeviceStep, Near};

/// Which argument keys each command takes (`client` aside).
const COMMAND_KEYS: [(&str, &[&str]); 36] = [
    ("handshake", &[]),
    ("movej", &["joints_deg", "speed", "blend", "queue", "block"]),
    (
        "movel",
        &[
            "position_m",
            "euler_deg",
            "speed",
            "blend",
            "queue",
            "block",
        ],
    ),
    ("movej_p", &["position_m", "euler_deg", "speed", "block"]),
    (
        "movec",
        &[
            "via_position_m",
            "via_euler_deg",
            "position_m",
            "euler_deg",
            "loops",
            "speed",
            "block",
        ],
    ),
    ("stop", &[]),
    ("slow_stop", &[]),
    ("pause", &[]),
    ("continue", &[]),
    ("delete_trajectories", &[]),
    ("clear_errors", &[]),
    ("power", &["on"]),
    ("push", &["period_ms", "enable"]),
    ("gripper_position", &["position", "block"]),
    ("gripper_pick", &["speed", "force", "block"]),
    ("gripper_release", &["speed", "block"]),
    ("read_gripper", &["expect", "tolerance"]),
    ("hand_posture", &["posture", "block"]),
    ("hand_angles", &["angles", "block"]),
    ("read_joints", &[]),
    ("reconnect", &[]),
    (
        "stream_joints",
        &[
            "from_deg",
            "to_deg",
            "duration_ms",
            "period_ms",
            "mode",
            "block",
        ],
    ),
    (
        "stream_pose",
        &[
            "from_position_m",
            "from_euler_deg",
            "position_m",
            "euler_deg",
            "duration_ms",
            "period_ms",
            "mode",
            "block",
        ],
    ),
    ("set_joint_step", &["joint", "step_deg", "speed", "block"]),
    ("set_pos_step", &["axis", "step_m", "speed", "block"]),
    ("set_ort_step", &["axis", "step_deg", "speed", "block"]),
    ("set_joint_teach", &["joint", "direction", "speed"]),
    ("set_pos_teach", &["axis", "direction", "speed"]),
    ("set_ort_teach", &["axis", "direction", "speed"]),
    ("set_stop_teach", &[]),
    ("set_param", &["name", "joint", "value"]),
    ("get_param", &["name", "joint", "expect", "tolerance"]),
    ("reset_params", &[]),
    ("reset_dh", &[]),
    ("set_zero_offset", &["joints_deg"]),
    ("joint_enable", &["joint", "on"]),
];

fn present_keys(a: &RawRmStep) -> Vec<(&'static str, Pos)> {
    let mut out = Vec::new();
    macro_rules! keys {
        ($($field:ident),* $(,)?) => {
            $(if let Some(v) = &a.$field { out.push((stringify!($field), pos(v))); })*
        };
    }
    keys!(
        joints_deg,
        position_m,
        euler_deg,
        via_position_m,
        via_euler_deg,
        loops,
        speed,
        blend,
        queue,
        block,
        position,
        force,
        posture,
        angles,
        period_ms,
        enable,
        on,
        expect,
        tolerance,
        from_deg,
        to_deg,
        from_position_m,
        from_euler_deg,
        duration_ms,
        mode,
        joint,
        axis,
        direction,
        step_deg,
        step_m,
        name,
        value,
    );
    out
}

pub(super) fn pose(
    ctx: &Ctx<'_>,
    position: &Option<S<Vec<f64>>>,
    euler: &Option<S<Vec<f64>>>,
    names: (&str, &str),
    command: &str,
    at: Pos,
) -> Res<PoseDeg> {
    let p = ctx.required(position, names.0, command, at)?;
    let e = ctx.required(euler, names.1, command, at)?;
    Ok(PoseDeg {
        position_m: ctx.array::<3>(p, names.0)?,
        euler_deg: ctx.array::<3>(e, names.1)?,
    })
}

fn motion(ctx: &Ctx<'_>, a: &RawRmStep) -> Res<Motion> {
    let speed = match &a.speed {
        Some(s) => int_in(ctx, s, "speed", 1, 100)? as u8,
        None => 20,
    };
    let blend = match &a.blend {
        Some(b) => int_in(ctx, b, "blend", 0, 100)? as u8,
        None => 0,
    };
    Ok(Motion {
        speed,
        blend,
        queue: a.queue.as_ref().is_some_and(|q| q.value),
        block: a.block.as_ref().is_none_or(|b| b.value),
    })
}

fn command(ctx: &Ctx<'_>, a: &RawRmStep, name: &str, at: Pos) -> Res<RmCommand> {
    let block = a.block.as_ref().is_none_or(|b| b.value);
    let unit = |v: &Option<S<i64>>, key: &str, lo: i64, default: i64| -> Res<u16> {
        v.as_ref()
            .map_or(Ok(default), |v| int_in(ctx, v, key, lo, 1000))
            .map(|x| x as u16)
    };
    Ok(match name {
        "handshake" => RmCommand::Handshake,
        "movej" => {
            let j = ctx.required(&a.joints_deg, "joints_deg", name, at)?;
            let dof = j.value.len().clamp(6, 7);
            RmCommand::MoveJ(joints(ctx, j, "joints_deg", dof)?, motion(ctx, a)?)
        }
        "movel" => RmCommand::MoveL(
            pose(
                ctx,
                &a.position_m,
                &a.euler_deg,
                ("position_m", "euler_deg"),
                name,
                at,
            )?,
            motion(ctx, a)?,
        ),
        "movej_p" => RmCommand::MoveJP(
            pose(
                ctx,
                &a.position_m,
                &a.euler_deg,
                ("position_m", "euler_deg"),
                name,
                at,
            )?,
            motion(ctx, a)?,
        ),
        "movec" => RmCommand::MoveC {
            via: pose(
                ctx,
                &a.via_position_m,
                &a.via_euler_deg,
                ("via_position_m", "via_euler_deg"),
                name,
                at,
            )?,
            to: pose(
                ctx,
                &a.position_m,
                &a.euler_deg,
                ("position_m", "euler_deg"),
                name,
                at,
            )?,
            loops: a
                .loops
                .as_ref()
                .map_or(Ok(0), |l| int_in(ctx, l, "loops", 0, 100))? as u32,
            motion: motion(ctx, a)?,
        },
        "stop" => RmCommand::Stop,
        "slow_stop" => RmCommand::SlowStop,
        "pause" => RmCommand::Pause,
        "continue" => RmCommand::Continue,
        "delete_trajectories" => RmCommand::DeleteTrajectories,
        "clear_errors" => RmCommand::ClearErrors,
        "power" => RmCommand::Power(ctx.required(&a.on, "on", name, at)?.value),
        "push" => {
            let p = ctx.required(&a.period_ms, "period_ms", name, at)?;
            let period_ms = int_in(ctx, p, "period_ms", 5, 500)?;
            if period_ms % 5 != 0 {
                return Err(ctx.err(pos(p), "`period_ms` must be a multiple of 5"));
            }
            RmCommand::Push {
                period_ms: period_ms as u32,
                enable: a.enable.as_ref().is_none_or(|e| e.value),
            }
        }
        "gripper_position" => RmCommand::GripperPosition {
            position: int_in(
                ctx,
                ctx.required(&a.position, "position", name, at)?,
                "position",
                1,
                1000,
            )? as u16,
            block,
        },
        "gripper_pick" => RmCommand::GripperPick {
            speed: unit(&a.speed, "speed", 1, 500)?,
            force: unit(&a.force, "force", 50, 200)?,
            block,
        },
        "gripper_release" => RmCommand::GripperRelease {
            speed: unit(&a.speed, "speed", 1, 500)?,
            block,
        },
        "read_gripper" => RmCommand::ReadGripper {
            expect: match &a.expect {
                Some(e) => Some(Near {
                    value: ctx.finite(e, "expect")?,
                    tolerance: a
                        .tolerance
                        .as_ref()
                        .map_or(Ok(5.0), |t| ctx.non_negative(t, "tolerance"))?,
                }),
                None => None,
            },
        },
        "hand_posture" => RmCommand::HandPosture {
            posture: int_in(
                ctx,
                ctx.required(&a.posture, "posture", name, at)?,
                "posture",
                1,
                40,
            )? as u8,
            block,
        },
        "hand_angles" => {
            let v = ctx.required(&a.angles, "angles", name, at)?;
            if v.value.len() != 6 || v.value.iter().any(|x| !(-1..=1000).contains(x)) {
                return Err(ctx.err(
                    pos(v),
                    "`angles` needs 6 values in 0..=1000 (-1 keeps a finger)",
                ));
            }
            let mut angles = [None; 6];
            for (slot, x) in angles.iter_mut().zip(&v.value) {
                *slot = u16::try_from(*x).ok();
            }
            RmCommand::HandAngles { angles, block }
        }
        "read_joints" => RmCommand::ReadJoints,
        "reconnect" => RmCommand::Reconnect,
        "stream_joints" | "stream_pose" => stream::command(ctx, a, name, at)?,
        "set_joint_step" | "set_pos_step" | "set_ort_step" | "set_joint_teach"
        | "set_pos_teach" | "set_ort_teach" | "set_stop_teach" => jog::command(ctx, a, name, at)?,
        _ => params::command(ctx, a, name, at)?,
    })
}

/// A `realman:` step.
pub(super) fn realman_step(
    ctx: &Ctx<'_>,
    a: &RawRmStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<RealmanAction>)> {
    let names: Vec<&str> = COMMAND_KEYS.iter().map(|(n, _)| *n).collect();
    let Some(cmd) = &a.command else {
        return Err(ctx.err(
            at,
            format!("`realman` needs `do:` with one of: {}", names.join(", ")),
        ));
    };
    let table: Vec<(&str, &str)> = names.iter().map(|n| (*n, *n)).collect();
    let name = ctx.choice(cmd, "do", &table)?;
    let allowed = COMMAND_KEYS
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(&[][..], |(_, k)| *k);
    ctx.only_arguments(
        &present_keys(a),
        allowed,
        name,
        "no arguments besides `client`",
    )?;
    let command = command(ctx, a, name, at)?;
    let client = match &a.client {
        Some(c) => int_in(ctx, c, "client", 1, MAX_CLIENTS)? as usize - 1,
        None => 0,
    };
    let device = ctx.device_of_kind(&a.device, at, "realman", "this step")?;
    let timeout = ctx.timeout(&a.timeout_ms)?;
    let expect_error = ctx.expect_error(&a.expect_error)?;
    let label = LABELS
        .iter()
        .find(|(n, _)| *n == name)
        .map_or("realman", |(_, l)| l);
    Ok((
        label,
        DeviceStep {
            device,
            action: RealmanAction { client, command },
            timeout,
            expect_error,
        },
    ))
}

/// Step labels for reports (`realman <command>`, static for the report).
const LABELS: [(&str, &str); 36] = [
    ("handshake", "realman handshake"),
    ("movej", "realman movej"),
    ("movel", "realman movel"),
    ("movej_p", "realman movej_p"),
    ("movec", "realman movec"),
    ("stop", "realman stop"),
    ("slow_stop", "realman slow_stop"),
    ("pause", "realman pause"),
    ("continue", "realman continue"),
    ("delete_trajectories", "realman delete_trajectories"),
    ("clear_errors", "realman clear_errors"),
    ("power", "realman power"),
    ("push", "realman push"),
    ("gripper_position", "realman gripper_position"),
    ("gripper_pick", "realman gripper_pick"),
    ("gripper_release", "realman gripper_release"),
    ("read_gripper", "realman read_gripper"),
    ("hand_posture", "realman hand_posture"),
    ("hand_angles", "realman hand_angles"),
    ("read_joints", "realman read_joints"),
    ("reconnect", "realman reconnect"),
    ("stream_joints", "realman stream_joints"),
    ("stream_pose", "realman stream_pose"),
    ("set_joint_step", "realman set_joint_step"),
    ("set_pos_step", "realman set_pos_step"),
    ("set_ort_step", "realman set_ort_step"),
    ("set_joint_teach", "realman set_joint_teach"),
    ("set_pos_teach", "realman set_pos_teach"),
    ("set_ort_teach", "realman set_ort_teach"),
    ("set_stop_teach", "realman set_stop_teach"),
    ("set_param", "realman set_param"),
    ("get_param", "realman get_param"),
    ("reset_params", "realman reset_params"),
    ("reset_dh", "realman reset_dh"),
    ("set_zero_offset", "realman set_zero_offset"),
    ("joint_enable", "realman joint_enable"),
];

#[cfg(test)]
mod tests {
    use super::{COMMAND_KEYS, LABELS};

    #[test]
    fn every_command_has_its_label() {
        for ((name, _), (label_of, label)) in COMMAND_KEYS.iter().zip(LABELS.iter()) {
            assert_eq!(name, label_of);
            assert_eq!(*label, format!("realman {name}"));
        }
    }
}
