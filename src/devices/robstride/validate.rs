//! Layer 2 of the RobStride grammar: the `robstride` device kind, the `robstride:` step and
//! the `motors:` conditions.

use std::collections::BTreeMap;
use std::time::Duration;

use driver::robstride::OpControl;
use sim::robstride::faults::{
    check_bus_voltage_v, check_external_torque_nm, check_temperature_c, max_external_torque_nm,
    ValueError as RsValueError,
};
use sim::robstride::{Fault, Load, Model, MotorConfig};

use super::model::{
    MotorCheck, MotorCond, RobstrideAction, RobstrideSettings, RsCommand, RsFault, FEEDBACK_KINDS,
    MIT_MODES, MODE_STATES, PARAMS, PROTOCOLS, REPORT_FLAGS, RUN_MODES, STATUS_FAULTS,
};
use super::raw::{RawConds, RawFault, RawMotorConds, RawRsLoad, RawRsStep, RawSettings, RawStep};
use crate::scenario::error::Pos;
use crate::scenario::{DeviceStep, Near};
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

/// Default tolerance of `read_param` expectations.
const DEFAULT_PARAM_TOLERANCE: f64 = 0.01;
/// Default tolerances of the per-motor conditions.
const DEFAULT_TOLERANCE_RAD: f64 = 0.05;
const DEFAULT_TOLERANCE_RAD_S: f64 = 0.2;
const DEFAULT_TOLERANCE_NM: f64 = 0.5;

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
        let model = Model::from_name(&m.value.model.value).ok_or_else(|| {
            ctx.err(
                pos(&m.value.model),
                format!(
                    "`model`: unknown RobStride model `{}`; expected one of: RS00, RS01, RS02, RS03, RS04, RS05, RS06, EL05",
                    m.value.model.value
                ),
            )
        })?;
        let mut config = MotorConfig::new(id, model);
        if let Some(load) = &m.value.load {
            config.load = match &load.value {
                RawRsLoad::NoLoad(_) => Load::None,
                RawRsLoad::Disc(disc) => Load::Disc {
                    mass_kg: bounded(ctx, &disc.mass_kg, "mass_kg", true, MAX_MASS_KG)?,
                    radius_m: bounded(ctx, &disc.radius_m, "radius_m", true, MAX_LENGTH_M)?,
                },
                RawRsLoad::Pendulum(p) => Load::Pendulum {
                    mass_kg: bounded(ctx, &p.mass_kg, "mass_kg", true, MAX_MASS_KG)?,
                    length_m: bounded(ctx, &p.length_m, "length_m", true, MAX_LENGTH_M)?,
                },
            };
        }
        if let Some(a) = &m.value.start_angle_rad {
            config.start_angle_rad =
                bounded(ctx, a, "start_angle_rad", false, MAX_START_ANGLE_RAD)?;
        }
        if let Some(f) = &m.value.friction_nm_s_per_rad {
            let friction = ctx.non_negative(f, "friction_nm_s_per_rad")?;
            config.friction_nm_s_per_rad = bounded(
                ctx,
                f,
                "friction_nm_s_per_rad",
                false,
                MAX_FRICTION_NM_S_PER_RAD,
            )
            .map(|_| friction)?;
        }
        motors.push(config);
    }
    Ok(RobstrideSettings { motors })
}

/// Which argument keys each command takes (`motor` aside).
const COMMAND_KEYS: [(&str, &str, &[&str]); 36] = [
    ("enable", "robstride enable", &[]),
    ("disable", "robstride disable", &["clear"]),
    ("mode", "robstride mode", &["mode"]),
    (
        "op_control",
        "robstride op_control",
        &["angle_rad", "speed_rad_s", "kp", "kd", "torque_nm"],
    ),
    (
        "velocity",
        "robstride velocity",
        &["speed_rad_s", "limit_cur_a", "acc_rad_s2"],
    ),
    (
        "profile",
        "robstride profile",
        &["target_rad", "vel_max_rad_s", "acc_rad_s2"],
    ),
    ("current", "robstride current", &["iq_a"]),
    ("csp", "robstride csp", &["target_rad", "limit_spd_rad_s"]),
    ("set_zero", "robstride set_zero", &[]),
    ("zero_here", "robstride zero_here", &[]),
    (
        "read_param",
        "robstride read_param",
        &["param", "expect", "tolerance"],
    ),
    ("write_param", "robstride write_param", &["param", "value"]),
    ("set_can_id", "robstride set_can_id", &["new_id"]),
    ("save", "robstride save", &[]),
    ("restart", "robstride restart", &[]),
    ("active_report", "robstride active_report", &["on"]),
    ("report_period", "robstride report_period", &["period_ms"]),
    ("can_timeout", "robstride can_timeout", &["window_ms"]),
    ("poll", "robstride poll", &[]),
    ("set_protocol", "robstride set_protocol", &["protocol"]),
    ("mit_enable", "robstride mit_enable", &[]),
    ("mit_stop", "robstride mit_stop", &[]),
    (
        "mit_control",
        "robstride mit_control",
        &["angle_rad", "speed_rad_s", "kp", "kd", "torque_nm"],
    ),
    ("mit_mode", "robstride mit_mode", &["mode"]),
    (
        "mit_position",
        "robstride mit_position",
        &["target_rad", "limit_spd_rad_s"],
    ),
    (
        "mit_velocity",
        "robstride mit_velocity",
        &["speed_rad_s", "limit_cur_a"],
    ),
    ("mit_zero", "robstride mit_zero", &[]),
    ("mit_clear", "robstride mit_clear", &[]),
    (
        "mit_read_param",
        "robstride mit_read_param",
        &["param", "expect", "tolerance"],
    ),
    (
        "mit_set_protocol",
        "robstride mit_set_protocol",
        &["protocol"],
    ),
    ("mit_active_report", "robstride mit_active_report", &["on"]),
    ("inject", "robstride inject", &["fault"]),
    ("remove_cause", "robstride remove_cause", &["fault"]),
    ("set_temperature", "robstride set_temperature", &["temp_c"]),
    (
        "set_bus_voltage",
        "robstride set_bus_voltage",
        &["voltage_v"],
    ),
    (
        "external_torque",
        "robstride external_torque",
        &["torque_nm"],
    ),
];

/// The argument keys present in a step, with their positions.
fn present_keys(a: &RawRsStep) -> Vec<(&'static str, Pos)> {
    let mut out = Vec::new();
    macro_rules! keys {
        ($($field:ident => $name:literal),* $(,)?) => {
            $(if let Some(v) = &a.$field { out.push(($name, pos(v))); })*
        };
    }
    keys!(
        clear => "clear", mode => "mode", angle_rad => "angle_rad", speed_rad_s => "speed_rad_s",
        kp => "kp", kd => "kd", torque_nm => "torque_nm", limit_cur_a => "limit_cur_a",
        acc_rad_s2 => "acc_rad_s2", target_rad => "target_rad", vel_max_rad_s => "vel_max_rad_s",
        iq_a => "iq_a", limit_spd_rad_s => "limit_spd_rad_s", param => "param", value => "value",
        expect => "expect", tolerance => "tolerance", new_id => "new_id", on => "on",
        period_ms => "period_ms", window_ms => "window_ms", fault => "fault", temp_c => "temp_c",
        voltage_v => "voltage_v", protocol => "protocol",
    );
    out
}

/// A number the driver and emulator hold as `f32`: finite in `f32` too (1e308 would become
/// infinity on the way).
fn f32_of(ctx: &Ctx<'_>, v: &S<f64>, key: &str) -> Res<f32> {
    let single = ctx.finite(v, key)? as f32;
    if single.is_finite() {
        Ok(single)
    } else {
        Err(ctx.err(
            pos(v),
            format!("`{key}` is too large (beyond ±3.4e38, the range of the motor's numbers)"),
        ))
    }
}

/// A value of an emulator command, checked against the emulator's own bounds
/// ([`sim::robstride::faults`]) so an absurd one is an error at its line, not NaN physics.
fn emulator_value(
    ctx: &Ctx<'_>,
    v: &S<f64>,
    check: impl Fn(f64) -> Result<f64, RsValueError>,
) -> Res<f64> {
    check(v.value).map_err(|e| ctx.err(pos(v), e.to_string()))
}

/// A RobStride step.
pub(crate) fn step(
    ctx: &Ctx<'_>,
    raw: &RawStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<RobstrideAction>)> {
    match raw {
        RawStep::Robstride(a) => robstride_step(ctx, a, at),
    }
}

/// A RobStride emulator fault on one motor.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RsFault> {
    let m = ctx.required(&raw.args.motor, "motor", "a robstride fault", at)?;
    Ok(RsFault {
        motor: can_id(ctx, m, "motor")?,
        fault: raw.kind,
    })
}

/// A `robstride:` step.
fn robstride_step(
    ctx: &Ctx<'_>,
    a: &RawRsStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<RobstrideAction>)> {
    let Some(cmd) = &a.command else {
        let names: Vec<&str> = COMMAND_KEYS.iter().map(|(n, _, _)| *n).collect();
        return Err(ctx.err(
            at,
            format!("`robstride` needs `do:` with one of: {}", names.join(", ")),
        ));
    };
    let table: Vec<(&str, &str)> = COMMAND_KEYS.iter().map(|(n, _, _)| (*n, *n)).collect();
    let name = ctx.choice(cmd, "do", &table)?;
    let (label, allowed) = COMMAND_KEYS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map_or(("robstride", &[][..]), |(_, l, k)| (*l, *k));
    ctx.only_arguments(
        &present_keys(a),
        allowed,
        name,
        "no arguments besides `motor`",
    )?;
    let need = |v: &Option<S<f64>>, key: &str| -> Res<f32> {
        let v = ctx.required(v, key, name, at)?;
        f32_of(ctx, v, key)
    };
    let need_ms = |v: &Option<S<i64>>, key: &str| -> Res<Duration> {
        let v = ctx.required(v, key, name, at)?;
        ctx.millis(v, key)
    };
    let opt = |v: &Option<S<f64>>, key: &str| -> Res<f32> {
        v.as_ref().map_or(Ok(0.0), |v| f32_of(ctx, v, key))
    };
    let param = |v: &Option<S<String>>| {
        let v = ctx.required(v, "param", name, at)?;
        ctx.choice(v, "param", &PARAMS)
    };
    let fault = |v: &Option<S<String>>| {
        let v = ctx.required(v, "fault", name, at)?;
        let names: Vec<(Fault, &str)> = Fault::ALL.iter().map(|f| (*f, f.name())).collect();
        ctx.choice(v, "fault", &names)
    };
    let protocol = |v: &Option<S<String>>| {
        let v = ctx.required(v, "protocol", name, at)?;
        ctx.choice(v, "protocol", &PROTOCOLS)
    };
    let expectation = || -> Res<Option<Near>> {
        match &a.expect {
            Some(e) => Ok(Some(Near {
                value: ctx.finite(e, "expect")?,
                tolerance: a
                    .tolerance
                    .as_ref()
                    .map_or(Ok(DEFAULT_PARAM_TOLERANCE), |t| {
                        ctx.non_negative(t, "tolerance")
                    })?,
            })),
            None => Ok(None),
        }
    };
    let command = match name {
        "enable" => RsCommand::Enable,
        "disable" => RsCommand::Disable {
            clear: a.clear.as_ref().is_some_and(|c| c.value),
        },
        "mode" => {
            let m = ctx.required(&a.mode, "mode", name, at)?;
            RsCommand::Mode(ctx.choice(m, "mode", &RUN_MODES)?)
        }
        "op_control" => RsCommand::OpControl(OpControl {
            torque_nm: opt(&a.torque_nm, "torque_nm")?,
            angle_rad: opt(&a.angle_rad, "angle_rad")?,
            speed_rad_s: opt(&a.speed_rad_s, "speed_rad_s")?,
            kp: opt(&a.kp, "kp")?,
            kd: opt(&a.kd, "kd")?,
        }),
        "velocity" => RsCommand::Velocity {
            speed_rad_s: need(&a.speed_rad_s, "speed_rad_s")?,
            limit_cur_a: need(&a.limit_cur_a, "limit_cur_a")?,
            acc_rad_s2: need(&a.acc_rad_s2, "acc_rad_s2")?,
        },
        "profile" => RsCommand::Profile {
            target_rad: need(&a.target_rad, "target_rad")?,
            vel_max_rad_s: need(&a.vel_max_rad_s, "vel_max_rad_s")?,
            acc_rad_s2: need(&a.acc_rad_s2, "acc_rad_s2")?,
        },
        "current" => RsCommand::Current {
            iq_a: need(&a.iq_a, "iq_a")?,
        },
        "csp" => RsCommand::Csp {
            target_rad: need(&a.target_rad, "target_rad")?,
            limit_spd_rad_s: need(&a.limit_spd_rad_s, "limit_spd_rad_s")?,
        },
        "set_zero" => RsCommand::SetZero,
        "zero_here" => RsCommand::ZeroHere,
        "read_param" => RsCommand::ReadParam {
            param: param(&a.param)?,
            expect: expectation()?,
        },
        "write_param" => RsCommand::WriteParam {
            param: param(&a.param)?,
            value: ctx.finite(ctx.required(&a.value, "value", name, at)?, "value")?,
        },
        "set_can_id" => RsCommand::SetCanId {
            new_id: can_id(ctx, ctx.required(&a.new_id, "new_id", name, at)?, "new_id")?,
        },
        "save" => RsCommand::Save,
        "restart" => RsCommand::Restart,
        "active_report" => RsCommand::ActiveReport {
            on: ctx.required(&a.on, "on", name, at)?.value,
        },
        "report_period" => RsCommand::ReportPeriod {
            period: need_ms(&a.period_ms, "period_ms")?,
        },
        "can_timeout" => RsCommand::CanTimeout {
            window: need_ms(&a.window_ms, "window_ms")?,
        },
        "poll" => RsCommand::Poll,
        "set_protocol" => RsCommand::SetProtocol(protocol(&a.protocol)?),
        "mit_enable" => RsCommand::MitEnable,
        "mit_stop" => RsCommand::MitStop,
        "mit_control" => RsCommand::MitControl(OpControl {
            torque_nm: opt(&a.torque_nm, "torque_nm")?,
            angle_rad: opt(&a.angle_rad, "angle_rad")?,
            speed_rad_s: opt(&a.speed_rad_s, "speed_rad_s")?,
            kp: opt(&a.kp, "kp")?,
            kd: opt(&a.kd, "kd")?,
        }),
        "mit_mode" => {
            let m = ctx.required(&a.mode, "mode", name, at)?;
            RsCommand::MitMode(ctx.choice(m, "mode", &MIT_MODES)?)
        }
        "mit_position" => RsCommand::MitPosition {
            target_rad: need(&a.target_rad, "target_rad")?,
            limit_spd_rad_s: need(&a.limit_spd_rad_s, "limit_spd_rad_s")?,
        },
        "mit_velocity" => RsCommand::MitVelocity {
            speed_rad_s: need(&a.speed_rad_s, "speed_rad_s")?,
            limit_cur_a: need(&a.limit_cur_a, "limit_cur_a")?,
        },
        "mit_zero" => RsCommand::MitZero,
        "mit_clear" => RsCommand::MitClear,
        "mit_read_param" => RsCommand::MitReadParam {
            param: param(&a.param)?,
            expect: expectation()?,
        },
        "mit_set_protocol" => RsCommand::MitSetProtocol(protocol(&a.protocol)?),
        "mit_active_report" => RsCommand::MitActiveReport {
            on: ctx.required(&a.on, "on", name, at)?.value,
        },
        "inject" => RsCommand::Inject(fault(&a.fault)?),
        "remove_cause" => RsCommand::RemoveCause(fault(&a.fault)?),
        "set_temperature" => RsCommand::SetTemperature {
            temp_c: emulator_value(
                ctx,
                ctx.required(&a.temp_c, "temp_c", name, at)?,
                check_temperature_c,
            )?,
        },
        "set_bus_voltage" => RsCommand::SetBusVoltage {
            voltage_v: emulator_value(
                ctx,
                ctx.required(&a.voltage_v, "voltage_v", name, at)?,
                check_bus_voltage_v,
            )?,
        },
        // The motor's model is not known here: the largest model's bound catches the absurd
        // values; the emulator checks the motor's own bound when the step runs.
        _ => RsCommand::ExternalTorque {
            torque_nm: emulator_value(
                ctx,
                ctx.required(&a.torque_nm, "torque_nm", name, at)?,
                |t| {
                    let strongest = Model::ALL
                        .into_iter()
                        .max_by(|a, b| {
                            max_external_torque_nm(*a).total_cmp(&max_external_torque_nm(*b))
                        })
                        .unwrap_or(Model::RS04);
                    check_external_torque_nm(strongest, t)
                },
            )?,
        },
    };
    let motor = match (&command, &a.motor) {
        (RsCommand::Restart, Some(m)) => {
            return Err(ctx.err(
                pos(m),
                "`do: restart` power-cycles the whole bus; it takes no `motor`",
            ))
        }
        (RsCommand::Restart, None) => 0,
        (_, m) => can_id(ctx, ctx.required(m, "motor", name, at)?, "motor")?,
    };
    let device = ctx.device_of_kind(&a.device, at, "robstride", "this step")?;
    let timeout = ctx.timeout(&a.timeout_ms)?;
    let expect_error = ctx.expect_error(&a.expect_error)?;
    Ok((
        label,
        DeviceStep {
            device,
            action: RobstrideAction { motor, command },
            timeout,
            expect_error,
        },
    ))
}

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
        let tol = |t: &Option<S<f64>>, key: &str, default: f64| {
            t.as_ref().map_or(Ok(default), |t| ctx.non_negative(t, key))
        };
        let mut push = |cond: MotorCond| out.push(MotorCheck { motor, cond });
        if let Some(p) = &c.position_rad {
            push(MotorCond::Position(Near {
                value: ctx.finite(p, "position_rad")?,
                tolerance: tol(&c.tolerance_rad, "tolerance_rad", DEFAULT_TOLERANCE_RAD)?,
            }));
        }
        if let Some(v) = &c.velocity_rad_s {
            push(MotorCond::Velocity(Near {
                value: ctx.finite(v, "velocity_rad_s")?,
                tolerance: tol(
                    &c.tolerance_rad_s,
                    "tolerance_rad_s",
                    DEFAULT_TOLERANCE_RAD_S,
                )?,
            }));
        }
        if let Some(t) = &c.torque_nm {
            push(MotorCond::Torque(Near {
                value: ctx.finite(t, "torque_nm")?,
                tolerance: tol(&c.tolerance_nm, "tolerance_nm", DEFAULT_TOLERANCE_NM)?,
            }));
        }
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::devices::robstride::model::{MotorCheck, MotorCond, RsCommand};
    use crate::harness::model::{Check, DeviceKind, StepKind};
    use crate::harness::parse_scenario;
    use crate::harness::test_support::error_of;

    const BENCH: &str = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 1, model: RS03, load: {pendulum: {mass_kg: 1.0, length_m: 0.3}}}, {id: 2, model: RS00}]}\n";

    #[test]
    fn a_valid_bench_step_and_condition_are_typed() {
        let text = format!(
            "{BENCH}steps:\n  - robstride: {{motor: 2, do: velocity, speed_rad_s: 5, limit_cur_a: 10, acc_rad_s2: 20}}\n  - wait_until: {{motors: {{2: {{velocity_rad_s: 5.0, faults: [stall_overload, under_voltage]}}}}, timeout_ms: 100}}\n"
        );
        let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
        let DeviceKind::Robstride(settings) = &s.bench.devices[0].kind else {
            panic!("not a robstride device");
        };
        assert_eq!(settings.motors.len(), 2);
        assert_eq!(
            settings.motors[0].load,
            sim::robstride::Load::Pendulum {
                mass_kg: 1.0,
                length_m: 0.3
            }
        );
        assert_eq!(s.steps[0].label, "robstride velocity");
        let StepKind::Action {
            action: crate::devices::Action::Robstride(a),
            ..
        } = &s.steps[0].kind
        else {
            panic!("not a robstride action");
        };
        assert_eq!(a.motor, 2);
        assert!(matches!(a.command, RsCommand::Velocity { speed_rad_s, .. } if speed_rad_s == 5.0));
        let StepKind::WaitUntil { checks, .. } = &s.steps[1].kind else {
            panic!("not wait_until");
        };
        // Flags come back in bit order whatever order the file lists them in.
        assert!(checks.contains(&Check::Robstride(MotorCheck {
            motor: 2,
            cond: MotorCond::StatusFaults(vec!["under_voltage", "stall_overload"])
        })));
    }

    #[test]
    fn absurd_load_parameters_are_refused_at_their_position() {
        let bench = |load: &str| {
            format!("bench:\n  devices:\n    bus: {{kind: robstride, motors: [{{id: 1, model: RS03, {load}}}]}}\nsteps:\n  - wait_ms: 1\n")
        };
        let e = error_of(&bench("load: {pendulum: {mass_kg: 1e308, length_m: 0.3}}"));
        assert!(
            e.starts_with("broken.yaml:3:85: `mass_kg` must be at most 1000, got 1e308"),
            "{e}"
        );
        let e = error_of(&bench("load: {pendulum: {mass_kg: 1.0, length_m: 1e308}}"));
        assert!(e.contains("`length_m` must be at most 10"), "{e}");
        let e = error_of(&bench("load: {disc: {mass_kg: 1.0, radius_m: 1e200}}"));
        assert!(e.contains("`radius_m` must be at most 10"), "{e}");
        let e = error_of(&bench("friction_nm_s_per_rad: 1e300"));
        assert!(e.contains("`friction_nm_s_per_rad` must be between"), "{e}");
        let e = error_of(&bench("start_angle_rad: -1e300"));
        assert!(
            e.contains("`start_angle_rad` must be between -100 and 100"),
            "{e}"
        );
    }

    #[test]
    fn absurd_emulator_values_are_refused_at_their_position() {
        let step = |args: &str| format!("{BENCH}steps:\n  - robstride: {{motor: 1, {args}}}\n");
        let e = error_of(&step("do: external_torque, torque_nm: 1e308"));
        assert_eq!(
            e,
            "broken.yaml:5:59: `torque_nm` must be between -1200 and 1200, got 1e308"
        );
        let e = error_of(&step("do: set_temperature, temp_c: 1e308"));
        assert!(
            e.starts_with("broken.yaml:5:56: `temp_c` must be between -40 and 200, got 1e308"),
            "{e}"
        );
        let e = error_of(&step("do: set_bus_voltage, voltage_v: -3"));
        assert!(
            e.contains("`voltage_v` must be between 0 and 120, got -3"),
            "{e}"
        );
        // Numbers the motor holds as f32 must fit one.
        let e = error_of(&step("do: current, iq_a: 1e300"));
        assert!(e.contains("`iq_a` is too large"), "{e}");
        // Plausible values pass.
        let ok = step("do: external_torque, torque_nm: -30.0");
        assert!(parse_scenario(Path::new("ok.yaml"), &ok).is_ok());
    }

    #[test]
    fn mit_commands_and_protocols_are_typed_and_checked() {
        let step = |args: &str| format!("{BENCH}steps:\n  - robstride: {{motor: 1, {args}}}\n");
        let command = |args: &str| {
            let s = parse_scenario(Path::new("ok.yaml"), &step(args)).expect("valid");
            let StepKind::Action {
                action: crate::devices::Action::Robstride(a),
                ..
            } = &s.steps[0].kind
            else {
                panic!("not a robstride action");
            };
            (s.steps[0].label.clone(), a.command.clone())
        };
        assert_eq!(
            command("do: set_protocol, protocol: mit"),
            (
                "robstride set_protocol".to_owned(),
                RsCommand::SetProtocol(driver::robstride::Protocol::Mit)
            )
        );
        assert_eq!(
            command("do: mit_mode, mode: position").1,
            RsCommand::MitMode(driver::robstride::MitMode::Position)
        );
        assert!(matches!(
            command("do: mit_velocity, speed_rad_s: 2, limit_cur_a: 5").1,
            RsCommand::MitVelocity { speed_rad_s, limit_cur_a } if speed_rad_s == 2.0 && limit_cur_a == 5.0
        ));
        assert!(command("do: mit_zero").1.is_mit());
        assert!(!command("do: set_protocol, protocol: private").1.is_mit());
        // A private run mode is not an MIT one, and a protocol must be named.
        let e = error_of(&step("do: mit_mode, mode: csp"));
        assert!(
            e.contains("`mode`") && e.contains("mit, position, velocity"),
            "{e}"
        );
        let e = error_of(&step("do: set_protocol, protocol: ethercat"));
        assert!(e.contains("private, canopen, mit"), "{e}");
        let e = error_of(&step("do: mit_set_protocol"));
        assert!(e.contains("`protocol`"), "{e}");
        let e = error_of(&step("do: mit_position, target_rad: 1.0"));
        assert!(e.contains("`limit_spd_rad_s`"), "{e}");
    }

    #[test]
    fn unknown_model_is_an_error_at_its_position() {
        let text = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 1, model: RS09}]}\nsteps:\n  - wait_ms: 1\n";
        assert!(error_of(text).starts_with(
            "broken.yaml:3:52: `model`: unknown RobStride model `RS09`; expected one of: RS00"
        ));
    }

    #[test]
    fn duplicate_and_out_of_range_motor_ids_are_refused() {
        let text = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 1, model: RS03}, {id: 1, model: RS00}]}\nsteps:\n  - wait_ms: 1\n";
        assert_eq!(error_of(text), "broken.yaml:3:64: duplicate motor id 1");
        let text = "bench:\n  devices:\n    bus: {kind: robstride, motors: [{id: 128, model: RS03}]}\nsteps:\n  - wait_ms: 1\n";
        assert_eq!(
            error_of(text),
            "broken.yaml:3:42: `id`: CAN ID 128 out of range, expected 1..=127"
        );
    }

    #[test]
    fn unknown_key_in_a_step_is_rejected() {
        let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: enable, speed: 3}}\n");
        let e = error_of(&text);
        assert!(
            e.starts_with("broken.yaml:5:39: unknown key `speed`"),
            "{e}"
        );
    }

    #[test]
    fn an_argument_of_another_command_names_the_valid_ones() {
        let text =
            format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: current, speed_rad_s: 3}}\n");
        assert_eq!(
            error_of(&text),
            "broken.yaml:5:53: `speed_rad_s` does not apply to `do: current`; it takes: iq_a"
        );
    }

    #[test]
    fn missing_arguments_and_unknown_names_are_errors() {
        let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: csp, target_rad: 1}}\n");
        assert_eq!(
            error_of(&text),
            "broken.yaml:5:5: `csp` needs `limit_spd_rad_s`"
        );
        let text =
            format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: read_param, param: loc_kq}}\n");
        assert!(error_of(&text).starts_with(
            "broken.yaml:5:50: `param`: unknown value `loc_kq`; expected one of: run_mode"
        ));
        let text =
            format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: inject, fault: melted}}\n");
        assert!(error_of(&text).starts_with("broken.yaml:5:46: `fault`: unknown value `melted`"));
        let text = format!("{BENCH}steps:\n  - robstride: {{do: enable}}\n");
        assert_eq!(error_of(&text), "broken.yaml:5:5: `enable` needs `motor`");
        let text = format!("{BENCH}steps:\n  - robstride: {{motor: 1, do: restart}}\n");
        assert!(error_of(&text).starts_with("broken.yaml:5:24: `do: restart` power-cycles"));
    }

    #[test]
    fn bad_motor_conditions_are_errors() {
        let text = format!("{BENCH}steps:\n  - expect: {{motors: {{1: {{faults: [too_hot]}}}}}}\n");
        assert!(error_of(&text).starts_with(
            "broken.yaml:5:36: `faults`: unknown flag `too_hot`; expected one of: under_voltage"
        ));
        let text =
            format!("{BENCH}steps:\n  - expect: {{motors: {{1: {{mode_state: running}}}}}}\n");
        assert!(
            error_of(&text).starts_with("broken.yaml:5:39: `mode_state`: unknown value `running`")
        );
        let text = format!("{BENCH}steps:\n  - expect: {{motors: {{1: {{velocity: 3}}}}}}\n");
        assert!(error_of(&text).starts_with("broken.yaml:5:27: unknown key `velocity`"));
    }

    #[test]
    fn piper_settings_on_a_robstride_bus_and_motors_on_a_piper_are_refused() {
        let text = "bench:\n  devices:\n    bus: {kind: robstride, firmware: S-V1.8-8, motors: [{id: 1, model: RS03}]}\nsteps:\n  - wait_ms: 1\n";
        let e = error_of(text);
        assert!(
            e.starts_with("broken.yaml:3:") && e.contains("`firmware`"),
            "{e}"
        );
        let text = "bench:\n  devices:\n    arm: {kind: piper, motors: [{id: 1, model: RS03}]}\nsteps:\n  - wait_ms: 1\n";
        let e = error_of(text);
        assert!(
            e.starts_with("broken.yaml:3:") && e.contains("`motors`"),
            "{e}"
        );
    }

    #[test]
    fn a_step_or_fault_aimed_at_the_wrong_kind_is_refused_at_its_position() {
        let two = "bench:\n  devices:\n    arm: {kind: piper}\n    bus: {kind: robstride, motors: [{id: 1, model: RS03}]}\n";
        let e = error_of(&format!(
            "{two}steps:\n  - move_j: {{device: bus, joints_deg: [0, 0, 0, 0, 0, 0]}}\n"
        ));
        assert!(e.starts_with("broken.yaml:6:"), "{e}");
        assert!(e.contains("device `bus` is a robstride"), "{e}");
        let e = error_of(&format!(
            "{two}steps:\n  - robstride: {{device: arm, motor: 1, do: enable}}\n"
        ));
        assert!(e.contains("device `arm` is a piper"), "{e}");
        let e = error_of(&format!("{two}faults:\n  - {{at_ms: 5, device: arm, fault: {{robstride.stall_overload: {{motor: 1}}}}}}\nsteps:\n  - wait_ms: 1\n"));
        assert!(e.starts_with("broken.yaml:6:"), "{e}");
        assert!(e.contains("device `arm` is a piper"), "{e}");
    }

    #[test]
    fn a_robstride_fault_is_scheduled_with_its_motor() {
        let text = format!("{BENCH}faults:\n  - {{at_ms: 100, duration_ms: 50, fault: {{under_voltage: {{motor: 2}}}}}}\nsteps:\n  - wait_ms: 1\n");
        let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
        assert_eq!(s.faults.len(), 1);
        assert_eq!(s.faults[0].fault.describe(), "under_voltage motor 2");
        assert_eq!(
            s.faults[0].duration,
            Some(std::time::Duration::from_millis(50))
        );
    }
}
