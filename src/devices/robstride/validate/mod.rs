//! Layer 2 of the RobStride grammar: the `robstride` device kind, the `robstride:` step and
//! the `motors:` conditions.

use sim::robstride::{Load, Model, MotorConfig};

use super::model::RobstrideSettings;
use super::raw::{RawRsLoad, RawSettings};
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

fn positive(ctx: &Ctx<'_>, v: &S<f64>, key: &str) -> Res<f64> {
    let x = ctx.finite(v, key)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(ctx.err(pos(v), format!("`{key}` must be > 0, got {x}")))
    }
}

/// Largest load mass, kg: far beyond any RobStride rig, small enough for finite physics.
const MAX_MASS_KG: f64 = 1000.0;
/// Largest disc radius or pendulum length, m.
const MAX_LENGTH_M: f64 = 10.0;
/// Largest rig friction, N·m·s/rad.
const MAX_FRICTION_NM_S_PER_RAD: f64 = 1000.0;
/// Largest |start angle|, rad (the protocol's position range is ±4π).
const MAX_START_ANGLE_RAD: f64 = 100.0;

/// A physical parameter in `min ..= max` (`min` itself excluded when `positive`); a finite
/// but absurd value (`mass_kg: 1e308`) would turn the rig's physics into NaN.
fn bounded(ctx: &Ctx<'_>, v: &S<f64>, key: &str, positive_only: bool, max: f64) -> Res<f64> {
    let x = if positive_only {
        positive(ctx, v, key)?
    } else {
        ctx.finite(v, key)?
    };
    if x.abs() > max {
        let range = if positive_only {
            format!("at most {max}")
        } else {
            format!("between -{max} and {max}")
        };
        return Err(ctx.err(pos(v), format!("`{key}` must be {range}, got {x:?}")));
    }
    Ok(x)
}

/// A motor's rig as its entry gives it (each `None` where not written): what a RobStride and a
/// Damiao motor's shaft drives alike (`sim::robstride::Load`).
pub(crate) struct Rig {
    /// `load:`.
    pub load: Option<Load>,
    /// `start_angle_rad:`.
    pub start_angle_rad: Option<f64>,
    /// `friction_nm_s_per_rad:`.
    pub friction_nm_s_per_rad: Option<f64>,
}

/// A motor entry's `load`, `start_angle_rad` and `friction_nm_s_per_rad`, each checked within
/// what keeps the rig's physics finite.
pub(crate) fn rig(
    ctx: &Ctx<'_>,
    load: &Option<S<RawRsLoad>>,
    start_angle_rad: &Option<S<f64>>,
    friction: &Option<S<f64>>,
) -> Res<Rig> {
    let load = load
        .as_ref()
        .map(|load| -> Res<Load> {
            Ok(match &load.value {
                RawRsLoad::NoLoad(_) => Load::None,
                RawRsLoad::Disc(disc) => Load::Disc {
                    mass_kg: bounded(ctx, &disc.mass_kg, "mass_kg", true, MAX_MASS_KG)?,
                    radius_m: bounded(ctx, &disc.radius_m, "radius_m", true, MAX_LENGTH_M)?,
                },
                RawRsLoad::Pendulum(p) => Load::Pendulum {
                    mass_kg: bounded(ctx, &p.mass_kg, "mass_kg", true, MAX_MASS_KG)?,
                    length_m: bounded(ctx, &p.length_m, "length_m", true, MAX_LENGTH_M)?,
                },
            })
        })
        .transpose()?;
    let start_angle_rad = start_angle_rad
        .as_ref()
        .map(|a| bounded(ctx, a, "start_angle_rad", false, MAX_START_ANGLE_RAD))
        .transpose()?;
    let friction_nm_s_per_rad = friction
        .as_ref()
        .map(|f| {
            let friction = ctx.non_negative(f, "friction_nm_s_per_rad")?;
            bounded(
                ctx,
                f,
                "friction_nm_s_per_rad",
                false,
                MAX_FRICTION_NM_S_PER_RAD,
            )
            .map(|_| friction)
        })
        .transpose()?;
    Ok(Rig {
        load,
        start_angle_rad,
        friction_nm_s_per_rad,
    })
}

/// The settings of a `kind: robstride` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, at: Pos) -> Res<RobstrideSettings> {
    let Some(list) = &d.motors else {
        return Err(ctx.err(
            at,
            "a robstride device needs `motors: [{id: 1, model: RS03}, ...]`",
        ));
    };
    if list.value.is_empty() {
        return Err(ctx.err(pos(list), "`motors` is empty"));
    }
    let mut motors: Vec<MotorConfig> = Vec::new();
    for m in &list.value {
        let id = can_id(ctx, &m.value.id, "id")?;
        if motors.iter().any(|other| other.can_id == id) {
            return Err(ctx.err(pos(&m.value.id), format!("duplicate motor id {id}")));
        }
        let model = Model::named(&m.value.model.value)
            .map_err(|e| ctx.err(pos(&m.value.model), format!("`model`: {e}")))?;
        let mut config = MotorConfig::new(id, model);
        let rig = rig(
            ctx,
            &m.value.load,
            &m.value.start_angle_rad,
            &m.value.friction_nm_s_per_rad,
        )?;
        if let Some(load) = rig.load {
            config.load = load;
        }
        if let Some(angle) = rig.start_angle_rad {
            config.start_angle_rad = angle;
        }
        if let Some(friction) = rig.friction_nm_s_per_rad {
            config.friction_nm_s_per_rad = friction;
        }
        motors.push(config);
    }
    Ok(RobstrideSettings {
        bus: named_bus(ctx, &d.bus)?,
        motors,
    })
}
