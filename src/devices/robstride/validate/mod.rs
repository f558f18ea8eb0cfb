//! Layer 2 of the RobStride grammar: the `robstride` device kind, the `robstride:` step and
//! the `motors:` conditions.

use sim::robstride::{Model, MotorConfig};

use super::model::RobstrideSettings;
use super::raw::RawSettings;
use crate::devices::contract::motor_bus::listed;
use crate::devices::contract::motor_rig::rig;
use crate::devices::named_bus;
use crate::scenario::error::Pos;
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

mod checks;
mod fault;
mod step;
#[cfg(test)]
mod tests;

pub(crate) use checks::checks;
pub(crate) use fault::fault;
pub(crate) use step::step;

fn can_id(ctx: &Ctx<'_>, v: &S<i64>, key: &str) -> Res<u8> {
    if (1..=0x7F).contains(&v.value) {
        Ok(v.value as u8)
    } else {
        Err(ctx.err(
            pos(v),
            format!("`{key}`: CAN ID {} out of range, expected 1..=127", v.value),
        ))
    }
}

/// The settings of a `kind: robstride` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, at: Pos) -> Res<RobstrideSettings> {
    let list = listed(
        ctx,
        &d.motors,
        "a robstride device needs `motors: [{id: 1, model: RS03}, ...]`",
        at,
    )?;
    let mut motors: Vec<MotorConfig> = Vec::new();
    for m in list {
        let id = can_id(ctx, &m.value.id, "id")?;
        if motors.iter().any(|other| other.can_id == id) {
            return Err(ctx.err(pos(&m.value.id), format!("duplicate motor id {id}")));
        }
        let model = Model::named(&m.value.model.value)
            .map_err(|e| ctx.err(pos(&m.value.model), format!("`model`: {e}")))?;
        let mut config = MotorConfig::new(id, model);
        rig(
            ctx,
            &m.value.load,
            &m.value.start_angle_rad,
            &m.value.friction_nm_s_per_rad,
        )?
        .apply(
            &mut config.load,
            &mut config.start_angle_rad,
            &mut config.friction_nm_s_per_rad,
        );
        motors.push(config);
    }
    Ok(RobstrideSettings {
        bus: named_bus(ctx, &d.bus)?,
        motors,
    })
}
