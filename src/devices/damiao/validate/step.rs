//! The `damiao:` step: which arguments each command takes, and each command typed.

use driver::damiao::{Register, RegisterKind, RegisterValue};
use sim::damiao::faults::TEMPERATURE_MAX_C;
use sim::damiao::EXTERNAL_TORQUE_PEAK_MULTIPLE;

use super::{esc_id, on_device};
use crate::devices::contract::motor_bus::{expectation, wire_f32};
use crate::devices::damiao::model::{DamiaoAction, DmCommand, MODES};
use crate::devices::damiao::raw::{RawDmStep, RawStep};
use crate::scenario::error::{suggestion, Pos};
use crate::scenario::{pos, Ctx, DeviceStep, Near, Res, S};

/// Default tolerance of `read_register` expectations.
const DEFAULT_REGISTER_TOLERANCE: f64 = 0.01;
/// Coldest temperature the emulator's side door sets (°C).
const TEMPERATURE_MIN_C: f64 = -40.0;

/// Each command: its name after `do:`, its label in reports and the argument keys it takes
/// (`motor` aside).
pub(in crate::devices::damiao) const COMMANDS: [(&str, &str, &[&str]); 17] = [
    ("enable", "damiao enable", &[]),
    ("disable", "damiao disable", &[]),
    ("zero", "damiao zero", &[]),
    ("clear_error", "damiao clear_error", &[]),
    (
        "mit",
        "damiao mit",
        &["p_rad", "v_rad_s", "kp", "kd", "t_nm"],
    ),
    ("pos_vel", "damiao pos_vel", &["p_rad", "v_rad_s"]),
    ("vel", "damiao vel", &["v_rad_s"]),
    (
        "force_pos",
        "damiao force_pos",
        &["p_rad", "v_rad_s", "i_limit"],
    ),
    ("mode", "damiao mode", &["mode"]),
    (
        "read_register",
        "damiao read_register",
        &["register", "expect", "tolerance"],
    ),
    (
        "write_register",
        "damiao write_register",
        &["register", "value"],
    ),
    ("save", "damiao save", &[]),
    ("refresh", "damiao refresh", &[]),
    ("poll", "damiao poll", &["period_ms"]),
    ("restart", "damiao restart", &[]),
    ("set_temperature", "damiao set_temperature", &["temp_c"]),
    ("external_torque", "damiao external_torque", &["torque_nm"]),
];

/// The argument keys present in a step, with their positions.
fn present_keys(a: &RawDmStep) -> Vec<(&'static str, Pos)> {
    let mut out = Vec::new();
    macro_rules! keys {
        ($($field:ident => $name:literal),* $(,)?) => {
            $(if let Some(v) = &a.$field { out.push(($name, pos(v))); })*
        };
    }
    keys!(
        p_rad => "p_rad", v_rad_s => "v_rad_s", kp => "kp", kd => "kd", t_nm => "t_nm",
        i_limit => "i_limit", mode => "mode", register => "register", value => "value",
        expect => "expect", tolerance => "tolerance", period_ms => "period_ms",
        temp_c => "temp_c", torque_nm => "torque_nm",
    );
    out
}

/// A Damiao step.
pub(crate) fn step(
    ctx: &Ctx<'_>,
    raw: &RawStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<DamiaoAction>)> {
    match raw {
        RawStep::Damiao(a) => damiao_step(ctx, a, at),
    }
}

/// A `damiao:` step.
fn damiao_step(
    ctx: &Ctx<'_>,
    a: &RawDmStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<DamiaoAction>)> {
    let names: Vec<&str> = COMMANDS.iter().map(|(n, _, _)| *n).collect();
    let Some(cmd) = &a.command else {
        return Err(ctx.err(
            at,
            format!("`damiao` needs `do:` with one of: {}", names.join(", ")),
        ));
    };
    let Some((name, label, allowed)) = COMMANDS.iter().find(|(n, _, _)| *n == cmd.value) else {
        return Err(ctx.err(
            pos(cmd),
            format!(
                "`do`: unknown value `{}`; expected one of: {}{}",
                cmd.value,
                names.join(", "),
                suggestion(&cmd.value, &names)
            ),
        ));
    };
    ctx.only_arguments(
        &present_keys(a),
        allowed,
        name,
        "no arguments besides `motor`",
    )?;
    let device = ctx.device_of_kind(&a.device, at, "damiao", "this step")?;
    let motor = match (*name, &a.motor) {
        ("restart", Some(m)) => {
            return Err(ctx.err(
                pos(m),
                "`do: restart` power-cycles the whole bus; it takes no `motor`",
            ))
        }
        ("restart", None) => None,
        (_, m) => {
            let m = ctx.required(m, "motor", name, at)?;
            let id = esc_id(ctx, m, "motor")?;
            let index = on_device(ctx, device, id, pos(m))?;
            Some((id, index))
        }
    };
    let args = CommandArgs {
        ctx,
        a,
        name,
        at,
        device,
        motor: motor.map(|(_, index)| index),
    };
    let command = args.command()?;
    Ok((
        label,
        DeviceStep {
            device,
            action: DamiaoAction {
                motor: motor.map_or(0, |(id, _)| id),
                command,
            },
            timeout: ctx.timeout(&a.timeout_ms)?,
            expect_error: ctx.expect_error(&a.expect_error)?,
        },
    ))
}

/// One command's arguments as written, read with the command's name in every message.
struct CommandArgs<'c, 'a> {
    ctx: &'c Ctx<'a>,
    a: &'c RawDmStep,
    /// The command (`do:`).
    name: &'static str,
    /// The step.
    at: Pos,
    /// The device it is for.
    device: usize,
    /// The motor's place in the device's `motors:` (none for `restart`).
    motor: Option<usize>,
}

impl CommandArgs<'_, '_> {
    /// A required number, as the wire's f32.
    fn need(&self, v: &Option<S<f64>>, key: &str) -> Res<f32> {
        let v = self.ctx.required(v, key, self.name, self.at)?;
        wire_f32(self.ctx, v, key)
    }

    /// An optional number, 0 when left out.
    fn opt(&self, v: &Option<S<f64>>, key: &str) -> Res<f32> {
        v.as_ref().map_or(Ok(0.0), |v| wire_f32(self.ctx, v, key))
    }

    /// A required number within `min..=max`.
    fn within(&self, v: &Option<S<f64>>, key: &str, (min, max): (f64, f64)) -> Res<f64> {
        let v = self.ctx.required(v, key, self.name, self.at)?;
        let x = self.ctx.finite(v, key)?;
        if (min..=max).contains(&x) {
            Ok(x)
        } else {
            Err(self.ctx.err(
                pos(v),
                format!("`{key}` must be between {min} and {max}, got {x:?}"),
            ))
        }
    }

    /// The required `register:`: a register of the driver's table, by its firmware name in
    /// any case.
    fn register(&self) -> Res<(Register, &S<String>)> {
        let v = self
            .ctx
            .required(&self.a.register, "register", self.name, self.at)?;
        let found = Register::ALL
            .iter()
            .copied()
            .find(|r| r.name().eq_ignore_ascii_case(v.value.trim()));
        let register = found.ok_or_else(|| {
            let names: Vec<&str> = Register::ALL.iter().map(|r| r.name()).collect();
            self.ctx.err(
                pos(v),
                format!(
                    "`register`: unknown register `{}`; expected one of: {}{}",
                    v.value,
                    names.join(", "),
                    suggestion(&v.value, &names)
                ),
            )
        })?;
        Ok((register, v))
    }

    /// `expect:` (and `tolerance:`) of a register read.
    fn expectation(&self) -> Res<Option<Near>> {
        expectation(
            self.ctx,
            &self.a.expect,
            &self.a.tolerance,
            DEFAULT_REGISTER_TOLERANCE,
        )
    }

    /// `write_register`'s register and value, in the register's wire type.
    fn write(&self) -> Res<DmCommand> {
        let (register, written) = self.register()?;
        if !register.writable() {
            return Err(self
                .ctx
                .err(pos(written), format!("`register`: {register} is read-only")));
        }
        if matches!(register, Register::EscId | Register::MstId) {
            return Err(self.ctx.err(
                pos(written),
                format!(
                    "`register`: {register} moves the motor to another identifier, which the damiao step does not follow (its motors keep the ids of the bench)"
                ),
            ));
        }
        let v = self
            .ctx
            .required(&self.a.value, "value", self.name, self.at)?;
        let value = match register.kind() {
            RegisterKind::U32 => {
                let x = self.ctx.finite(v, "value")?;
                if x.fract() != 0.0 || !(0.0..=f64::from(u32::MAX)).contains(&x) {
                    return Err(self.ctx.err(
                        pos(v),
                        format!(
                            "`value`: {} holds a whole number 0..={}, got {x}",
                            register.name(),
                            u32::MAX
                        ),
                    ));
                }
                // Whole and within u32: the cast is exact.
                RegisterValue::U32(x as u32)
            }
            RegisterKind::F32 => RegisterValue::F32(wire_f32(self.ctx, v, "value")?),
        };
        Ok(DmCommand::WriteRegister { register, value })
    }

    /// The largest external push on this step's motor: ten times its model's peak torque.
    fn max_push_nm(&self) -> f64 {
        let peak = self
            .motor
            .and_then(|m| self.ctx.part_actuator(self.device, m))
            .map_or(0.0, |model| model.peak_torque_nm);
        EXTERNAL_TORQUE_PEAK_MULTIPLE * peak
    }

    /// The command.
    fn command(&self) -> Res<DmCommand> {
        let a = self.a;
        Ok(match self.name {
            "enable" => DmCommand::Enable,
            "disable" => DmCommand::Disable,
            "zero" => DmCommand::Zero,
            "clear_error" => DmCommand::ClearError,
            "mit" => DmCommand::Mit {
                p_rad: self.opt(&a.p_rad, "p_rad")?,
                v_rad_s: self.opt(&a.v_rad_s, "v_rad_s")?,
                kp: self.opt(&a.kp, "kp")?,
                kd: self.opt(&a.kd, "kd")?,
                t_nm: self.opt(&a.t_nm, "t_nm")?,
            },
            "pos_vel" => DmCommand::PosVel {
                p_rad: self.need(&a.p_rad, "p_rad")?,
                v_rad_s: self.need(&a.v_rad_s, "v_rad_s")?,
            },
            "vel" => DmCommand::Vel {
                v_rad_s: self.need(&a.v_rad_s, "v_rad_s")?,
            },
            "force_pos" => DmCommand::ForcePos {
                p_rad: self.need(&a.p_rad, "p_rad")?,
                v_rad_s: self.need(&a.v_rad_s, "v_rad_s")?,
                i_limit: self.need(&a.i_limit, "i_limit")?,
            },
            "mode" => {
                let v = self.ctx.required(&a.mode, "mode", self.name, self.at)?;
                DmCommand::Mode(self.ctx.choice(v, "mode", &MODES)?)
            }
            "read_register" => DmCommand::ReadRegister {
                register: self.register()?.0,
                expect: self.expectation()?,
            },
            "write_register" => self.write()?,
            "save" => DmCommand::Save,
            "refresh" => DmCommand::Refresh,
            "poll" => {
                let v = self
                    .ctx
                    .required(&a.period_ms, "period_ms", self.name, self.at)?;
                DmCommand::Poll {
                    period: self.ctx.millis(v, "period_ms")?,
                }
            }
            "restart" => DmCommand::Restart,
            "set_temperature" => DmCommand::SetTemperature {
                temp_c: self.within(&a.temp_c, "temp_c", (TEMPERATURE_MIN_C, TEMPERATURE_MAX_C))?,
            },
            _ => {
                let max = self.max_push_nm();
                DmCommand::ExternalTorque {
                    torque_nm: self.within(&a.torque_nm, "torque_nm", (-max, max))?,
                }
            }
        })
    }
}
