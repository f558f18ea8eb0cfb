//! The `motors:` conditions of `expect` / `wait_until`.

use std::collections::BTreeMap;

use crate::devices::contract::motor_bus::motion_conditions;
use crate::devices::robstride::model::{
    MotorCheck, MotorCond, FEEDBACK_KINDS, MODE_STATES, REPORT_FLAGS, STATUS_FAULTS,
};
use crate::devices::robstride::raw::{RawConds, RawMotorConds};
use crate::scenario::error::Pos;
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

fn names(
    ctx: &Ctx<'_>,
    list: &S<Vec<S<String>>>,
    table: &[&'static str],
    key: &str,
) -> Res<Vec<&'static str>> {
    for f in &list.value {
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
    }
    // In table order, as the observation lists them.
    Ok(table
        .iter()
        .filter(|n| list.value.iter().any(|f| f.value == **n))
        .copied()
        .collect())
}

fn one_of(ctx: &Ctx<'_>, v: &S<String>, table: &[&'static str], key: &str) -> Res<&'static str> {
    table
        .iter()
        .find(|n| **n == v.value)
        .copied()
        .ok_or_else(|| {
            ctx.err(
                pos(v),
                format!(
                    "`{key}`: unknown value `{}`; expected one of: {}",
                    v.value,
                    table.join(", ")
                ),
            )
        })
}

/// The `motors:` conditions of `expect` / `wait_until`.
pub(crate) fn checks(ctx: &Ctx<'_>, c: &RawConds, step: &str, at: Pos) -> Res<Vec<MotorCheck>> {
    let mut out = Vec::new();
    let Some(motors) = &c.motors else {
        return Err(ctx.err(at, format!("`{step}` has no condition")));
    };
    motor_checks(ctx, motors, &mut out)?;
    Ok(out)
}

fn motor_checks(
    ctx: &Ctx<'_>,
    motors: &S<BTreeMap<i64, S<RawMotorConds>>>,
    out: &mut Vec<MotorCheck>,
) -> Res<()> {
    for (id, conds) in &motors.value {
        if !(1..=0x7F).contains(id) {
            return Err(ctx.err(
                pos(motors),
                format!("`motors`: CAN ID {id} out of range, expected 1..=127"),
            ));
        }
        let motor = *id as u8;
        let c = &conds.value;
        let motion = motion_conditions(
            ctx,
            [
                (&c.position_rad, &c.tolerance_rad),
                (&c.velocity_rad_s, &c.tolerance_rad_s),
                (&c.torque_nm, &c.tolerance_nm),
            ],
            [MotorCond::Position, MotorCond::Velocity, MotorCond::Torque],
        )?;
        out.extend(motion.into_iter().map(|cond| MotorCheck { motor, cond }));
        let mut push = |cond: MotorCond| out.push(MotorCheck { motor, cond });
        if let Some(t) = &c.temp_min_c {
            push(MotorCond::TempMin(ctx.finite(t, "temp_min_c")?));
        }
        if let Some(t) = &c.temp_max_c {
            push(MotorCond::TempMax(ctx.finite(t, "temp_max_c")?));
        }
        if let Some(m) = &c.mode_state {
            push(MotorCond::ModeState(one_of(
                ctx,
                m,
                &MODE_STATES,
                "mode_state",
            )?));
        }
        if let Some(f) = &c.faults {
            push(MotorCond::StatusFaults(names(
                ctx,
                f,
                &STATUS_FAULTS,
                "faults",
            )?));
        }
        if let Some(f) = &c.fault_report {
            push(MotorCond::FaultReport(names(
                ctx,
                f,
                &REPORT_FLAGS,
                "fault_report",
            )?));
        }
        if let Some(k) = &c.feedback {
            push(MotorCond::Feedback(one_of(
                ctx,
                k,
                &FEEDBACK_KINDS,
                "feedback",
            )?));
        }
        if out.iter().all(|check| check.motor != motor) {
            return Err(ctx.err(
                pos(conds),
                format!("motor {motor} has no condition (for example `velocity_rad_s`, `mode_state`, `faults`)"),
            ));
        }
    }
    Ok(())
}
