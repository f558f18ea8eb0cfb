//! Layer 2 of the Realman grammar: the `realman` device kind, the `realman:` step, the arm
//! conditions and the emulator faults.

mod jog;
mod params;
mod step;
mod stream;

use sim::realman::{RealmanFault, RealmanFaultKind};

use super::model::{RealmanAction, RealmanSettings, RmCond, RmFault, ARM_STATES, ERRORS, MODELS};
use super::raw::{RawConds, RawFault, RawSettings, RawStep};
use crate::scenario::error::Pos;
use crate::scenario::{DeviceStep, Near};
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

/// Default tolerances of the conditions.
const DEFAULT_TOLERANCE_DEG: f64 = 0.05;
const DEFAULT_TOLERANCE_M: f64 = 0.001;
const DEFAULT_TOLERANCE_HZ: f64 = 2.0;
/// Most driver connections a scenario may open.
const MAX_CLIENTS: i64 = 4;

/// The settings of a `kind: realman` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, _at: Pos) -> Res<RealmanSettings> {
    let model = match &d.model {
        Some(m) => ctx.choice(m, "model", &MODELS)?,
        None => "RM65-B",
    };
    let dof = if model == "RM75-B" { 7 } else { 6 };
    let initial_joints_deg = match &d.initial_joints_deg {
        Some(j) => Some(joints(ctx, j, "initial_joints_deg", dof)?),
        None => None,
    };
    let clients = match &d.clients {
        Some(c) if (1..=MAX_CLIENTS).contains(&c.value) => c.value as usize,
        Some(c) => {
            return Err(ctx.err(
                pos(c),
                format!(
                    "`clients`: {} out of range, expected 1..={MAX_CLIENTS}",
                    c.value
                ),
            ))
        }
        None => 1,
    };
    Ok(RealmanSettings {
        model,
        initial_joints_deg,
        gripper: d.gripper.as_ref().is_none_or(|g| g.value),
        clients,
    })
}

fn joints(ctx: &Ctx<'_>, v: &S<Vec<f64>>, key: &str, dof: usize) -> Res<Vec<f64>> {
    if v.value.len() != dof || v.value.iter().any(|x| !x.is_finite()) {
        return Err(ctx.err(
            pos(v),
            format!(
                "`{key}` needs {dof} finite angles (degrees), got {:?}",
                v.value
            ),
        ));
    }
    Ok(v.value.clone())
}

fn int_in(ctx: &Ctx<'_>, v: &S<i64>, key: &str, lo: i64, hi: i64) -> Res<i64> {
    if (lo..=hi).contains(&v.value) {
        Ok(v.value)
    } else {
        Err(ctx.err(
            pos(v),
            format!("`{key}`: {} out of range, expected {lo}..={hi}", v.value),
        ))
    }
}

/// A Realman step.
pub(crate) fn step(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<(&'static str, DeviceStep<RealmanAction>)> {
    match raw {
        RawStep::Realman(a) => step::realman_step(ctx, a, at),
    }
}

/// A Realman emulator fault with its arguments.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RmFault> {
    let a = &raw.args;
    let name = raw.kind.name();
    // Bounds from the emulator's table, the one the web view and Python check against too.
    let int = |v: &Option<S<i64>>, key: &str| -> Res<i64> {
        let (lo, hi) = raw.kind.param(key).map_or((0, i64::MAX), |p| {
            (
                i64::try_from(p.min).unwrap_or(i64::MAX),
                i64::try_from(p.max).unwrap_or(i64::MAX),
            )
        });
        int_in(ctx, ctx.required(v, key, name, at)?, key, lo, hi)
    };
    let f = match raw.kind {
        RealmanFaultKind::ConnectionDrop => RealmanFault::ConnectionDrop { peer_ip: None },
        RealmanFaultKind::ReplyDelay => RealmanFault::ReplyDelay {
            delay_ms: int(&a.delay_ms, "delay_ms")? as u64,
        },
        RealmanFaultKind::MalformedReply => RealmanFault::MalformedReply {
            count: int(&a.count, "count")? as u32,
        },
        RealmanFaultKind::UdpLoss => RealmanFault::UdpLoss {
            permille: int(&a.permille, "permille")? as u16,
        },
        RealmanFaultKind::UdpReorder => RealmanFault::UdpReorder,
        RealmanFaultKind::JointError => RealmanFault::JointError {
            joint: int(&a.joint, "joint")? as u8,
            code: int(&a.code, "code")? as u16,
        },
        RealmanFaultKind::PowerLoss => RealmanFault::PowerLoss,
        RealmanFaultKind::Collision => RealmanFault::Collision,
        RealmanFaultKind::EStop => RealmanFault::EStop,
        RealmanFaultKind::GripperFault => RealmanFault::GripperFault {
            bits: int(&a.bits, "bits")? as u8,
        },
    };
    Ok(RmFault(f))
}

/// The arm conditions of `expect` / `wait_until`.
pub(crate) fn checks(ctx: &Ctx<'_>, c: &RawConds, step: &str, at: Pos) -> Res<Vec<RmCond>> {
    let mut out = Vec::new();
    let tol = |t: &Option<S<f64>>, key: &str, default: f64| {
        t.as_ref().map_or(Ok(default), |t| ctx.non_negative(t, key))
    };
    if let Some(j) = &c.joints_deg {
        let dof = j.value.len().clamp(6, 7);
        out.push(RmCond::Joints(
            joints(ctx, j, "joints_deg", dof)?,
            tol(&c.tolerance_deg, "tolerance_deg", DEFAULT_TOLERANCE_DEG)?,
        ));
    }
    if let Some(p) = &c.position_m {
        out.push(RmCond::Position(
            ctx.array::<3>(p, "position_m")?,
            tol(&c.tolerance_m, "tolerance_m", DEFAULT_TOLERANCE_M)?,
        ));
    }
    if let Some(s) = &c.arm_state {
        let table: Vec<(&'static str, &str)> = ARM_STATES.iter().map(|n| (*n, *n)).collect();
        out.push(RmCond::ArmState(ctx.choice(s, "arm_state", &table)?));
    }
    if let Some(list) = &c.errors {
        let mut names = Vec::new();
        for e in &list.value {
            let table: Vec<(&'static str, &str)> = ERRORS.iter().map(|(n, _)| (*n, *n)).collect();
            names.push(ctx.choice(e, "errors", &table)?);
        }
        // In table order, as the observation lists them.
        let ordered = ERRORS
            .iter()
            .map(|(n, _)| *n)
            .filter(|n| names.contains(n))
            .collect();
        out.push(RmCond::Errors(ordered));
    }
    if let Some(e) = &c.joints_enabled {
        out.push(RmCond::Enabled(e.value.clone()));
    }
    if let Some(h) = &c.push_hz {
        out.push(RmCond::PushHz(Near {
            value: ctx.non_negative(h, "push_hz")?,
            tolerance: tol(&c.tolerance_hz, "tolerance_hz", DEFAULT_TOLERANCE_HZ)?,
        }));
    }
    if let Some(k) = &c.connected {
        out.push(RmCond::Connected(k.value));
    }
    if out.is_empty() {
        return Err(ctx.err(at, format!("`{step}` has no condition")));
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
