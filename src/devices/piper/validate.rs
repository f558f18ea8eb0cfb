//! Layer 2 of the Piper's vocabulary: check its raw settings, steps, faults and conditions.

use std::path::PathBuf;

use sim::piper::{FaultKind, NtcBoard, PiperFault};

use super::model::*;
use super::raw::*;
use super::vocab;
use crate::scenario::error::Pos;
use crate::scenario::{DeviceStep, Near};
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

/// Default MOVE speed percentage.
const DEFAULT_SPEED_PCT: u8 = 50;
/// Longest `every_ms` re-send period, ms.
const MAX_EVERY_MS: i64 = 10_000;
/// Default tolerance on joint angles.
const DEFAULT_TOLERANCE_DEG: f64 = 0.5;
/// Default tolerance on positions and gripper stroke.
const DEFAULT_TOLERANCE_MM: f64 = 1.0;
/// Default firmware profile.
pub const DEFAULT_FIRMWARE: &str = "S-V1.8-8";

/// Validation helpers for the Piper's joint-indexed values.
trait PiperCtx {
    fn joint(&self, value: &S<i64>, key: &str, allow_all: bool) -> Res<u8>;
    fn joint_required(
        &self,
        value: &Option<S<i64>>,
        action: &str,
        at: Pos,
        allow_all: bool,
    ) -> Res<u8>;
    fn pct(&self, value: &Option<S<i64>>) -> Res<u8>;
    fn every_ms(&self, value: &Option<S<i64>>) -> Res<Option<u32>>;
    fn optional_list(&self, value: &S<Vec<Option<f64>>>, key: &str) -> Res<Vec<Option<f64>>>;
    fn joints_list(&self, value: &S<Vec<i64>>, key: &str) -> Res<Vec<u8>>;
}

impl PiperCtx for Ctx<'_> {
    fn joint(&self, value: &S<i64>, key: &str, allow_all: bool) -> Res<u8> {
        let max = if allow_all { 7 } else { PIPER_JOINTS as i64 };
        if (1..=max).contains(&value.value) {
            Ok(value.value as u8)
        } else {
            let range = if allow_all {
                "1..=6, or 7 for all joints"
            } else {
                "1..=6"
            };
            Err(self.err(
                pos(value),
                format!(
                    "`{key}`: joint index {} out of range, expected {range}",
                    value.value
                ),
            ))
        }
    }

    fn joint_required(
        &self,
        value: &Option<S<i64>>,
        action: &str,
        at: Pos,
        allow_all: bool,
    ) -> Res<u8> {
        let v = self.required(value, "joint", action, at)?;
        self.joint(v, "joint", allow_all)
    }

    fn pct(&self, value: &Option<S<i64>>) -> Res<u8> {
        match value {
            None => Ok(DEFAULT_SPEED_PCT),
            Some(v) if (0..=100).contains(&v.value) => Ok(v.value as u8),
            Some(v) => Err(self.err(
                pos(v),
                format!("`speed_pct` must be 0..=100, got {}", v.value),
            )),
        }
    }

    fn every_ms(&self, value: &Option<S<i64>>) -> Res<Option<u32>> {
        match value {
            None => Ok(None),
            Some(v) if (1..=MAX_EVERY_MS).contains(&v.value) => Ok(Some(v.value as u32)),
            Some(v) => Err(self.err(
                pos(v),
                format!("`every_ms` must be 1..={MAX_EVERY_MS}, got {}", v.value),
            )),
        }
    }

    fn optional_list(&self, value: &S<Vec<Option<f64>>>, key: &str) -> Res<Vec<Option<f64>>> {
        if value.value.len() != PIPER_JOINTS {
            return Err(self.err(
                pos(value),
                format!(
                    "`{key}` needs one entry per joint ({PIPER_JOINTS}; use ~ for joints not checked), got {}",
                    value.value.len()
                ),
            ));
        }
        if value.value.iter().flatten().any(|v| !v.is_finite()) {
            return Err(self.err(pos(value), format!("`{key}` must hold finite numbers")));
        }
        Ok(value.value.clone())
    }

    fn joints_list(&self, value: &S<Vec<i64>>, key: &str) -> Res<Vec<u8>> {
        let mut joints = Vec::new();
        for j in &value.value {
            if !(1..=PIPER_JOINTS as i64).contains(j) {
                return Err(self.err(
                    pos(value),
                    format!("`{key}`: joint index {j} out of range, expected 1..=6"),
                ));
            }
            joints.push(*j as u8);
        }
        joints.sort_unstable();
        joints.dedup();
        Ok(joints)
    }
}

/// The settings of a `kind: piper` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, _at: Pos) -> Res<PiperSettings> {
    let firmware = match &d.firmware {
        Some(fw) => fw
            .value
            .parse::<sim::piper::FirmwareProfile>()
            .map_err(|_| {
                let names: Vec<&str> = sim::piper::FirmwareProfile::ALL
                    .iter()
                    .map(|p| p.version_string())
                    .collect();
                ctx.err(
                    pos(fw),
                    format!(
                        "`firmware`: unknown Piper firmware `{}`; the emulator implements: {}",
                        fw.value,
                        names.join(", ")
                    ),
                )
            })?
            .version_string()
            .to_owned(),
        None => DEFAULT_FIRMWARE.to_owned(),
    };
    let urdf = match &d.urdf {
        Some(path) => {
            let p = PathBuf::from(&path.value);
            let resolved = if p.is_absolute() || p.exists() {
                p
            } else {
                ctx.file.parent().map_or(p.clone(), |dir| dir.join(&p))
            };
            if !resolved.exists() {
                return Err(ctx.err(
                    pos(path),
                    format!("`urdf`: file `{}` not found", path.value),
                ));
            }
            Some(resolved)
        }
        None => None,
    };
    let initial_joints_deg = match &d.initial_joints_deg {
        Some(list) => ctx.array::<PIPER_JOINTS>(list, "initial_joints_deg")?,
        None => [0.0; PIPER_JOINTS],
    };
    let gripper_max_mm = match &d.gripper_max_mm {
        Some(v) if matches!(v.value, 0 | 70 | 100) => Some(v.value as u8),
        Some(v) => {
            return Err(ctx.err(
                pos(v),
                format!(
                    "`gripper_max_mm` must be 0 (never set), 70 or 100, got {}",
                    v.value
                ),
            ))
        }
        None => None,
    };
    let collision_levels = d
        .collision_levels
        .as_ref()
        .map(|l| levels(ctx, l))
        .transpose()?;
    let mut obstacles = Vec::new();
    for (i, o) in d.obstacles.iter().flatten().enumerate() {
        let at_m = ctx.array::<3>(&o.value.at_m, "at_m")?;
        let shape = match (&o.value.box_m, &o.value.sphere_radius_m) {
            (Some(size), None) => {
                let size_m = ctx.array::<3>(size, "box_m")?;
                if size_m.iter().any(|s| *s <= 0.0) {
                    return Err(ctx.err(pos(size), "`box_m` edge lengths must be > 0"));
                }
                ObstacleShape::Box { size_m }
            }
            (None, Some(r)) => {
                let radius_m = ctx.non_negative(r, "sphere_radius_m")?;
                ObstacleShape::Sphere { radius_m }
            }
            _ => return Err(ctx.err(
                pos(o),
                "an obstacle needs exactly one shape: `box_m: [x, y, z]` or `sphere_radius_m: r`",
            )),
        };
        obstacles.push(Obstacle {
            name: o
                .value
                .name
                .clone()
                .unwrap_or_else(|| format!("obstacle{}", i + 1)),
            shape,
            at_m,
        });
    }
    Ok(PiperSettings {
        firmware,
        urdf,
        initial_joints_deg,
        gripper_max_mm,
        collision_levels,
        obstacles,
    })
}

/// Emulator fault arguments: reject the ones a fault does not take, fill defaults from the
/// emulator's table ([`FaultKind::params`]).
struct EmuArgs<'c, 'a> {
    ctx: &'c Ctx<'a>,
    args: &'c RawEmuArgs,
    kind: FaultKind,
    at: Pos,
}

impl EmuArgs<'_, '_> {
    fn allow(&self) -> Res<()> {
        let allowed: Vec<&str> = self.kind.params().iter().map(|p| p.name).collect();
        let present: [(&str, Option<Pos>); 5] = [
            ("joint", self.args.joint.as_ref().map(pos)),
            ("temp_c", self.args.temp_c.as_ref().map(pos)),
            ("voltage_v", self.args.voltage_v.as_ref().map(pos)),
            ("torque_nm", self.args.torque_nm.as_ref().map(pos)),
            ("board", self.args.board.as_ref().map(pos)),
        ];
        for (key, at) in present {
            if let Some(at) = at {
                if !allowed.contains(&key) {
                    let takes = if allowed.is_empty() {
                        "no arguments".to_owned()
                    } else {
                        allowed.join(", ")
                    };
                    return Err(self.ctx.err(
                        at,
                        format!(
                            "`{}` takes no `{key}` (it takes: {takes})",
                            self.kind.name()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn joint(&self) -> Res<u8> {
        self.ctx
            .joint_required(&self.args.joint, self.kind.name(), self.at, false)
    }

    /// A numeric parameter: the value written, else the table's default, else an error. A
    /// written value is checked against the table's range ([`sim::piper::FaultParam::check`],
    /// the check the emulator applies), so an absurd one is an error at its line.
    fn number(&self, value: &Option<S<f64>>, key: &str) -> Res<f64> {
        match value {
            Some(v) => {
                let x = self.ctx.finite(v, key)?;
                match self.kind.param(key) {
                    Some(param) => param
                        .check(x)
                        .map_err(|e| self.ctx.err(pos(v), e.to_string())),
                    None => Ok(x),
                }
            }
            None => {
                let default = self
                    .kind
                    .params()
                    .iter()
                    .find(|p| p.name == key)
                    .and_then(|p| p.default);
                match default {
                    Some(d) => Ok(d),
                    None => {
                        let v = self.ctx.required(value, key, self.kind.name(), self.at)?;
                        self.ctx.finite(v, key)
                    }
                }
            }
        }
    }
}

/// A Piper emulator fault (`fpos`: where the fault is written).
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, fpos: Pos) -> Res<PiperFault> {
    let e = EmuArgs {
        ctx,
        args: &raw.args,
        kind: raw.kind,
        at: fpos,
    };
    e.allow()?;
    let a = &raw.args;
    Ok(match raw.kind {
        FaultKind::CommLoss => PiperFault::CommLoss { joint: e.joint()? },
        FaultKind::MotorOverTemp => PiperFault::MotorOverTemp {
            joint: e.joint()?,
            temp_c: e.number(&a.temp_c, "temp_c")?,
        },
        FaultKind::DriverOverTemp => PiperFault::DriverOverTemp {
            joint: e.joint()?,
            temp_c: e.number(&a.temp_c, "temp_c")?,
        },
        FaultKind::OverCurrent => PiperFault::OverCurrent { joint: e.joint()? },
        FaultKind::UnderVoltage => PiperFault::UnderVoltage {
            voltage_v: e.number(&a.voltage_v, "voltage_v")?,
        },
        FaultKind::DriverError => PiperFault::DriverError { joint: e.joint()? },
        FaultKind::Stall => PiperFault::Stall { joint: e.joint()? },
        FaultKind::ExternalTorque => PiperFault::ExternalTorque {
            joint: e.joint()?,
            torque_nm: e.number(&a.torque_nm, "torque_nm")?,
        },
        FaultKind::Collision => PiperFault::Collision { joint: e.joint()? },
        FaultKind::Estop => PiperFault::Estop,
        FaultKind::NtcOverTemp => PiperFault::NtcOverTemp {
            board: match &a.board {
                None => NtcBoard::Main,
                Some(b) => {
                    let boards = NtcBoard::ALL.map(|b| (b, b.name()));
                    ctx.choice(b, "board", &boards)?
                }
            },
        },
        FaultKind::GripperSensorFault => PiperFault::GripperSensorFault,
        FaultKind::TeachButton => PiperFault::TeachButton,
    })
}

fn pose(
    ctx: &Ctx<'_>,
    position: &Option<S<Vec<f64>>>,
    orientation: &Option<S<Vec<f64>>>,
    action: &str,
    at: Pos,
) -> Res<Pose> {
    let p = ctx.required(position, "position_mm", action, at)?;
    let o = ctx.required(orientation, "orientation_deg", action, at)?;
    Ok(Pose {
        position_mm: ctx.array::<3>(p, "position_mm")?,
        orientation_deg: ctx.array::<3>(o, "orientation_deg")?,
    })
}

fn raw_pose(ctx: &Ctx<'_>, raw: &Option<S<RawPose>>, key: &str, at: Pos) -> Res<Pose> {
    let p = ctx.required(raw, key, "move_c", at)?;
    Ok(Pose {
        position_mm: ctx.array::<3>(&p.value.position_mm, "position_mm")?,
        orientation_deg: ctx.array::<3>(&p.value.orientation_deg, "orientation_deg")?,
    })
}

fn near(ctx: &Ctx<'_>, value: &Option<S<f64>>, key: &str, tolerance: f64) -> Res<Option<Near>> {
    value
        .as_ref()
        .map(|v| {
            Ok(Near {
                value: ctx.finite(v, key)?,
                tolerance,
            })
        })
        .transpose()
}

fn small_uint(
    ctx: &Ctx<'_>,
    value: &Option<S<i64>>,
    key: &str,
    range: std::ops::RangeInclusive<i64>,
) -> Res<Option<u16>> {
    match value {
        None => Ok(None),
        Some(v) if range.contains(&v.value) => Ok(Some(v.value as u16)),
        Some(v) => Err(ctx.err(
            pos(v),
            format!(
                "`{key}` must be {}..={}, got {}",
                range.start(),
                range.end(),
                v.value
            ),
        )),
    }
}

fn levels(ctx: &Ctx<'_>, raw: &S<Vec<i64>>) -> Res<[u8; PIPER_JOINTS]> {
    if raw.value.len() != PIPER_JOINTS {
        return Err(ctx.err(
            pos(raw),
            format!(
                "`levels` needs exactly 6 values (one per joint), got {}",
                raw.value.len()
            ),
        ));
    }
    let mut out = [0u8; PIPER_JOINTS];
    for (slot, v) in out.iter_mut().zip(&raw.value) {
        if !(0..=8).contains(v) {
            return Err(ctx.err(pos(raw), format!("collision levels are 0..=8, got {v}")));
        }
        *slot = *v as u8;
    }
    Ok(out)
}

fn offset(ctx: &Ctx<'_>, raw: &Option<S<i64>>, key: &str) -> Res<u8> {
    match raw {
        None => Ok(0),
        Some(v) if matches!(v.value, 0 | 0x10 | 0x20) => Ok(v.value as u8),
        Some(v) => Err(ctx.err(
            pos(v),
            format!("`{key}` must be 0, 0x10 or 0x20, got {}", v.value),
        )),
    }
}

/// Build an action step from its common arguments.
struct Common<'r> {
    device: &'r Option<S<String>>,
    timeout_ms: &'r Option<S<i64>>,
    expect_error: &'r Option<S<String>>,
}

macro_rules! common {
    ($args:expr) => {
        Common {
            device: &$args.device,
            timeout_ms: &$args.timeout_ms,
            expect_error: &$args.expect_error,
        }
    };
}

fn action(ctx: &Ctx<'_>, common: Common<'_>, at: Pos, action: PiperAction) -> Res<DeviceStep<PiperAction>> {
    let device = ctx.device_of_kind(common.device, at, "piper", "this step")?;
    let timeout = ctx.timeout(common.timeout_ms)?;
    let expect_error = ctx.expect_error(common.expect_error)?;
    Ok(DeviceStep {
        device,
        action,
        timeout,
        expect_error,
    })
}

/// A Piper step: its label and action.
pub(crate) fn step(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<(&'static str, DeviceStep<PiperAction>)> {
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
    })
}

/// A Piper's conditions.
pub(crate) fn checks(ctx: &Ctx<'_>, c: &RawConds, step: &str, at: Pos) -> Res<Vec<Check>> {
    let mut out = Vec::new();
    let tolerance_deg = match &c.tolerance_deg {
        Some(t) => ctx.non_negative(t, "tolerance_deg")?,
        None => DEFAULT_TOLERANCE_DEG,
    };
    let tolerance_mm = match &c.tolerance_mm {
        Some(t) => ctx.non_negative(t, "tolerance_mm")?,
        None => DEFAULT_TOLERANCE_MM,
    };
    if let Some(j) = &c.joints_deg {
        out.push(Check::JointsNear {
            targets_deg: ctx.optional_list(j, "joints_deg")?,
            tolerance_deg,
        });
    }
    if let Some(j) = &c.joints_min_deg {
        out.push(Check::JointsMin {
            bounds_deg: ctx.optional_list(j, "joints_min_deg")?,
        });
    }
    if let Some(j) = &c.joints_max_deg {
        out.push(Check::JointsMax {
            bounds_deg: ctx.optional_list(j, "joints_max_deg")?,
        });
    }
    if let Some(s) = &c.max_speed_deg_s {
        out.push(Check::MaxSpeed {
            deg_s: ctx.non_negative(s, "max_speed_deg_s")?,
        });
    }
    if let Some(s) = &c.max_current_a {
        out.push(Check::MaxCurrent {
            amps: ctx.non_negative(s, "max_current_a")?,
        });
    }
    if let Some(p) = &c.position_mm {
        out.push(Check::PositionNear {
            mm: ctx.array::<3>(p, "position_mm")?,
            tolerance_mm,
        });
    }
    if let Some(o) = &c.orientation_deg {
        out.push(Check::OrientationNear {
            deg: ctx.array::<3>(o, "orientation_deg")?,
            tolerance_deg,
        });
    }
    if let Some(g) = &c.gripper_mm {
        out.push(Check::GripperNear {
            mm: ctx.non_negative(g, "gripper_mm")?,
            tolerance_mm,
        });
    }
    if let Some(s) = &c.arm_status {
        let name = vocab::resolve_arm_status(&s.value).ok_or_else(|| {
            let names = vocab::arm_status_names();
            ctx.err(
                pos(s),
                format!(
                    "`arm_status`: unknown value `{}`; expected a code 0x00..=0x0F or one of: {}",
                    s.value,
                    names.join(", ")
                ),
            )
        })?;
        out.push(Check::Status {
            field: "arm_status",
            value: name.to_owned(),
        });
    }
    if let Some(s) = &c.ctrl_mode {
        let name = vocab::resolve_ctrl_mode(&s.value).ok_or_else(|| {
            let names = vocab::ctrl_mode_names();
            ctx.err(
                pos(s),
                format!(
                    "`ctrl_mode`: unknown value `{}`; expected one of: {}",
                    s.value,
                    names.join(", ")
                ),
            )
        })?;
        out.push(Check::Status {
            field: "ctrl_mode",
            value: name.to_owned(),
        });
    }
    for (key, field, table) in [
        (&c.move_mode, "move_mode", vocab::move_mode_names()),
        (&c.motion, "motion", vocab::motion_names()),
        (&c.feedback, "feedback", vocab::FEEDBACK.to_vec()),
    ] {
        if let Some(s) = key {
            if !table.contains(&s.value.as_str()) {
                return Err(ctx.err(
                    pos(s),
                    format!(
                        "`{field}`: unknown value `{}`; expected one of: {}",
                        s.value,
                        table.join(", ")
                    ),
                ));
            }
            out.push(Check::Status {
                field,
                value: s.value.clone(),
            });
        }
    }
    if let Some(l) = c.leader_frames {
        out.push(Check::Status {
            field: "leader_frames",
            value: l.to_string(),
        });
    }
    if let Some(e) = c.enabled {
        out.push(Check::Enabled(e));
    }
    if let Some(j) = &c.enabled_joints {
        out.push(Check::EnabledJoints(ctx.joints_list(j, "enabled_joints")?));
    }
    if let Some(e) = c.gripper_enabled {
        out.push(Check::GripperEnabled(e));
    }
    if let Some(j) = &c.comm_error_joints {
        out.push(Check::CommErrorJoints(
            ctx.joints_list(j, "comm_error_joints")?,
        ));
    }
    if let Some(j) = &c.limit_error_joints {
        out.push(Check::LimitErrorJoints(
            ctx.joints_list(j, "limit_error_joints")?,
        ));
    }
    if let Some(map) = &c.joint_faults {
        for (joint, flags) in &map.value {
            if !(1..=PIPER_JOINTS as i64).contains(joint) {
                return Err(ctx.err(
                    pos(map),
                    format!("`joint_faults`: joint index {joint} out of range, expected 1..=6"),
                ));
            }
            let flags = flag_list(ctx, flags, &vocab::joint_flags(), "joint_faults")?;
            out.push(Check::JointFaults {
                joint: *joint as u8,
                flags,
            });
        }
    }
    if let Some(flags) = &c.gripper_faults {
        out.push(Check::GripperFaults(flag_list(
            ctx,
            &flags.value,
            &vocab::gripper_flags(),
            "gripper_faults",
        )?));
    }
    if out.is_empty() {
        return Err(ctx.err(
            at,
            format!(
                "`{step}` has no condition (for example `joints_deg`, `arm_status`, `enabled`)"
            ),
        ));
    }
    Ok(out)
}

fn flag_list(ctx: &Ctx<'_>, flags: &[S<String>], table: &[&str], key: &str) -> Res<Vec<String>> {
    let mut out = Vec::new();
    for f in flags {
        if !table.contains(&f.value.as_str()) {
            return Err(ctx.err(
                pos(f),
                format!(
                    "`{key}`: unknown flag `{}`; expected one of: {}",
                    f.value,
                    table.join(", ")
                ),
            ));
        }
        out.push(f.value.clone());
    }
    out.sort();
    out.dedup();
    Ok(out)
}
