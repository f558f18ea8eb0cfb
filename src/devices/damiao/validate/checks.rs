//! The `motors:` conditions of `expect` / `wait_until`.

use std::collections::BTreeMap;

use super::{esc_id_at, on_device};
use crate::devices::contract::motor_bus::motion_conditions;
use crate::devices::damiao::model::{state_named, MotorCheck, MotorCond, STATES};
use crate::devices::damiao::raw::{RawConds, RawMotorConds};
use crate::scenario::error::{suggestion, Pos};
use crate::scenario::{pos, Ctx, Near, Res, S};

/// Default tolerance of the temperature conditions: the feedback carries whole degrees.
const DEFAULT_TOLERANCE_C: f64 = 1.0;

/// The `motors:` conditions of `expect` / `wait_until` on device `device`.
pub(crate) fn checks(
    ctx: &Ctx<'_>,
    c: &RawConds,
    device: usize,
    step: &str,
    at: Pos,
) -> Res<Vec<MotorCheck>> {
    let Some(motors) = &c.motors else {
        return Err(ctx.err(at, format!("`{step}` has no condition")));
    };
    let mut out = Vec::new();
    motor_checks(ctx, motors, device, &mut out)?;
    Ok(out)
}

/// The state a `state:` condition names, or an error listing them with the nearest.
fn state(ctx: &Ctx<'_>, v: &S<String>) -> Res<&'static str> {
    state_named(&v.value).map(|(_, name)| name).ok_or_else(|| {
        let names: Vec<&str> = STATES.iter().map(|(_, n)| *n).collect();
        ctx.err(
            pos(v),
            format!(
                "`state`: unknown value `{}`; expected one of: {} (or the name of the fault that latches it){}",
                v.value,
                names.join(", "),
                suggestion(&v.value, &names)
            ),
        )
    })
}

fn motor_checks(
    ctx: &Ctx<'_>,
    motors: &S<BTreeMap<i64, S<RawMotorConds>>>,
    device: usize,
    out: &mut Vec<MotorCheck>,
) -> Res<()> {
    for (id, conds) in &motors.value {
        let motor = esc_id_at(ctx, *id, pos(motors), "motors")?;
        on_device(ctx, device, motor, pos(conds))?;
        let c = &conds.value;
        let tol = |t: &Option<S<f64>>, key: &str, default: f64| {
            t.as_ref().map_or(Ok(default), |t| ctx.non_negative(t, key))
        };
        let near = |v: &S<f64>, key: &str, t: &Option<S<f64>>, t_key: &str, default: f64| {
            Ok::<_, Box<crate::scenario::ScenarioError>>(Near {
                value: ctx.finite(v, key)?,
                tolerance: tol(t, t_key, default)?,
            })
        };
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
        if let Some(s) = &c.state {
            push(MotorCond::State(state(ctx, s)?));
        }
        if let Some(t) = &c.mos_temp_c {
            push(MotorCond::MosTemp(near(
                t,
                "mos_temp_c",
                &c.tolerance_c,
                "tolerance_c",
                DEFAULT_TOLERANCE_C,
            )?));
        }
        if let Some(t) = &c.rotor_temp_c {
            push(MotorCond::RotorTemp(near(
                t,
                "rotor_temp_c",
                &c.tolerance_c,
                "tolerance_c",
                DEFAULT_TOLERANCE_C,
            )?));
        }
        if out.iter().all(|check| check.motor != motor) {
            return Err(ctx.err(
                pos(conds),
                format!("motor {motor} has no condition (for example `position_rad`, `state`, `rotor_temp_c`)"),
            ));
        }
    }
    Ok(())
}
