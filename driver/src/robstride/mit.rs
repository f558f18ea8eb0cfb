//! A handle on one motor speaking the MIT protocol variant (protocol note §12): enable, stop,
//! the MIT setpoint, position and velocity modes, zero, faults, parameters, IDs, save and the
//! switch back (command 8). Every request waits for its documented reply with a timeout and
//! returns a typed [`RobstrideError`].
//!
//! ```no_run
//! # async fn demo(bus: std::sync::Arc<dyn bus::CanBus>) -> Result<(), driver::robstride::RobstrideError> {
//! use driver::robstride::{DriverConfig, MitMode, Model, RobstrideDriver};
//! let driver = RobstrideDriver::new(bus, DriverConfig::default());
//! let motor = driver.mit_motor(1, Model::RS03)?;
//! motor.set_mode(MitMode::Position).await?;
//! motor.enable().await?;
//! motor.set_position(1.0, 2.0).await?;
//! # Ok(()) }
//! ```

use std::sync::Arc;
use std::time::Duration;

use bus::CanFrame;
use tokio::sync::{mpsc, watch, Mutex};

use crate::robstride::codec::{MotorMode, OpControl};
use crate::robstride::driver::{MitRoute, Shared};
use crate::robstride::error::RobstrideError;
use crate::robstride::mit_codec::{self, kind, marker, MitIncoming, MitStatus, NO_ARG};
use crate::robstride::model::{Model, Ranges};
use crate::robstride::motor::Protocol;
use crate::robstride::params::{Param, ParamType, ParamValue};

/// Run modes of the MIT variant (command 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MitMode {
    /// 0: MIT setpoints (command 3), the default.
    Mit,
    /// 1: position mode with CSP semantics (command 10).
    Position,
    /// 2: velocity mode (command 11).
    Velocity,
}

impl MitMode {
    /// F_CMD of command 6.
    pub fn code(self) -> u8 {
        match self {
            Self::Mit => 0,
            Self::Position => 1,
            Self::Velocity => 2,
        }
    }

    /// The private run_mode (0x7005) the firmware uses for it: 0, 5 (CSP) or 2.
    pub fn run_mode(self) -> u8 {
        match self {
            Self::Mit => 0,
            Self::Position => 5,
            Self::Velocity => 2,
        }
    }
}

/// A handle on one motor in the MIT variant, from [`crate::robstride::RobstrideDriver::mit_motor`].
pub struct MitMotor {
    shared: Arc<Shared>,
    can_id: u8,
    model: Model,
    ranges: Ranges,
    replies: Mutex<mpsc::UnboundedReceiver<MitIncoming>>,
    status: watch::Receiver<Option<MitStatus>>,
    timeout: Duration,
}

impl std::fmt::Debug for MitMotor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MitMotor")
            .field("can_id", &self.can_id)
            .field("model", &self.model)
            .finish_non_exhaustive()
    }
}

impl Drop for MitMotor {
    fn drop(&mut self) {
        self.shared.mit_routes().remove(&self.can_id);
    }
}

type Channels = (
    mpsc::UnboundedReceiver<MitIncoming>,
    watch::Receiver<Option<MitStatus>>,
);

fn add_route(shared: &Shared, can_id: u8, ranges: Ranges) -> Result<Channels, RobstrideError> {
    if !(1..=0x7F).contains(&can_id) {
        return Err(RobstrideError::InvalidCanId { id: can_id });
    }
    let mut routes = shared.mit_routes();
    if routes.contains_key(&can_id) {
        return Err(RobstrideError::MotorInUse { motor: can_id });
    }
    let (replies, replies_rx) = mpsc::unbounded_channel();
    let (status, status_rx) = watch::channel(None);
    routes.insert(
        can_id,
        MitRoute {
            replies,
            status,
            ranges,
        },
    );
    Ok((replies_rx, status_rx))
}

fn check(field: &'static str, value: f32, min: f32, max: f32) -> Result<(), RobstrideError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(())
    } else {
        Err(RobstrideError::OutOfRange {
            field,
            value: f64::from(value),
            min: f64::from(min),
            max: f64::from(max),
        })
    }
}

impl MitMotor {
    pub(crate) fn register(
        shared: Arc<Shared>,
        can_id: u8,
        model: Model,
        ranges: Ranges,
    ) -> Result<Self, RobstrideError> {
        let (replies, status) = add_route(&shared, can_id, ranges)?;
        let timeout = shared.config.timeout;
        Ok(Self {
            shared,
            can_id,
            model,
            ranges,
            replies: Mutex::new(replies),
            status,
            timeout,
        })
    }

    /// The motor's CAN ID.
    pub fn can_id(&self) -> u8 {
        self.can_id
    }

    /// The motor's model.
    pub fn model(&self) -> Model {
        self.model
    }

    /// Change how long requests wait for replies.
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// The latest Response 1 (reply or active report), if any arrived.
    pub fn last_status(&self) -> Option<MitStatus> {
        *self.status.borrow()
    }

    /// A receiver that sees every new Response 1 of this motor.
    pub fn subscribe_status(&self) -> watch::Receiver<Option<MitStatus>> {
        self.status.clone()
    }

    async fn exchange<T>(
        &self,
        request: &'static str,
        frame: CanFrame,
        mut pick: impl FnMut(&MitIncoming) -> Option<T>,
    ) -> Result<T, RobstrideError> {
        let mut replies = self.replies.lock().await;
        // A late reply to an earlier request must not answer this one.
        while replies.try_recv().is_ok() {}
        self.shared.bus.send(frame).await?;
        let wait = async {
            loop {
                match replies.recv().await {
                    Some(incoming) => {
                        if let Some(result) = pick(&incoming) {
                            return Ok(result);
                        }
                    }
                    None => return Err(RobstrideError::Closed),
                }
            }
        };
        tokio::time::timeout(self.timeout, wait)
            .await
            .map_err(|_| RobstrideError::Timeout {
                motor: self.can_id,
                request,
                after: self.timeout,
            })?
    }

    async fn status_request(
        &self,
        request: &'static str,
        frame: CanFrame,
    ) -> Result<MitStatus, RobstrideError> {
        self.exchange(request, frame, |incoming| match incoming {
            MitIncoming::Status(status) => Some(*status),
            _ => None,
        })
        .await
    }

    async fn uid_request(
        &self,
        request: &'static str,
        frame: CanFrame,
        from: u8,
    ) -> Result<[u8; 8], RobstrideError> {
        self.exchange(request, frame, |incoming| match incoming {
            MitIncoming::Uid { motor_id, uid } if *motor_id == from => Some(*uid),
            _ => None,
        })
        .await
    }

    async fn command(
        &self,
        request: &'static str,
        f_cmd: u8,
        mark: u8,
    ) -> Result<MitStatus, RobstrideError> {
        let frame = mit_codec::command(self.can_id, f_cmd, mark)?;
        self.status_request(request, frame).await
    }

    /// Enable (command 1): the motor must report run mode.
    pub async fn enable(&self) -> Result<MitStatus, RobstrideError> {
        let status = self
            .command("MIT enable", NO_ARG, marker::ENABLE_OR_MODE)
            .await?;
        if status.mode != MotorMode::Run {
            return Err(RobstrideError::MitEnableRefused {
                motor: self.can_id,
                fault: status.fault,
            });
        }
        Ok(status)
    }

    /// Stop (command 2).
    pub async fn stop(&self) -> Result<MitStatus, RobstrideError> {
        self.command("MIT stop", NO_ARG, marker::STOP_OR_PROTOCOL)
            .await
    }

    /// MIT setpoint (command 3); values outside the model's ranges are refused.
    pub async fn control(&self, cmd: OpControl) -> Result<MitStatus, RobstrideError> {
        let r = self.ranges;
        check("angle_rad", cmd.angle_rad, -r.angle_rad, r.angle_rad)?;
        check(
            "speed_rad_s",
            cmd.speed_rad_s,
            -r.speed_rad_s,
            r.speed_rad_s,
        )?;
        check("kp", cmd.kp, 0.0, r.kp_max)?;
        check("kd", cmd.kd, 0.0, r.kd_max)?;
        check("torque_nm", cmd.torque_nm, -r.torque_nm, r.torque_nm)?;
        let frame = mit_codec::setpoint(self.can_id, &cmd, &r)?;
        self.status_request("MIT setpoint", frame).await
    }

    /// Set the mechanical zero here (command 4; the motor ignores it in position mode).
    pub async fn set_zero(&self) -> Result<MitStatus, RobstrideError> {
        self.command("MIT set zero", NO_ARG, marker::ZERO).await
    }

    /// Clear latched faults whose cause is gone (command 5, F_CMD 0xFF).
    pub async fn clear_faults(&self) -> Result<MitStatus, RobstrideError> {
        self.command("MIT clear fault", NO_ARG, marker::FAULT).await
    }

    /// The latched fault word (command 5 with F_CMD 0; bits as the private type 21).
    pub async fn fault_word(&self) -> Result<u32, RobstrideError> {
        let frame = mit_codec::command(self.can_id, 0, marker::FAULT)?;
        let motor = self.can_id;
        self.exchange("MIT fault query", frame, |incoming| match incoming {
            MitIncoming::FaultWord { motor_id, word } if *motor_id == motor => Some(*word),
            _ => None,
        })
        .await
    }

    /// Set the run mode (command 6; the motor accepts it only while stopped), then read
    /// run_mode back (command 14) to check it took.
    pub async fn set_mode(&self, mode: MitMode) -> Result<MitStatus, RobstrideError> {
        let status = self
            .command("MIT set mode", mode.code(), marker::ENABLE_OR_MODE)
            .await?;
        let actual = self.read_param(Param::RunMode).await?.as_f64() as u8;
        if actual != mode.run_mode() {
            return Err(RobstrideError::ModeNotApplied {
                motor: self.can_id,
                wanted: mode.run_mode(),
                actual,
            });
        }
        Ok(status)
    }

    /// Position-mode setpoint (command 10): target angle (rad) and speed limit (rad/s).
    pub async fn set_position(
        &self,
        angle_rad: f32,
        speed_rad_s: f32,
    ) -> Result<MitStatus, RobstrideError> {
        check("angle_rad", angle_rad, -1.0e6, 1.0e6)?;
        check("speed_rad_s", speed_rad_s, 0.0, self.ranges.speed_rad_s)?;
        let frame = mit_codec::f32_pair(kind::POSITION, self.can_id, angle_rad, speed_rad_s)?;
        self.status_request("MIT position setpoint", frame).await
    }

    /// Velocity-mode setpoint (command 11): speed (rad/s) and current limit (A).
    pub async fn set_velocity(
        &self,
        speed_rad_s: f32,
        current_limit_a: f32,
    ) -> Result<MitStatus, RobstrideError> {
        let r = self.ranges;
        check("speed_rad_s", speed_rad_s, -r.speed_rad_s, r.speed_rad_s)?;
        check("current_limit_a", current_limit_a, 0.0, r.current_a)?;
        let frame = mit_codec::f32_pair(kind::VELOCITY, self.can_id, speed_rad_s, current_limit_a)?;
        self.status_request("MIT velocity setpoint", frame).await
    }

    /// Active reporting of Response 1 frames on or off (command 13).
    pub async fn set_active_reporting(&self, on: bool) -> Result<MitStatus, RobstrideError> {
        self.command("MIT active report", u8::from(on), marker::REPORT)
            .await
    }

    /// Read a parameter (command 14). The variant has no failure reply: an index the motor
    /// does not serve goes unanswered and reads as [`RobstrideError::ParamReadFailed`].
    pub async fn read_param(&self, param: Param) -> Result<ParamValue, RobstrideError> {
        let (index, ty) = param.index_and_type();
        self.read_raw(index, ty).await
    }

    /// Read any index (0x70xx, 0x20xx, 0x30xx) with a given wire type (command 14).
    pub async fn read_raw(&self, index: u16, ty: ParamType) -> Result<ParamValue, RobstrideError> {
        let frame = mit_codec::read_param(self.can_id, index)?;
        let refused = RobstrideError::ParamReadFailed {
            motor: self.can_id,
            index,
        };
        self.param_exchange("MIT read parameter", frame, false, index, ty, refused)
            .await
    }

    /// Write a parameter (command 15); returns the value the motor stored (after its
    /// clamping). A refused write (read-only or unknown index) goes unanswered and is
    /// [`RobstrideError::ParamRefused`].
    pub async fn write_param(
        &self,
        param: Param,
        value: ParamValue,
    ) -> Result<ParamValue, RobstrideError> {
        let (index, ty) = param.index_and_type();
        if value.ty() != ty {
            return Err(RobstrideError::OutOfRange {
                field: "parameter value type",
                value: value.as_f64(),
                min: 0.0,
                max: 0.0,
            });
        }
        self.write_raw(index, value).await
    }

    /// Write any index with a typed value (command 15).
    pub async fn write_raw(
        &self,
        index: u16,
        value: ParamValue,
    ) -> Result<ParamValue, RobstrideError> {
        if let ParamValue::F32(v) = value {
            check("parameter value", v, f32::MIN, f32::MAX)?;
        }
        let frame = mit_codec::write_param(self.can_id, index, value)?;
        let refused = RobstrideError::ParamRefused {
            motor: self.can_id,
            index,
        };
        self.param_exchange(
            "MIT write parameter",
            frame,
            true,
            index,
            value.ty(),
            refused,
        )
        .await
    }

    /// Send a command 14/15 `frame` and wait for its reply (same direction `write`, index
    /// echoed), the value read as `ty`. The variant has no failure frame: a motor refuses by
    /// not answering, so a timeout is the `refused` error.
    async fn param_exchange(
        &self,
        what: &'static str,
        frame: CanFrame,
        write: bool,
        index: u16,
        ty: ParamType,
        refused: RobstrideError,
    ) -> Result<ParamValue, RobstrideError> {
        let answer = self
            .exchange(what, frame, |incoming| match incoming {
                MitIncoming::Param {
                    write: answered_write,
                    index: echo,
                    value,
                    ..
                } if *answered_write == write && *echo == index => {
                    Some(ParamValue::from_bytes(ty, *value))
                }
                _ => None,
            })
            .await;
        match answer {
            Err(RobstrideError::Timeout { .. }) => Err(refused),
            other => other,
        }
    }

    /// Save the parameters (command 12); returns the MCU UID (Response 2).
    pub async fn save(&self) -> Result<[u8; 8], RobstrideError> {
        let frame = mit_codec::command(self.can_id, NO_ARG, marker::SAVE)?;
        self.uid_request("MIT save", frame, self.can_id).await
    }

    /// Set the host ID replies go to (command 9); returns the MCU UID. Only a host ID equal
    /// to this driver's keeps the handle's replies flowing. Host IDs 0..=0x7F are refused:
    /// Response 1 to such an identifier would look like another motor's Response 2.
    pub async fn set_host_id(&self, host: u8) -> Result<[u8; 8], RobstrideError> {
        if host <= 0x7F {
            return Err(RobstrideError::OutOfRange {
                field: "host_id",
                value: f64::from(host),
                min: 128.0,
                max: 255.0,
            });
        }
        let frame = mit_codec::command(self.can_id, host, marker::HOST_ID)?;
        self.uid_request("MIT set host ID", frame, self.can_id)
            .await
    }

    /// Switch the protocol for the next power-on (command 8); returns the MCU UID.
    pub async fn switch_protocol(&self, protocol: Protocol) -> Result<[u8; 8], RobstrideError> {
        let code = match protocol {
            Protocol::Private => 0,
            Protocol::CanOpen => 1,
            Protocol::Mit => 2,
        };
        let frame = mit_codec::command(self.can_id, code, marker::STOP_OR_PROTOCOL)?;
        self.uid_request("MIT protocol switch", frame, self.can_id)
            .await
    }

    /// Change the CAN ID (command 7; refused by the motor while enabled). The handle follows
    /// the motor to its new ID; returns the MCU UID from the new ID.
    pub async fn set_can_id(&mut self, new_id: u8) -> Result<[u8; 8], RobstrideError> {
        let (mut new_replies, new_status) = add_route(&self.shared, new_id, self.ranges)?;
        let frame = mit_codec::command(self.can_id, new_id, marker::CAN_ID)?;
        if let Err(error) = self.shared.bus.send(frame).await {
            self.shared.mit_routes().remove(&new_id);
            return Err(error.into());
        }
        let answer = tokio::time::timeout(self.timeout, async {
            loop {
                match new_replies.recv().await {
                    Some(MitIncoming::Uid { uid, .. }) => return Some(uid),
                    Some(_) => continue,
                    None => return None,
                }
            }
        })
        .await
        .ok()
        .flatten();
        let Some(uid) = answer else {
            self.shared.mit_routes().remove(&new_id);
            return Err(RobstrideError::Timeout {
                motor: self.can_id,
                request: "MIT set CAN ID",
                after: self.timeout,
            });
        };
        self.shared.mit_routes().remove(&self.can_id);
        self.can_id = new_id;
        self.replies = Mutex::new(new_replies);
        self.status = new_status;
        Ok(uid)
    }
}
