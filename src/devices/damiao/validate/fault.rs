//! A Damiao emulator fault in a scenario's `faults:` list or an `inject:` step.

use sim::damiao::actuator::KIND as DAMIAO;
use sim::fault_args::FaultArgValue;

use super::{esc_id_at, on_device};
use crate::devices::damiao::model::DmFault;
use crate::devices::damiao::raw::RawFault;
use crate::devices::damiao::Kind;
use crate::devices::KindSpec;
use crate::scenario::error::Pos;
use crate::scenario::{Ctx, Res};

/// The argument naming the motor: its ESC_ID.
const MOTOR: &str = "motor";

/// A Damiao emulator fault on one motor: `motor` (its ESC_ID, a motor of the device) and the
/// fault's own value, checked by the emulator's one fault builder at that motor's model's
/// thresholds (the registry's `fault_label`, which the web view and Python reach too); an
/// error points at the argument it is about.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, device: Option<usize>, at: Pos) -> Res<DmFault> {
    let name = raw.kind.name();
    let args = raw.args.args();
    let motor_at = raw.args.place(MOTOR).unwrap_or(at);
    let motor = match args.get(MOTOR) {
        None => return Err(ctx.err(at, format!("`{name}` needs `{MOTOR}` (the motor's ESC_ID)"))),
        Some(FaultArgValue::Number(x)) if x.is_finite() && x.fract() == 0.0 => {
            // Whole: out-of-range values saturate and are refused below.
            esc_id_at(ctx, *x as i64, motor_at, MOTOR)?
        }
        Some(other) => {
            return Err(ctx.err(
                motor_at,
                format!("`{MOTOR}` must be a whole number (an ESC_ID), got {other}"),
            ))
        }
    };
    let is_damiao = |d: usize| ctx.devices.get(d).is_some_and(|(_, k)| *k == Kind::NAME);
    // The motor's device: the one the entry names, else the Damiao device that has it.
    let on = device.filter(|d| is_damiao(*d)).or_else(|| {
        (0..ctx.devices.len()).find(|d| {
            is_damiao(*d)
                && ctx
                    .parts
                    .get(*d)
                    .is_some_and(|p| p.contains(&motor.to_string()))
        })
    });
    let model = match (on, device) {
        (Some(d), _) => {
            let index = on_device(ctx, d, motor, motor_at)?;
            ctx.part_actuator(d, index).map(|m| m.name)
        }
        // Another kind's device: the harness says which kind it is.
        (None, Some(_)) => None,
        (None, None) => {
            return Err(ctx.err(motor_at, format!("no Damiao motor {motor} on the bench")))
        }
    };
    let values = raw.args.args_except(&[MOTOR]);
    let label = (DAMIAO.fault_label)(model.unwrap_or("DM4310"), name, &values, false)
        .map_err(|e| raw.args.refusal(ctx, at, e))?;
    Ok(DmFault {
        motor,
        fault: raw.kind,
        values,
        label,
    })
}
