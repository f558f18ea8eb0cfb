//! What each `robstride:` step does on the bench: private-protocol and MIT commands through the
//! driver, emulator commands through the in-process emulator, and the driver's errors as
//! scenario error classes.

use std::sync::Arc;
use std::time::Duration;

use driver::robstride::{Feedback, ParamValue, RobstrideError};
use sim::robstride::RobstrideHandle;

use super::{lock, RobstrideDevice};
use crate::devices::robstride::model::{RobstrideAction, RsCommand};
use crate::devices::robstride::observe::{f2, near_text};
use crate::devices::{within, DeviceError, Reply};
use crate::scenario::ErrorClass;

pub(super) fn classify(error: &RobstrideError) -> ErrorClass {
    match error {
        RobstrideError::Timeout { .. } => ErrorClass::Timeout,
        RobstrideError::Bus(_) | RobstrideError::Closed => ErrorClass::Bus,
        RobstrideError::ParamRefused { .. }
        | RobstrideError::ParamReadFailed { .. }
        | RobstrideError::EnableRefused { .. }
        | RobstrideError::MitEnableRefused { .. }
        | RobstrideError::ModeNotApplied { .. } => ErrorClass::Rejected,
        _ => ErrorClass::InvalidArgument,
    }
}

pub(super) fn derr(error: RobstrideError) -> DeviceError {
    DeviceError::new(classify(&error), error.to_string())
}

impl RobstrideDevice {
    /// An MIT-variant command; the reply carries the angle/speed of Response 1 when there is
    /// one and the value for `mit_read_param`.
    async fn mit_act(
        &self,
        id: u8,
        command: &RsCommand,
        reply: &mut Reply,
    ) -> Result<(), DeviceError> {
        let m = self.mit_motor(id)?;
        let status = match command {
            RsCommand::MitEnable => Some(m.enable().await.map_err(derr)?),
            RsCommand::MitStop => Some(m.stop().await.map_err(derr)?),
            RsCommand::MitControl(cmd) => Some(m.control(*cmd).await.map_err(derr)?),
            RsCommand::MitMode(mode) => Some(m.set_mode(*mode).await.map_err(derr)?),
            RsCommand::MitPosition {
                target_rad,
                limit_spd_rad_s,
            } => Some(
                m.set_position(*target_rad, *limit_spd_rad_s)
                    .await
                    .map_err(derr)?,
            ),
            RsCommand::MitVelocity {
                speed_rad_s,
                limit_cur_a,
            } => Some(
                m.set_velocity(*speed_rad_s, *limit_cur_a)
                    .await
                    .map_err(derr)?,
            ),
            RsCommand::MitZero => Some(m.set_zero().await.map_err(derr)?),
            RsCommand::MitClear => Some(m.clear_faults().await.map_err(derr)?),
            RsCommand::MitReadParam { param, expect } => {
                let raw = m.read_param(*param).await.map_err(derr)?;
                param_reply(reply, *param, raw, expect.as_ref());
                None
            }
            RsCommand::MitSetProtocol(protocol) => {
                m.switch_protocol(*protocol).await.map_err(derr)?;
                None
            }
            RsCommand::MitActiveReport { on } => {
                Some(m.set_active_reporting(*on).await.map_err(derr)?)
            }
            _ => None,
        };
        if let Some(s) = status {
            reply
                .values
                .push(("angle_rad".to_owned(), f2(f64::from(s.angle_rad))));
            reply
                .values
                .push(("speed_rad_s".to_owned(), f2(f64::from(s.speed_rad_s))));
        }
        lock(&self.mit_active).insert(id);
        Ok(())
    }

    pub(super) async fn emulator_do(
        &self,
        what: impl FnOnce(
            &RobstrideHandle,
        )
            -> futures::future::BoxFuture<'_, Result<(), sim::robstride::RobstrideError>>,
    ) -> Result<(), DeviceError> {
        let handle = self.emulator.running().await?;
        what(&handle)
            .await
            .map_err(|e| DeviceError::unsupported(format!("emulator: {e}")))
    }

    async fn restart(&self) -> Result<(), DeviceError> {
        self.emulator.power_cycle(async {}).await
    }

    pub(super) async fn act(
        &self,
        action: &RobstrideAction,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let late = || format!("{}: no reply", action.command.name());
        within(timeout, late, self.act_inner(action)).await
    }

    async fn act_inner(&self, action: &RobstrideAction) -> Result<Reply, DeviceError> {
        let id = action.motor;
        let mut reply = Reply::default();
        match &action.command {
            RsCommand::Restart => self.restart().await?,
            RsCommand::Inject(fault) => {
                let fault = *fault;
                self.emulator_do(|h| Box::pin(h.inject(id, fault))).await?;
            }
            RsCommand::RemoveCause(fault) => {
                let fault = *fault;
                self.emulator_do(|h| Box::pin(h.clear(id, fault))).await?;
            }
            RsCommand::SetTemperature { temp_c } => {
                let t = *temp_c;
                self.emulator_do(|h| Box::pin(h.set_temperature(id, t)))
                    .await?;
            }
            RsCommand::SetBusVoltage { voltage_v } => {
                let v = *voltage_v;
                self.emulator_do(|h| Box::pin(h.set_bus_voltage(id, v)))
                    .await?;
            }
            RsCommand::ExternalTorque { torque_nm } => {
                let t = *torque_nm;
                self.emulator_do(|h| Box::pin(h.set_external_torque(id, t)))
                    .await?;
            }
            RsCommand::SetCanId { new_id } => self.set_can_id(id, *new_id, &mut reply).await?,
            command if command.is_mit() => self.mit_act(id, command, &mut reply).await?,
            command => self.private_act(id, command, &mut reply).await?,
        }
        Ok(reply)
    }

    /// `set_can_id`: the driver's handle moves to the new ID (and the trace columns follow it).
    async fn set_can_id(&self, id: u8, new_id: u8, reply: &mut Reply) -> Result<(), DeviceError> {
        // An unknown ID gets the error that lists the known ones.
        drop(self.motor(id)?);
        let Some(arc) = lock(&self.motors).remove(&id) else {
            return Err(DeviceError::unsupported(format!(
                "no motor with CAN ID {id}"
            )));
        };
        let mut motor = match Arc::try_unwrap(arc) {
            Ok(m) => m,
            Err(arc) => {
                lock(&self.motors).insert(id, arc);
                return Err(DeviceError::unsupported(format!(
                    "motor {id} is busy; cannot change its CAN ID now"
                )));
            }
        };
        let result = motor.set_can_id(new_id).await;
        let now = motor.can_id();
        lock(&self.motors).insert(now, Arc::new(motor));
        for slot in lock(&self.ids).iter_mut().filter(|(_, c)| *c == id) {
            slot.1 = now;
        }
        let uid = result.map_err(derr)?;
        let hex: String = uid.iter().map(|b| format!("{b:02X}")).collect();
        reply.values.push(("can_id".to_owned(), now.to_string()));
        reply.values.push(("uid".to_owned(), hex));
        Ok(())
    }

    /// A private-protocol command through the motor's driver handle.
    async fn private_act(
        &self,
        id: u8,
        command: &RsCommand,
        reply: &mut Reply,
    ) -> Result<(), DeviceError> {
        let m = self.motor(id)?;
        // Any private command that gets here addresses the private protocol: the
        // private status is what conditions and traces read again.
        lock(&self.mit_active).remove(&id);
        match command {
            RsCommand::Enable => push_feedback(reply, &m.enable().await.map_err(derr)?),
            RsCommand::Disable { clear } => {
                push_feedback(reply, &m.disable(*clear).await.map_err(derr)?);
            }
            RsCommand::Mode(mode) => {
                push_feedback(reply, &m.switch_mode(*mode).await.map_err(derr)?);
            }
            RsCommand::OpControl(cmd) => {
                push_feedback(reply, &m.op_control(*cmd).await.map_err(derr)?);
            }
            RsCommand::Velocity {
                speed_rad_s,
                limit_cur_a,
                acc_rad_s2,
            } => {
                m.set_velocity(*speed_rad_s, *limit_cur_a, *acc_rad_s2)
                    .await
                    .map_err(derr)?;
            }
            RsCommand::Profile {
                target_rad,
                vel_max_rad_s,
                acc_rad_s2,
            } => {
                m.move_profile(*target_rad, *vel_max_rad_s, *acc_rad_s2)
                    .await
                    .map_err(derr)?;
            }
            RsCommand::Current { iq_a } => {
                m.set_current(*iq_a).await.map_err(derr)?;
            }
            RsCommand::Csp {
                target_rad,
                limit_spd_rad_s,
            } => {
                m.set_position(*target_rad, *limit_spd_rad_s)
                    .await
                    .map_err(derr)?;
            }
            RsCommand::SetZero => push_feedback(reply, &m.set_zero().await.map_err(derr)?),
            RsCommand::ZeroHere => push_feedback(reply, &m.zero_here().await.map_err(derr)?),
            RsCommand::ReadParam { param, expect } => {
                let raw = m.read_param(*param).await.map_err(derr)?;
                param_reply(reply, *param, raw, expect.as_ref());
            }
            RsCommand::SetProtocol(protocol) => {
                m.set_protocol(*protocol).await.map_err(derr)?;
            }
            RsCommand::WriteParam { param, value } => {
                m.write_param(*param, *value).await.map_err(derr)?;
            }
            RsCommand::Save => {
                m.save().await.map_err(derr)?;
            }
            RsCommand::ActiveReport { on } => {
                m.set_active_reporting(*on).await.map_err(derr)?;
            }
            RsCommand::ReportPeriod { period } => {
                m.set_report_period(*period).await.map_err(derr)?;
            }
            RsCommand::CanTimeout { window } => {
                m.set_can_timeout(*window).await.map_err(derr)?;
            }
            RsCommand::Poll => push_feedback(reply, &m.poll().await.map_err(derr)?),
            // Handled above.
            RsCommand::Restart
            | RsCommand::Inject(_)
            | RsCommand::RemoveCause(_)
            | RsCommand::SetTemperature { .. }
            | RsCommand::SetBusVoltage { .. }
            | RsCommand::ExternalTorque { .. }
            | RsCommand::SetCanId { .. }
            | RsCommand::MitEnable
            | RsCommand::MitStop
            | RsCommand::MitControl(_)
            | RsCommand::MitMode(_)
            | RsCommand::MitPosition { .. }
            | RsCommand::MitVelocity { .. }
            | RsCommand::MitZero
            | RsCommand::MitClear
            | RsCommand::MitReadParam { .. }
            | RsCommand::MitSetProtocol(_)
            | RsCommand::MitActiveReport { .. } => {}
        }
        Ok(())
    }
}

/// The angle and speed of a private status frame in a step's reply.
fn push_feedback(reply: &mut Reply, f: &Feedback) {
    reply
        .values
        .push(("angle_rad".to_owned(), f2(f64::from(f.angle_rad))));
    reply
        .values
        .push(("speed_rad_s".to_owned(), f2(f64::from(f.speed_rad_s))));
}

/// A read parameter in a step's reply, and a mismatch when it misses the expectation.
fn param_reply(
    reply: &mut Reply,
    param: driver::robstride::Param,
    raw: ParamValue,
    expect: Option<&crate::scenario::Near>,
) {
    let value = raw.as_f64();
    let name = param.name();
    // Integer parameters as integers, floats to the millesimal.
    let shown = match raw {
        ParamValue::F32(_) => format!("{value:.3}"),
        _ => format!("{value}"),
    };
    reply.values.push((name.to_owned(), shown.clone()));
    if let Some(e) = expect {
        if (value - e.value).abs() > e.tolerance + 1e-9 {
            reply
                .mismatches
                .push((name.to_owned(), near_text(e), shown));
        }
    }
}
