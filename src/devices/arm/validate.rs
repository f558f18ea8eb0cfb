//! Layer 2 of the `arm` grammar: the `kind: arm` device (its vendor from `vendor:` or the
//! file's `matrix: {vendor: [...]}`), the `arm:` step, the conditions and the faults.

use driver::arm::Vendor;

use super::model::{
    error_codes, ArmAction, ArmCall, ArmCond, ArmFault, ArmSettings, MoveArgs, PoseDeg,
};
use super::raw::{RawArmStep, RawConds, RawFault, RawSettings, RawStep};
use crate::scenario::error::Pos;
use crate::scenario::DeviceStep;
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

/// Both vendors' arms have six joints.
const JOINTS: usize = 6;
/// Default tolerances of the conditions.
const DEFAULT_TOLERANCE_DEG: f64 = 0.1;
const DEFAULT_TOLERANCE_M: f64 = 0.001;

/// Each method the `arm` step calls, its step label and the argument keys it takes.
const METHODS: [(&str, &str, &[&str]); 14] = [
    ("connect", "arm connect", &[]),
    ("disconnect", "arm disconnect", &[]),
    (
        "move_joint_position",
        "arm move_joint_position",
        &["joints_deg", "v", "r", "trajectory_connect", "block"],
    ),
    (
        "move_cartesian_linear",
        "arm move_cartesian_linear",
        &[
            "position_m",
            "euler_deg",
            "v",
            "r",
            "trajectory_connect",
            "block",
        ],
    ),
    (
        "move_joint_pose",
        "arm move_joint_pose",
        &[
            "position_m",
            "euler_deg",
            "v",
            "r",
            "trajectory_connect",
            "block",
        ],
    ),
    (
        "move_joint_follow",
        "arm move_joint_follow",
        &["joints_deg"],
    ),
    ("set_arm_stop", "arm set_arm_stop", &[]),
    ("set_arm_slow_stop", "arm set_arm_slow_stop", &[]),
    ("set_arm_pause", "arm set_arm_pause", &[]),
    ("set_arm_continue", "arm set_arm_continue", &[]),
    (
        "set_gripper_position",
        "arm set_gripper_position",
        &["position", "block"],
    ),
    (
        "set_gripper_release",
        "arm set_gripper_release",
        &["speed", "block"],
    ),
    (
        "set_gripper_pick",
        "arm set_gripper_pick",
        &["speed", "force", "block"],
    ),
    ("get_joint_degree", "arm get_joint_degree", &[]),
];

/// The settings of a `kind: arm` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, at: Pos) -> Res<ArmSettings> {
    let vendors: Vec<(Vendor, &str)> = Vendor::ALL.iter().map(|v| (*v, v.name())).collect();
    let vendor = match (&d.vendor, ctx.matrix_value("vendor")) {
        (Some(v), None) => ctx.choice(v, "vendor", &vendors)?,
        (None, Some(m)) => vendors
            .iter()
            .find(|(_, n)| *n == m)
            .map(|(v, _)| *v)
            .ok_or_else(|| {
                ctx.err(
                    at,
                    format!(
                        "matrix vendor `{m}` is not an arm vendor ({})",
                        names(&vendors)
                    ),
                )
            })?,
        (Some(v), Some(_)) => {
            return Err(ctx.err(
                pos(v),
                "`vendor` is set by the file's `matrix:`; drop it here",
            ))
        }
        (None, None) => {
            return Err(ctx.err(
                at,
                format!(
                    "an arm needs `vendor:` ({}) or a `matrix: {{vendor: [...]}}` in the file",
                    names(&vendors)
                ),
            ))
        }
    };
    Ok(ArmSettings {
        vendor,
        gripper: d.gripper.as_ref().is_none_or(|g| g.value),
    })
}

fn names(vendors: &[(Vendor, &str)]) -> String {
    vendors
        .iter()
        .map(|(_, n)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

fn joints(ctx: &Ctx<'_>, v: &S<Vec<f64>>, key: &str) -> Res<Vec<f64>> {
    if v.value.len() != JOINTS || v.value.iter().any(|x| !x.is_finite()) {
        return Err(ctx.err(
            pos(v),
            format!(
                "`{key}` needs {JOINTS} finite angles (degrees), got {:?}",
                v.value
            ),
        ));
    }
    Ok(v.value.clone())
}

fn int_in(
    ctx: &Ctx<'_>,
    v: &Option<S<i64>>,
    key: &str,
    range: (i64, i64),
    default: i64,
) -> Res<i64> {
    match v {
        None => Ok(default),
        Some(v) if (range.0..=range.1).contains(&v.value) => Ok(v.value),
        Some(v) => Err(ctx.err(
            pos(v),
            format!(
                "`{key}`: {} out of range, expected {}..={}",
                v.value, range.0, range.1
            ),
        )),
    }
}

fn move_args(ctx: &Ctx<'_>, a: &RawArmStep) -> Res<MoveArgs> {
    Ok(MoveArgs {
        v: int_in(ctx, &a.v, "v", (1, 100), 20)? as u8,
        r: int_in(ctx, &a.r, "r", (0, 100), 0)? as u8,
        trajectory_connect: a.trajectory_connect.as_ref().is_some_and(|t| t.value),
        block: a.block.as_ref().is_none_or(|b| b.value),
    })
}

fn pose(ctx: &Ctx<'_>, a: &RawArmStep, method: &str, at: Pos) -> Res<PoseDeg> {
    let p = ctx.required(&a.position_m, "position_m", method, at)?;
    let e = ctx.required(&a.euler_deg, "euler_deg", method, at)?;
    Ok(PoseDeg {
        position_m: ctx.array::<3>(p, "position_m")?,
        euler_deg: ctx.array::<3>(e, "euler_deg")?,
    })
}

fn call(ctx: &Ctx<'_>, a: &RawArmStep, method: &str, at: Pos) -> Res<ArmCall> {
    let block = a.block.as_ref().is_none_or(|b| b.value);
    Ok(match method {
        "connect" => ArmCall::Connect,
        "disconnect" => ArmCall::Disconnect,
        "move_joint_position" => {
            let j = ctx.required(&a.joints_deg, "joints_deg", method, at)?;
            ArmCall::MoveJointPosition(joints(ctx, j, "joints_deg")?, move_args(ctx, a)?)
        }
        "move_cartesian_linear" => {
            ArmCall::MoveCartesianLinear(pose(ctx, a, method, at)?, move_args(ctx, a)?)
        }
        "move_joint_pose" => ArmCall::MoveJointPose(pose(ctx, a, method, at)?, move_args(ctx, a)?),
        "move_joint_follow" => {
            let j = ctx.required(&a.joints_deg, "joints_deg", method, at)?;
            ArmCall::MoveJointFollow(joints(ctx, j, "joints_deg")?)
        }
        "set_arm_stop" => ArmCall::Stop,
        "set_arm_slow_stop" => ArmCall::SlowStop,
        "set_arm_pause" => ArmCall::Pause,
        "set_arm_continue" => ArmCall::Continue,
        "set_gripper_position" => ArmCall::GripperPosition {
            position: int_in(ctx, &a.position, "position", (1, 1000), 1000)? as u16,
            block,
        },
        "set_gripper_release" => ArmCall::GripperRelease {
            speed: int_in(ctx, &a.speed, "speed", (1, 1000), 500)? as u16,
            block,
        },
        "set_gripper_pick" => ArmCall::GripperPick {
            speed: int_in(ctx, &a.speed, "speed", (1, 1000), 500)? as u16,
            force: int_in(ctx, &a.force, "force", (50, 1000), 200)? as u16,
            block,
        },
        _ => ArmCall::GetJointDegree,
    })
}

fn present_keys(a: &RawArmStep) -> Vec<(&'static str, Pos)> {
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
        v,
        r,
        trajectory_connect,
        block,
        position,
        speed,
        force
    );
    out
}

/// An `arm` step.
pub(crate) fn step(
    ctx: &Ctx<'_>,
    raw: &RawStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<ArmAction>)> {
    let RawStep::Arm(a) = raw;
    let table: Vec<(&str, &str)> = METHODS.iter().map(|(n, _, _)| (*n, *n)).collect();
    let Some(method) = &a.method else {
        return Err(ctx.err(
            at,
            format!(
                "`arm` needs `do:` with an Arm API method: {}",
                table.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ),
        ));
    };
    let name = ctx.choice(method, "do", &table)?;
    let (_, label, allowed) = METHODS
        .iter()
        .find(|(n, _, _)| *n == name)
        .copied()
        .unwrap_or(("", "arm", &[]));
    ctx.only_arguments(&present_keys(a), allowed, name, "no arguments")?;
    let call = call(ctx, a, name, at)?;
    let device = ctx.device_of_kind(&a.device, at, "arm", "this step")?;
    let timeout = ctx.timeout(&a.timeout_ms)?;
    let expect_code = a
        .expect_code
        .as_ref()
        .map(|c| ctx.choice(c, "expect_code", &error_codes()))
        .transpose()?;
    Ok((
        label,
        DeviceStep {
            device,
            action: ArmAction { call, expect_code },
            timeout,
            expect_error: None,
        },
    ))
}

/// The conditions of `expect` / `wait_until`.
pub(crate) fn checks(ctx: &Ctx<'_>, c: &RawConds, _step: &str, _at: Pos) -> Res<Vec<ArmCond>> {
    let mut out = Vec::new();
    if let Some(j) = &c.joints_deg {
        let tol = c
            .tolerance_deg
            .as_ref()
            .map_or(Ok(DEFAULT_TOLERANCE_DEG), |t| {
                ctx.non_negative(t, "tolerance_deg")
            })?;
        out.push(ArmCond::Joints(joints(ctx, j, "joints_deg")?, tol));
    }
    if let Some(p) = &c.position_m {
        let tol = c
            .tolerance_m
            .as_ref()
            .map_or(Ok(DEFAULT_TOLERANCE_M), |t| {
                ctx.non_negative(t, "tolerance_m")
            })?;
        out.push(ArmCond::Position(ctx.array::<3>(p, "position_m")?, tol));
    }
    if let Some(g) = &c.gripper_actpos {
        let actpos = int_in(ctx, &c.gripper_actpos, "gripper_actpos", (0, 1000), g.value)?;
        let tol = int_in(ctx, &c.tolerance_actpos, "tolerance_actpos", (0, 1000), 10)?;
        out.push(ArmCond::GripperActpos(actpos as i32, tol as i32));
    }
    if let Some(c) = &c.connected {
        out.push(ArmCond::Connected(c.value));
    }
    Ok(out)
}

/// An arm fault.
pub(crate) fn fault(_ctx: &Ctx<'_>, raw: &RawFault, _at: Pos) -> Res<ArmFault> {
    Ok(ArmFault(raw.kind))
}
