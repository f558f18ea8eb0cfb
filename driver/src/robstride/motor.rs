//! A handle on one motor: every request of the private protocol, each with a timeout and a
//! typed error, and the mode sequences of the manual (spec §8).

use std::sync::Arc;
use std::time::Duration;

use bus::CanFrame;
use tokio::sync::{mpsc, watch, Mutex};

use crate::robstride::codec::{self, comm, FaultReport, Feedback, Incoming, MotorMode, OpControl};
use crate::robstride::driver::{Route, Shared};
use crate::robstride::error::RobstrideError;
use crate::robstride::model::{Model, Ranges};
use crate::robstride::params::{Param, ParamType, ParamValue};

/// Run modes (parameter 0x7005).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunMode {
    /// 0: operation control (type-1 frames).
    OperationControl,
    /// 1: profile position (vel_max, acc_set, loc_ref).
    ProfilePosition,
    /// 2: velocity (limit_cur, acc_rad, spd_ref).
    Velocity,
    /// 3: current (iq_ref).
    Current,
    /// 4: return to the mechanical zero.
    ZeroReturn,
    /// 5: cyclic synchronous position (limit_spd, loc_ref).
    CyclicPosition,
}

impl RunMode {
    /// The parameter value.
    pub fn code(self) -> u8 {
        match self {
            Self::OperationControl => 0,
            Self::ProfilePosition => 1,
            Self::Velocity => 2,
            Self::Current => 3,
            Self::ZeroReturn => 4,
            Self::CyclicPosition => 5,
        }
    }
}

/// Bit rates of the baud command (type 23).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Baud {
    /// 1 Mbit/s.
    M1,
    /// 500 kbit/s.
    K500,
    /// 250 kbit/s.
    K250,
    /// 125 kbit/s.
    K125,
}

/// Protocols of the switch command (type 25).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Protocol {
    /// Private 29-bit protocol.
    Private,
    /// CANopen.
    CanOpen,
    /// MIT 11-bit protocol.
    Mit,
}

/// A handle on one motor of a [`crate::robstride::RobstrideDriver`].
pub struct Motor {
    shared: Arc<Shared>,
    can_id: u8,
    model: Model,
    ranges: Ranges,
    replies: Mutex<mpsc::UnboundedReceiver<Incoming>>,
    feedback: watch::Receiver<Option<Feedback>>,
    faults: watch::Receiver<Option<FaultReport>>,
    timeout: Duration,
}

impl std::fmt::Debug for Motor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Motor")
            .field("can_id", &self.can_id)
            .field("model", &self.model)
            .finish_non_exhaustive()
    }
}

impl Drop for Motor {
    fn drop(&mut self) {
        self.shared.routes().remove(&self.can_id);
    }
}

type Channels = (
    mpsc::UnboundedReceiver<Incoming>,
    watch::Receiver<Option<Feedback>>,
    watch::Receiver<Option<FaultReport>>,
);

fn add_route(shared: &Shared, can_id: u8, ranges: Ranges) -> Result<Channels, RobstrideError> {
    if !(1..=0x7F).contains(&can_id) {
        return Err(RobstrideError::InvalidCanId { id: can_id });
    }
    let mut routes = shared.routes();
    if routes.contains_key(&can_id) {
        return Err(RobstrideError::MotorInUse { motor: can_id });
    }
    let (replies, replies_rx) = mpsc::unbounded_channel();
    let (feedback, feedback_rx) = watch::channel(None);
    let (faults, faults_rx) = watch::channel(None);
    routes.insert(
        can_id,
        Route {
            replies,
            feedback,
            faults,
            ranges,
        },
    );
    Ok((replies_rx, feedback_rx, faults_rx))
}

impl Motor {
    pub(crate) fn register(
        shared: Arc<Shared>,
        can_id: u8,
        model: Model,
        ranges: Ranges,
    ) -> Result<Self, RobstrideError> {
        let (replies, feedback, faults) = add_route(&shared, can_id, ranges)?;
        let timeout = shared.config.timeout;
        Ok(Self {
            shared,
            can_id,
            model,
            ranges,
            replies: Mutex::new(replies),
            feedback,
            faults,
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

    /// The scaling ranges in use.
    pub fn ranges(&self) -> &Ranges {
        &self.ranges
    }

    /// Change how long requests wait for replies.
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// The latest status (reply or active report), if any arrived.
    pub fn last_feedback(&self) -> Option<Feedback> {
        *self.feedback.borrow()
    }

    /// A receiver that sees every new status of this motor.
    pub fn subscribe_feedback(&self) -> watch::Receiver<Option<Feedback>> {
        self.feedback.clone()
    }

    /// The latest type-21 fault frame, if any arrived.
    pub fn last_fault_report(&self) -> Option<FaultReport> {
        *self.faults.borrow()
    }

    fn host(&self) -> u16 {
        u16::from(self.shared.config.host_id)
    }

    /// Send `frame` and wait for the first reply `pick` accepts.
    async fn exchange<T>(
        &self,
        request: &'static str,
        frame: CanFrame,
        mut pick: impl FnMut(&Incoming) -> Option<Result<T, RobstrideError>>,
    ) -> Result<T, RobstrideError> {
        let mut replies = self.replies.lock().await;
        // Replies that arrived late for an earlier request would answer this one.
        while replies.try_recv().is_ok() {}
        self.shared.bus.send(frame).await?;
        let wait = async {
            loop {
                match replies.recv().await {
                    Some(incoming) => {
                        if let Some(result) = pick(&incoming) {
                            return result;
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
    ) -> Result<Feedback, RobstrideError> {
        self.exchange(request, frame, |incoming| match incoming {
            Incoming::Feedback(feedback) => Some(Ok(*feedback)),
            _ => None,
        })
        .await
    }

    /// Ping (type 0): the motor's MCU UID.
    pub async fn device_id(&self) -> Result<[u8; 8], RobstrideError> {
        let frame = codec::request(comm::GET_ID, self.host(), self.can_id, [0; 8])?;
        self.exchange("get device ID", frame, |incoming| match incoming {
            Incoming::DeviceId { uid, .. } => Some(Ok(*uid)),
            _ => None,
        })
        .await
    }

    /// Enable (type 3): the motor must report run mode.
    pub async fn enable(&self) -> Result<Feedback, RobstrideError> {
        let frame = codec::request(comm::ENABLE, self.host(), self.can_id, [0; 8])?;
        let feedback = self.status_request("enable", frame).await?;
        if feedback.mode != MotorMode::Run {
            return Err(RobstrideError::EnableRefused {
                motor: self.can_id,
                faults: feedback.faults,
            });
        }
        Ok(feedback)
    }

    /// Stop (type 4); with `clear_faults` the motor also clears latched faults.
    pub async fn disable(&self, clear_faults: bool) -> Result<Feedback, RobstrideError> {
        let data = [u8::from(clear_faults), 0, 0, 0, 0, 0, 0, 0];
        let frame = codec::request(comm::STOP, self.host(), self.can_id, data)?;
        self.status_request("stop", frame).await
    }

    /// Firmware version (type 4 `00 C4`; note the motor also stops).
    pub async fn firmware_version(&self) -> Result<[u8; 4], RobstrideError> {
        let data = [0, 0xC4, 0, 0, 0, 0, 0, 0];
        let frame = codec::request(comm::STOP, self.host(), self.can_id, data)?;
        self.exchange("version read", frame, |incoming| match incoming {
            Incoming::Version { version, .. } => Some(Ok(*version)),
            _ => None,
        })
        .await
    }

    /// Poll status with a host type-2 frame (undocumented, answered by K-Scale's firmware).
    pub async fn poll(&self) -> Result<Feedback, RobstrideError> {
        let frame = codec::request(comm::STATUS, self.host(), self.can_id, [0; 8])?;
        self.status_request("status poll", frame).await
    }

    /// Operation-control command (type 1); values outside the model's ranges are refused.
    pub async fn op_control(&self, cmd: OpControl) -> Result<Feedback, RobstrideError> {
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
        let frame = codec::op_control_frame(self.can_id, &cmd, &r)?;
        self.status_request("operation control", frame).await
    }

    /// Set the mechanical zero at the current position (type 6).
    pub async fn set_zero(&self) -> Result<Feedback, RobstrideError> {
        let frame = codec::request(
            comm::SET_ZERO,
            self.host(),
            self.can_id,
            [1, 0, 0, 0, 0, 0, 0, 0],
        )?;
        self.status_request("set zero", frame).await
    }

    /// The manual's zeroing sequence: stop, set zero, enable again.
    pub async fn zero_here(&self) -> Result<Feedback, RobstrideError> {
        self.disable(false).await?;
        self.set_zero().await?;
        self.enable().await
    }

    /// Change the CAN ID (type 7; refused by the motor while enabled, so disable first). The
    /// handle follows the motor to its new ID.
    pub async fn set_can_id(&mut self, new_id: u8) -> Result<[u8; 8], RobstrideError> {
        let (new_replies, new_feedback, new_faults) = add_route(&self.shared, new_id, self.ranges)?;
        let mut new_replies = new_replies;
        let data2 = (u16::from(new_id) << 8) | self.host();
        let frame = codec::request(comm::SET_CAN_ID, data2, self.can_id, [0; 8])?;
        let sent = self.shared.bus.send(frame).await;
        let answer = match sent {
            Ok(()) => tokio::time::timeout(self.timeout, async {
                loop {
                    match new_replies.recv().await {
                        Some(Incoming::DeviceId { uid, .. }) => return Some(uid),
                        Some(_) => continue,
                        None => return None,
                    }
                }
            })
            .await
            .ok()
            .flatten(),
            Err(error) => {
                self.shared.routes().remove(&new_id);
                return Err(error.into());
            }
        };
        let Some(uid) = answer else {
            self.shared.routes().remove(&new_id);
            return Err(RobstrideError::Timeout {
                motor: self.can_id,
                request: "set CAN ID",
                after: self.timeout,
            });
        };
        self.shared.routes().remove(&self.can_id);
        self.can_id = new_id;
        self.replies = Mutex::new(new_replies);
        self.feedback = new_feedback;
        self.faults = new_faults;
        Ok(uid)
    }

    /// Read a parameter (type 17).
    pub async fn read_param(&self, param: Param) -> Result<ParamValue, RobstrideError> {
        let (index, ty) = param.index_and_type();
        self.read_raw(index, ty).await
    }

    /// Read any index with a given wire type (type 17).
    pub async fn read_raw(&self, index: u16, ty: ParamType) -> Result<ParamValue, RobstrideError> {
        let [lo, hi] = index.to_le_bytes();
        let frame = codec::request(
            comm::READ_PARAM,
            self.host(),
            self.can_id,
            [lo, hi, 0, 0, 0, 0, 0, 0],
        )?;
        let motor = self.can_id;
        self.exchange("read parameter", frame, |incoming| match incoming {
            Incoming::Param {
                ok: true,
                index: echo,
                value,
                ..
            } if *echo == index => Some(Ok(ParamValue::from_bytes(ty, *value))),
            // Failure replies carry a zero payload (no index echo) on hardware.
            Incoming::Param { ok: false, .. } => {
                Some(Err(RobstrideError::ParamReadFailed { motor, index }))
            }
            _ => None,
        })
        .await
    }

    /// A float parameter as f32 (any wire type converted).
    pub async fn read_f32(&self, param: Param) -> Result<f32, RobstrideError> {
        Ok(self.read_param(param).await?.as_f64() as f32)
    }

    /// Write a parameter (type 18, volatile until [`Motor::save`]). The value is converted to
    /// the parameter's wire type.
    pub async fn write_param(&self, param: Param, value: f64) -> Result<Feedback, RobstrideError> {
        let (index, ty) = param.index_and_type();
        let typed = match ty {
            ParamType::U8 => ParamValue::U8(int_in_range(param, value, 255.0)? as u8),
            ParamType::U16 => ParamValue::U16(int_in_range(param, value, 65535.0)? as u16),
            ParamType::U32 => {
                ParamValue::U32(int_in_range(param, value, f64::from(u32::MAX))? as u32)
            }
            ParamType::F32 => {
                if !value.is_finite() {
                    return Err(RobstrideError::OutOfRange {
                        field: "parameter value",
                        value,
                        min: f64::from(f32::MIN),
                        max: f64::from(f32::MAX),
                    });
                }
                ParamValue::F32(value as f32)
            }
        };
        self.write_raw(index, typed).await
    }

    /// Write any index with a typed value (type 18).
    pub async fn write_raw(
        &self,
        index: u16,
        value: ParamValue,
    ) -> Result<Feedback, RobstrideError> {
        let [lo, hi] = index.to_le_bytes();
        let v = value.to_bytes();
        let frame = codec::request(
            comm::WRITE_PARAM,
            self.host(),
            self.can_id,
            [lo, hi, 0, 0, v[0], v[1], v[2], v[3]],
        )?;
        let motor = self.can_id;
        self.exchange("write parameter", frame, |incoming| match incoming {
            Incoming::Feedback(feedback) => Some(Ok(*feedback)),
            Incoming::Param { ok: false, .. } => {
                Some(Err(RobstrideError::ParamRefused { motor, index }))
            }
            _ => None,
        })
        .await
    }

    /// Switch run mode the way the manual says: stop, write run_mode, read it back, enable.
    pub async fn switch_mode(&self, mode: RunMode) -> Result<Feedback, RobstrideError> {
        self.disable(false).await?;
        self.write_param(Param::RunMode, f64::from(mode.code()))
            .await?;
        let actual = self.read_param(Param::RunMode).await?.as_f64() as u8;
        if actual != mode.code() {
            return Err(RobstrideError::ModeNotApplied {
                motor: self.can_id,
                wanted: mode.code(),
                actual,
            });
        }
        self.enable().await
    }

    /// Velocity mode setpoint: limit_cur, acc_rad, then spd_ref (run mode must be Velocity).
    pub async fn set_velocity(
        &self,
        speed_rad_s: f32,
        limit_cur_a: f32,
        acc_rad_s2: f32,
    ) -> Result<Feedback, RobstrideError> {
        let r = self.ranges;
        check("speed_rad_s", speed_rad_s, -r.speed_rad_s, r.speed_rad_s)?;
        check("limit_cur_a", limit_cur_a, 0.0, r.current_a)?;
        check("acc_rad_s2", acc_rad_s2, 0.0, f32::MAX)?;
        self.write_param(Param::LimitCur, f64::from(limit_cur_a))
            .await?;
        self.write_param(Param::AccRad, f64::from(acc_rad_s2))
            .await?;
        self.write_param(Param::SpdRef, f64::from(speed_rad_s))
            .await
    }

    /// PP move: vel_max, acc_set, then loc_ref (run mode must be ProfilePosition).
    pub async fn move_profile(
        &self,
        target_rad: f32,
        vel_max_rad_s: f32,
        acc_rad_s2: f32,
    ) -> Result<Feedback, RobstrideError> {
        let r = self.ranges;
        check("vel_max_rad_s", vel_max_rad_s, 0.0, r.speed_rad_s)?;
        check("acc_rad_s2", acc_rad_s2, 0.0, f32::MAX)?;
        check("target_rad", target_rad, f32::MIN, f32::MAX)?;
        self.write_param(Param::VelMax, f64::from(vel_max_rad_s))
            .await?;
        self.write_param(Param::AccSet, f64::from(acc_rad_s2))
            .await?;
        self.write_param(Param::LocRef, f64::from(target_rad)).await
    }

    /// Current mode setpoint iq_ref (run mode must be Current).
    pub async fn set_current(&self, iq_a: f32) -> Result<Feedback, RobstrideError> {
        let limit = self.ranges.current_a;
        check("iq_a", iq_a, -limit, limit)?;
        self.write_param(Param::IqRef, f64::from(iq_a)).await
    }

    /// CSP setpoint: limit_spd, then loc_ref (run mode must be CyclicPosition).
    pub async fn set_position(
        &self,
        target_rad: f32,
        limit_spd_rad_s: f32,
    ) -> Result<Feedback, RobstrideError> {
        check(
            "limit_spd_rad_s",
            limit_spd_rad_s,
            0.0,
            self.ranges.speed_rad_s,
        )?;
        check("target_rad", target_rad, f32::MIN, f32::MAX)?;
        self.write_param(Param::LimitSpd, f64::from(limit_spd_rad_s))
            .await?;
        self.write_param(Param::LocRef, f64::from(target_rad)).await
    }

    /// The load-side multi-turn angle at start-up (mechPos, 0x7019).
    pub async fn read_initial_position(&self) -> Result<f32, RobstrideError> {
        self.read_f32(Param::MechPos).await
    }

    /// Save parameters (type 22).
    pub async fn save(&self) -> Result<Feedback, RobstrideError> {
        let frame = codec::request(
            comm::SAVE,
            self.host(),
            self.can_id,
            [1, 2, 3, 4, 5, 6, 7, 8],
        )?;
        self.status_request("save", frame).await
    }

    /// Active reporting on/off (type 24); the motor does not answer, reports follow.
    pub async fn set_active_reporting(&self, on: bool) -> Result<(), RobstrideError> {
        let frame = codec::request(
            comm::ACTIVE_REPORT,
            self.host(),
            self.can_id,
            codec::magic_payload(u8::from(on)),
        )?;
        Ok(self.shared.bus.send(frame).await?)
    }

    /// Active-report period (EPScan_time): 10 ms, +5 ms per step above 1.
    pub async fn set_report_period(&self, period: Duration) -> Result<Feedback, RobstrideError> {
        let ms = period.as_millis().max(10) as f64;
        let steps = ((ms - 10.0) / 5.0).round() + 1.0;
        self.write_param(Param::EpscanTime, steps).await
    }

    /// Baud rate for the next power cycle (type 23, answered with type 0).
    pub async fn set_baud(&self, baud: Baud) -> Result<[u8; 8], RobstrideError> {
        let code = match baud {
            Baud::M1 => 1,
            Baud::K500 => 2,
            Baud::K250 => 3,
            Baud::K125 => 4,
        };
        self.type0_request("set baud", comm::BAUD, code).await
    }

    /// Protocol for the next power cycle (type 25, answered with type 0).
    pub async fn set_protocol(&self, protocol: Protocol) -> Result<[u8; 8], RobstrideError> {
        let code = match protocol {
            Protocol::Private => 0,
            Protocol::CanOpen => 1,
            Protocol::Mit => 2,
        };
        self.type0_request("set protocol", comm::PROTOCOL, code)
            .await
    }

    async fn type0_request(
        &self,
        request: &'static str,
        comm_type: u8,
        code: u8,
    ) -> Result<[u8; 8], RobstrideError> {
        let frame = codec::request(
            comm_type,
            self.host(),
            self.can_id,
            codec::magic_payload(code),
        )?;
        self.exchange(request, frame, |incoming| match incoming {
            Incoming::DeviceId { uid, .. } => Some(Ok(*uid)),
            _ => None,
        })
        .await
    }

    /// CAN watchdog (canTimeout): the motor resets if no command arrives within `window`;
    /// `Duration::ZERO` disables it.
    pub async fn set_can_timeout(&self, window: Duration) -> Result<Feedback, RobstrideError> {
        let ticks = window.as_secs_f64() * f64::from(self.shared.config.can_timeout_ticks_per_s);
        self.write_param(Param::CanTimeout, ticks.round()).await
    }
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

fn int_in_range(param: Param, value: f64, max: f64) -> Result<f64, RobstrideError> {
    let rounded = value.round();
    if value.is_finite() && rounded >= 0.0 && rounded <= max {
        Ok(rounded)
    } else {
        let field = match param {
            Param::RunMode => "run_mode",
            Param::EpscanTime => "EPScan_time",
            Param::CanTimeout => "canTimeout",
            _ => "parameter value",
        };
        Err(RobstrideError::OutOfRange {
            field,
            value,
            min: 0.0,
            max,
        })
    }
}
