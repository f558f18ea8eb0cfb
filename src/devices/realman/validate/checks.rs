//! The arm conditions of `expect` / `wait_until` in a Realman scenario.

use super::joints;
use crate::devices::realman::model::{RmCond, ARM_STATES, ERRORS};
use crate::devices::realman::raw::RawConds;
use crate::scenario::error::Pos;
use crate::scenario::{Ctx, Near, Res, S};

/// Default tolerances of the conditions.
const DEFAULT_TOLERANCE_DEG: f64 = 0.05;
const DEFAULT_TOLERANCE_M: f64 = 0.001;
const DEFAULT_TOLERANCE_HZ: f64 = 2.0;

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
