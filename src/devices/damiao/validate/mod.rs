//! Layer 2 of the Damiao grammar: the `damiao` device kind, the `damiao:` step and the
//! `motors:` conditions.

use driver::damiao::{MAX_ESC_ID, MAX_MST_ID};
use sim::damiao::{Model, MotorConfig, OPENARM_MST_OFFSET};

use super::model::DamiaoSettings;
use super::raw::{RawDmMotor, RawSettings};
use crate::devices::contract::motor_bus::listed;
use crate::devices::contract::motor_rig::rig;
use crate::devices::named_bus;
use crate::scenario::error::{suggestion, Pos};
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

mod checks;
mod fault;
pub(super) mod step;
#[cfg(test)]
mod tests;

pub(crate) use checks::checks;
pub(crate) use fault::fault;
pub(crate) use step::step;

/// A motor's ESC_ID as a step, condition or fault names it: 1..=0x4FE (the force-position
/// command goes to 0x300 + ESC_ID, below the register identifier 0x7FF).
pub(super) fn esc_id(ctx: &Ctx<'_>, v: &S<i64>, key: &str) -> Res<u16> {
    esc_id_at(ctx, v.value, pos(v), key)
}

/// [`esc_id`] of a number written at `at`.
pub(super) fn esc_id_at(ctx: &Ctx<'_>, value: i64, at: Pos, key: &str) -> Res<u16> {
    match u16::try_from(value) {
        Ok(id) if (1..=MAX_ESC_ID).contains(&id) => Ok(id),
        _ => Err(ctx.err(
            at,
            format!(
                "`{key}`: ESC_ID {value} out of range, expected 1..={MAX_ESC_ID} (0x{MAX_ESC_ID:X}: the force-position command goes to 0x300 + ESC_ID, below 0x7FF)"
            ),
        )),
    }
}

/// The place of motor `motor` in device `device`'s `motors:` (its parts are its motors'
/// ESC_IDs, [`crate::devices::damiao::Kind`]'s `parts`), or an error at `at` listing them.
pub(super) fn on_device(ctx: &Ctx<'_>, device: usize, motor: u16, at: Pos) -> Res<usize> {
    let parts = ctx.parts.get(device).map_or(&[][..], Vec::as_slice);
    let id = motor.to_string();
    parts.iter().position(|p| *p == id).ok_or_else(|| {
        let names: Vec<&str> = parts.iter().map(String::as_str).collect();
        ctx.err(
            at,
            format!(
                "no motor {motor} on device `{}`; its motors: {}{}",
                ctx.devices.get(device).map_or("", |(n, _)| n.as_str()),
                names.join(", "),
                suggestion(&id, &names)
            ),
        )
    })
}

/// The model a motor entry names, with the nearest name when it names none.
fn model(ctx: &Ctx<'_>, v: &S<String>) -> Res<Model> {
    Model::named(&v.value).map_err(|e| {
        let names: Vec<&str> = Model::ALL.iter().map(|m| m.name()).collect();
        ctx.err(
            pos(v),
            format!(
                "`model`: {e}{}",
                suggestion(&v.value.to_ascii_uppercase(), &names)
            ),
        )
    })
}

/// The identifiers a motor is commanded on: its ESC_ID and the three mode offsets.
fn command_ids(esc_id: u16) -> [u16; 4] {
    [esc_id, 0x100 + esc_id, 0x200 + esc_id, 0x300 + esc_id]
}

/// The settings of a `kind: damiao` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, at: Pos) -> Res<DamiaoSettings> {
    let list = listed(
        ctx,
        &d.motors,
        "a damiao device needs `motors: [{id: 1, model: DM4310}, ...]`",
        at,
    )?;
    let mut motors: Vec<MotorConfig> = Vec::new();
    for m in list {
        let config = motor(ctx, &m.value)?;
        if motors.iter().any(|other| other.esc_id == config.esc_id) {
            return Err(ctx.err(
                pos(&m.value.id),
                format!("duplicate motor id {}", config.esc_id),
            ));
        }
        motors.push(config);
    }
    // Every motor answers on an identifier of its own, on which no motor is commanded: a
    // feedback frame on another motor's command identifier would be taken as a command.
    for (k, (m, config)) in list.iter().zip(&motors).enumerate() {
        let at = m.value.feedback_id.as_ref().map_or(pos(&m.value.id), pos);
        let given = if m.value.feedback_id.is_some() {
            "`feedback_id`"
        } else {
            "its default feedback_id, id + 0x10"
        };
        let mst = config.mst_id;
        if let Some(other) = motors.iter().find(|o| command_ids(o.esc_id).contains(&mst)) {
            return Err(ctx.err(
                at,
                format!(
                    "motor {} answers on 0x{mst:02X} ({given}), an identifier motor {} is commanded on: give each motor a `feedback_id` no motor is commanded on",
                    config.esc_id, other.esc_id
                ),
            ));
        }
        if let Some(other) = motors[..k].iter().find(|o| o.mst_id == mst) {
            return Err(ctx.err(
                at,
                format!(
                    "motors {} and {} both answer on 0x{mst:02X}: give each its own `feedback_id`",
                    other.esc_id, config.esc_id
                ),
            ));
        }
    }
    Ok(DamiaoSettings {
        bus: named_bus(ctx, &d.bus)?,
        motors,
    })
}

/// One motor entry.
fn motor(ctx: &Ctx<'_>, m: &RawDmMotor) -> Res<MotorConfig> {
    let id = esc_id(ctx, &m.id, "id")?;
    let model = model(ctx, &m.model)?;
    let mut config = MotorConfig::new(id, model);
    config.mst_id = match &m.feedback_id {
        None => id + OPENARM_MST_OFFSET,
        Some(f) => match u16::try_from(f.value) {
            Ok(mst) if mst <= MAX_MST_ID => mst,
            _ => {
                return Err(ctx.err(
                    pos(f),
                    format!(
                        "`feedback_id`: {} out of range, expected 0..={MAX_MST_ID} (0x{MAX_MST_ID:X}; 0x7FF carries the register requests)",
                        f.value
                    ),
                ))
            }
        },
    };
    rig(ctx, &m.load, &m.start_angle_rad, &m.friction_nm_s_per_rad)?.apply(
        &mut config.load,
        &mut config.start_angle_rad,
        &mut config.friction_nm_s_per_rad,
    );
    Ok(config)
}
