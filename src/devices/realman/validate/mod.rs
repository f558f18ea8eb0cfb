//! Layer 2 of the Realman grammar: the `realman` device kind, the `realman:` step, the arm
//! conditions and the emulator faults.

mod checks;
mod fault;
mod jog;
mod params;
mod step;
mod stream;

pub(crate) use checks::checks;
pub(crate) use fault::fault;

use super::model::{RealmanAction, RealmanSettings, MODELS};
use super::raw::{RawSettings, RawStep};
use crate::scenario::error::Pos;
use crate::scenario::{pos, Ctx, DeviceStep, Res, S};

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
pub(crate) fn step(
    ctx: &Ctx<'_>,
    raw: &RawStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<RealmanAction>)> {
    match raw {
        RawStep::Realman(a) => step::realman_step(ctx, a, at),
    }
}

#[cfg(test)]
mod tests;
