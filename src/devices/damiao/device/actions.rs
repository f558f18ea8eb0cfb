//! What each `damiao:` step does on the bench: motor commands through the driver, the host's
//! reads, emulator commands through the in-process emulator, and the driver's errors as
//! scenario error classes.

use std::time::Duration;

use driver::damiao::{DamiaoError, Feedback, Register, RegisterValue};

use super::{emulator_error, DamiaoDevice};
use crate::devices::contract::motor_bus::fixed;
use crate::devices::damiao::model::{state_name, DamiaoAction, DmCommand, MODES};
use crate::devices::damiao::observe::near_text;
use crate::devices::{within, DeviceError, Reply};
use crate::scenario::{ErrorClass, Near};

pub(super) fn classify(error: &DamiaoError) -> ErrorClass {
    match error {
        DamiaoError::Timeout { .. } => ErrorClass::Timeout,
        DamiaoError::Bus(_) | DamiaoError::Closed => ErrorClass::Bus,
        DamiaoError::Motor(_)
        | DamiaoError::EnableRefused { .. }
        | DamiaoError::ModeNotApplied { .. } => ErrorClass::Rejected,
        _ => ErrorClass::InvalidArgument,
    }
}

fn derr(error: DamiaoError) -> DeviceError {
    DeviceError::new(classify(&error), error.to_string())
}

impl DamiaoDevice {
    pub(super) async fn act(
        &self,
        action: &DamiaoAction,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let late = || format!("{}: no reply", action.command.name());
        within(timeout, late, self.act_inner(action)).await
    }

    async fn act_inner(&self, action: &DamiaoAction) -> Result<Reply, DeviceError> {
        let id = action.motor;
        let mut reply = Reply::default();
        match &action.command {
            DmCommand::Restart => self.restart().await?,
            DmCommand::SetTemperature { temp_c } => {
                self.motor(id)?;
                self.emulator
                    .running()
                    .await?
                    .set_temperature(id, *temp_c)
                    .await
                    .map_err(emulator_error)?;
            }
            DmCommand::ExternalTorque { torque_nm } => {
                self.motor(id)?;
                self.emulator
                    .running()
                    .await?
                    .set_external_torque(id, *torque_nm)
                    .await
                    .map_err(emulator_error)?;
            }
            DmCommand::Poll { period } => {
                self.motor(id)?;
                self.set_poll(id, *period);
            }
            command => self.motor_act(id, command, &mut reply).await?,
        }
        Ok(reply)
    }

    /// Power-cycle the emulator: its motors come back with what they saved (registers, zero),
    /// and the host opens fresh handles on them.
    async fn restart(&self) -> Result<(), DeviceError> {
        self.emulator.power_cycle(self.close_handles()).await?;
        self.open_handles().map_err(DeviceError::unsupported)
    }

    /// A command through the motor's driver handle.
    async fn motor_act(
        &self,
        id: u16,
        command: &DmCommand,
        reply: &mut Reply,
    ) -> Result<(), DeviceError> {
        let m = self.motor(id)?;
        let feedback = match command {
            DmCommand::Enable => Some(m.enable().await),
            DmCommand::Disable => Some(m.disable().await),
            DmCommand::Zero => Some(m.set_zero().await),
            DmCommand::ClearError => Some(m.clear_error().await),
            DmCommand::Refresh => Some(m.refresh().await),
            DmCommand::Mit {
                p_rad,
                v_rad_s,
                kp,
                kd,
                t_nm,
            } => Some(m.mit(*p_rad, *v_rad_s, *kp, *kd, *t_nm).await),
            DmCommand::PosVel { p_rad, v_rad_s } => Some(m.pos_vel(*p_rad, *v_rad_s).await),
            DmCommand::Vel { v_rad_s } => Some(m.velocity(*v_rad_s).await),
            DmCommand::ForcePos {
                p_rad,
                v_rad_s,
                i_limit,
            } => Some(m.force_position(*p_rad, *v_rad_s, *i_limit).await),
            DmCommand::Mode(mode) => {
                m.set_control_mode(*mode).await.map_err(derr)?;
                let name = MODES
                    .iter()
                    .find(|(m, _)| m == mode)
                    .map_or("?", |(_, n)| *n);
                reply.values.push(("mode".to_owned(), name.to_owned()));
                None
            }
            DmCommand::ReadRegister { register, expect } => {
                let value = m.read_register(*register).await.map_err(derr)?;
                register_reply(reply, *register, value, expect.as_ref());
                None
            }
            DmCommand::WriteRegister { register, value } => {
                let stored = m.write_register(*register, *value).await.map_err(derr)?;
                register_reply(reply, *register, stored, None);
                if stored != *value {
                    return Err(DeviceError::new(
                        ErrorClass::Rejected,
                        format!(
                            "motor {id} refused {} = {}: it keeps {}",
                            register.name(),
                            shown(*value),
                            shown(stored)
                        ),
                    ));
                }
                None
            }
            DmCommand::Save => {
                m.save().await.map_err(derr)?;
                None
            }
            // Handled by the caller.
            DmCommand::Poll { .. }
            | DmCommand::Restart
            | DmCommand::SetTemperature { .. }
            | DmCommand::ExternalTorque { .. } => None,
        };
        if let Some(result) = feedback {
            push_feedback(reply, &result.map_err(derr)?);
        }
        Ok(())
    }
}

/// A feedback frame in a step's reply: position, velocity, torque and state.
fn push_feedback(reply: &mut Reply, f: &Feedback) {
    let values = [
        ("position_rad", fixed(f64::from(f.position_rad), 3)),
        ("velocity_rad_s", fixed(f64::from(f.velocity_rad_s), 2)),
        ("torque_nm", fixed(f64::from(f.torque_nm), 2)),
        ("state", state_name(f.state).to_owned()),
    ];
    for (name, value) in values {
        reply.values.push((name.to_owned(), value));
    }
}

/// A register value as shown: integers whole, reals to the thousandth.
fn shown(value: RegisterValue) -> String {
    match value {
        RegisterValue::U32(v) => v.to_string(),
        RegisterValue::F32(v) => fixed(f64::from(v), 3),
    }
}

/// A register's value in a step's reply, and a mismatch when it misses the expectation.
fn register_reply(
    reply: &mut Reply,
    register: Register,
    value: RegisterValue,
    expect: Option<&Near>,
) {
    let name = register.name();
    let text = shown(value);
    reply.values.push((name.to_owned(), text.clone()));
    if let Some(e) = expect {
        if (value.as_f64() - e.value).abs() > e.tolerance + 1e-9 {
            reply.mismatches.push((name.to_owned(), near_text(e), text));
        }
    }
}
