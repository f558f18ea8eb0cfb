//! The `robstride:` step: which arguments each command takes, and each command typed.

use std::time::Duration;

use driver::robstride::{OpControl, Param, Protocol};
use sim::robstride::faults::{
    check_bus_voltage_v, check_external_torque_nm, check_temperature_c, max_external_torque_nm,
    ValueError as RsValueError,
};
use sim::robstride::{Fault, Model};

use super::can_id;
use crate::devices::contract::motor_bus::{expectation, wire_f32};
use crate::devices::robstride::model::{
    params, RobstrideAction, RsCommand, MIT_MODES, PROTOCOLS, RUN_MODES,
};
use crate::devices::robstride::raw::{RawRsStep, RawStep};
use crate::scenario::error::Pos;
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};
use crate::scenario::{DeviceStep, Near};

/// Default tolerance of `read_param` expectations.
const DEFAULT_PARAM_TOLERANCE: f64 = 0.01;

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
    let args = CommandArgs { ctx, a, name, at };
    let command = match private_command(&args)? {
        Some(command) => command,
        None => match mit_command(&args)? {
            Some(command) => command,
            None => side_door_command(&args)?,
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

/// One command's arguments as written, read with the command's name in every message.
struct CommandArgs<'c, 'a> {
    ctx: &'c Ctx<'a>,
    a: &'c RawRsStep,
    /// The command (`do:`).
    name: &'static str,
    /// The step.
    at: Pos,
}

impl CommandArgs<'_, '_> {
    /// A required number, as the wire's f32.
    fn need(&self, v: &Option<S<f64>>, key: &str) -> Res<f32> {
        let v = self.ctx.required(v, key, self.name, self.at)?;
        wire_f32(self.ctx, v, key)
    }

    /// A required duration in milliseconds.
    fn need_ms(&self, v: &Option<S<i64>>, key: &str) -> Res<Duration> {
        let v = self.ctx.required(v, key, self.name, self.at)?;
        self.ctx.millis(v, key)
    }

    /// An optional number, 0 when left out.
    fn opt(&self, v: &Option<S<f64>>, key: &str) -> Res<f32> {
        v.as_ref().map_or(Ok(0.0), |v| wire_f32(self.ctx, v, key))
    }

    /// A required value of `key`, checked by `check` as the emulator checks it.
    fn emulator(
        &self,
        v: &Option<S<f64>>,
        key: &str,
        check: impl Fn(f64) -> Result<f64, RsValueError>,
    ) -> Res<f64> {
        emulator_value(
            self.ctx,
            self.ctx.required(v, key, self.name, self.at)?,
            check,
        )
    }

    /// A required word of `table`.
    fn word<T: Copy>(&self, v: &Option<S<String>>, key: &str, table: &[(T, &str)]) -> Res<T> {
        let v = self.ctx.required(v, key, self.name, self.at)?;
        self.ctx.choice(v, key, table)
    }

    /// The required `param:`.
    fn param(&self) -> Res<Param> {
        self.word(&self.a.param, "param", &params())
    }

    /// The required `protocol:`.
    fn protocol(&self) -> Res<Protocol> {
        self.word(&self.a.protocol, "protocol", &PROTOCOLS)
    }

    /// The required `on:`.
    fn on(&self) -> Res<bool> {
        Ok(self
            .ctx
            .required(&self.a.on, "on", self.name, self.at)?
            .value)
    }

    /// The operation-control (MIT) frame's five values, each 0 when left out.
    fn op_control(&self) -> Res<OpControl> {
        let a = self.a;
        Ok(OpControl {
            torque_nm: self.opt(&a.torque_nm, "torque_nm")?,
            angle_rad: self.opt(&a.angle_rad, "angle_rad")?,
            speed_rad_s: self.opt(&a.speed_rad_s, "speed_rad_s")?,
            kp: self.opt(&a.kp, "kp")?,
            kd: self.opt(&a.kd, "kd")?,
        })
    }

    /// `expect:` (and `tolerance:`) of a parameter read.
    fn expectation(&self) -> Res<Option<Near>> {
        expectation(
            self.ctx,
            &self.a.expect,
            &self.a.tolerance,
            DEFAULT_PARAM_TOLERANCE,
        )
    }
}

/// A command of the private protocol (29-bit frames); `None` for another front end's.
fn private_command(args: &CommandArgs<'_, '_>) -> Res<Option<RsCommand>> {
    let a = args.a;
    Ok(Some(match args.name {
        "enable" => RsCommand::Enable,
        "disable" => RsCommand::Disable {
            clear: a.clear.as_ref().is_some_and(|c| c.value),
        },
        "mode" => RsCommand::Mode(args.word(&a.mode, "mode", &RUN_MODES)?),
        "op_control" => RsCommand::OpControl(args.op_control()?),
        "velocity" => RsCommand::Velocity {
            speed_rad_s: args.need(&a.speed_rad_s, "speed_rad_s")?,
            limit_cur_a: args.need(&a.limit_cur_a, "limit_cur_a")?,
            acc_rad_s2: args.need(&a.acc_rad_s2, "acc_rad_s2")?,
        },
        "profile" => RsCommand::Profile {
            target_rad: args.need(&a.target_rad, "target_rad")?,
            vel_max_rad_s: args.need(&a.vel_max_rad_s, "vel_max_rad_s")?,
            acc_rad_s2: args.need(&a.acc_rad_s2, "acc_rad_s2")?,
        },
        "current" => RsCommand::Current {
            iq_a: args.need(&a.iq_a, "iq_a")?,
        },
        "csp" => RsCommand::Csp {
            target_rad: args.need(&a.target_rad, "target_rad")?,
            limit_spd_rad_s: args.need(&a.limit_spd_rad_s, "limit_spd_rad_s")?,
        },
        "set_zero" => RsCommand::SetZero,
        "zero_here" => RsCommand::ZeroHere,
        "read_param" => RsCommand::ReadParam {
            param: args.param()?,
            expect: args.expectation()?,
        },
        "write_param" => RsCommand::WriteParam {
            param: args.param()?,
            value: args.ctx.finite(
                args.ctx.required(&a.value, "value", args.name, args.at)?,
                "value",
            )?,
        },
        "set_can_id" => RsCommand::SetCanId {
            new_id: can_id(
                args.ctx,
                args.ctx.required(&a.new_id, "new_id", args.name, args.at)?,
                "new_id",
            )?,
        },
        "save" => RsCommand::Save,
        "restart" => RsCommand::Restart,
        "active_report" => RsCommand::ActiveReport { on: args.on()? },
        "report_period" => RsCommand::ReportPeriod {
            period: args.need_ms(&a.period_ms, "period_ms")?,
        },
        "can_timeout" => RsCommand::CanTimeout {
            window: args.need_ms(&a.window_ms, "window_ms")?,
        },
        "poll" => RsCommand::Poll,
        "set_protocol" => RsCommand::SetProtocol(args.protocol()?),
        _ => return Ok(None),
    }))
}

/// A command of the MIT variant (11-bit frames); `None` for another front end's.
fn mit_command(args: &CommandArgs<'_, '_>) -> Res<Option<RsCommand>> {
    let a = args.a;
    Ok(Some(match args.name {
        "mit_enable" => RsCommand::MitEnable,
        "mit_stop" => RsCommand::MitStop,
        "mit_control" => RsCommand::MitControl(args.op_control()?),
        "mit_mode" => RsCommand::MitMode(args.word(&a.mode, "mode", &MIT_MODES)?),
        "mit_position" => RsCommand::MitPosition {
            target_rad: args.need(&a.target_rad, "target_rad")?,
            limit_spd_rad_s: args.need(&a.limit_spd_rad_s, "limit_spd_rad_s")?,
        },
        "mit_velocity" => RsCommand::MitVelocity {
            speed_rad_s: args.need(&a.speed_rad_s, "speed_rad_s")?,
            limit_cur_a: args.need(&a.limit_cur_a, "limit_cur_a")?,
        },
        "mit_zero" => RsCommand::MitZero,
        "mit_clear" => RsCommand::MitClear,
        "mit_read_param" => RsCommand::MitReadParam {
            param: args.param()?,
            expect: args.expectation()?,
        },
        "mit_set_protocol" => RsCommand::MitSetProtocol(args.protocol()?),
        "mit_active_report" => RsCommand::MitActiveReport { on: args.on()? },
        _ => return Ok(None),
    }))
}

/// A command to the emulator itself (faults, temperature, supply, load), not on the wire.
fn side_door_command(args: &CommandArgs<'_, '_>) -> Res<RsCommand> {
    let a = args.a;
    let fault_names: Vec<(Fault, &str)> = Fault::ALL.iter().map(|f| (*f, f.name())).collect();
    Ok(match args.name {
        "inject" => {
            let fault = args.word(&a.fault, "fault", &fault_names)?;
            if let (Some(value), Some(written)) = (fault.values().first(), &a.fault) {
                // A step has no place for a fault's values; the `faults:` list has.
                return Err(args.ctx.err(
                    crate::scenario::pos(written),
                    format!(
                        "`{}` takes `{}`: schedule it in `faults:` as `{}: {{motor: …, {}: …}}`",
                        fault.name(),
                        value.name,
                        fault.name(),
                        value.name
                    ),
                ));
            }
            RsCommand::Inject(fault)
        }
        "remove_cause" => RsCommand::RemoveCause(args.word(&a.fault, "fault", &fault_names)?),
        "set_temperature" => RsCommand::SetTemperature {
            temp_c: args.emulator(&a.temp_c, "temp_c", check_temperature_c)?,
        },
        "set_bus_voltage" => RsCommand::SetBusVoltage {
            voltage_v: args.emulator(&a.voltage_v, "voltage_v", check_bus_voltage_v)?,
        },
        // The motor's model is not known here: the largest model's bound catches the absurd
        // values; the emulator checks the motor's own bound when the step runs.
        _ => RsCommand::ExternalTorque {
            torque_nm: args.emulator(&a.torque_nm, "torque_nm", |t| {
                let strongest = Model::ALL
                    .into_iter()
                    .max_by(|a, b| {
                        max_external_torque_nm(*a).total_cmp(&max_external_torque_nm(*b))
                    })
                    .unwrap_or(Model::RS04);
                check_external_torque_nm(strongest, t)
            })?,
        },
    })
}
