//! A handle on one Damiao motor: the special commands, the four control modes' commands,
//! refresh and the registers. Every request waits for the reply the firmware gives
//! (docs/protocols/damiao.md §11) and returns it decoded, or a typed [`DamiaoError`].

use std::sync::{Arc, Mutex};
use std::time::Duration;

use bus::CanFrame;
use tokio::sync::{mpsc, watch};

use crate::damiao::codec::{
    self, op, special, ControlMode, Feedback, ForcePosCommand, MitCommand, MotorState, Reply,
    FORCE_POS_CURRENT_MAX, FORCE_POS_SPEED_MAX, KD_MAX, KP_MAX,
};
use crate::damiao::driver::Shared;
use crate::damiao::error::{DamiaoError, MotorError};
use crate::damiao::model::{Model, Ranges};
use crate::damiao::register::{Register, RegisterValue};

/// A handle on one motor, from [`crate::damiao::DamiaoDriver::motor`].
///
/// The handle remembers the control mode it last wrote or read (CTRL_MODE) and refuses a
/// command of another mode with [`DamiaoError::WrongMode`], since the motor would ignore it.
/// Until the mode is known every command is sent, and one the motor ignores ends in
/// [`DamiaoError::Timeout`].
pub struct DamiaoMotor {
    shared: Arc<Shared>,
    esc_id: u16,
    mst_id: u16,
    model: Model,
    ranges: Ranges,
    replies: tokio::sync::Mutex<mpsc::UnboundedReceiver<Reply>>,
    feedback: watch::Receiver<Option<Feedback>>,
    timeout: Duration,
    mode: Mutex<Option<ControlMode>>,
}

impl std::fmt::Debug for DamiaoMotor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DamiaoMotor")
            .field("bus", &self.shared.bus.name())
            .field("esc_id", &self.esc_id)
            .field("mst_id", &self.mst_id)
            .field("model", &self.model)
            .field("ranges", &self.ranges)
            .finish_non_exhaustive()
    }
}

impl Drop for DamiaoMotor {
    fn drop(&mut self) {
        self.shared.routes().remove(&self.mst_id);
    }
}

/// `value` must be finite and within `min..=max`.
fn check(field: &'static str, value: f32, min: f32, max: f32) -> Result<(), DamiaoError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(())
    } else {
        Err(DamiaoError::OutOfRange {
            field,
            value: f64::from(value),
            min: f64::from(min),
            max: f64::from(max),
        })
    }
}

impl DamiaoMotor {
    pub(crate) fn new(
        shared: Arc<Shared>,
        esc_id: u16,
        mst_id: u16,
        model: Model,
        ranges: Ranges,
        replies: mpsc::UnboundedReceiver<Reply>,
        feedback: watch::Receiver<Option<Feedback>>,
    ) -> Self {
        let timeout = shared.config.timeout;
        Self {
            shared,
            esc_id,
            mst_id,
            model,
            ranges,
            replies: tokio::sync::Mutex::new(replies),
            feedback,
            timeout,
            mode: Mutex::new(None),
        }
    }

    /// The command identifier (ESC_ID).
    pub fn esc_id(&self) -> u16 {
        self.esc_id
    }

    /// The feedback identifier (MST_ID) replies are routed on.
    pub fn mst_id(&self) -> u16 {
        self.mst_id
    }

    /// The motor's model.
    pub fn model(&self) -> Model {
        self.model
    }

    /// The MIT ranges this handle encodes and decodes with.
    pub fn ranges(&self) -> Ranges {
        self.ranges
    }

    /// How long requests wait for replies.
    pub fn timeout(&self) -> Duration {
        self.timeout
    }

    /// Change how long requests wait for replies.
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// The control mode last written to or read from CTRL_MODE through this handle, if any.
    pub fn control_mode(&self) -> Option<ControlMode> {
        *self
            .mode
            .lock()
            .unwrap_or_else(|poison| poison.into_inner())
    }

    /// The latest feedback frame of this motor, if any arrived.
    pub fn last_feedback(&self) -> Option<Feedback> {
        *self.feedback.borrow()
    }

    /// A receiver that sees every new feedback frame of this motor.
    pub fn subscribe_feedback(&self) -> watch::Receiver<Option<Feedback>> {
        self.feedback.clone()
    }

    fn note_mode(&self, value: RegisterValue) {
        let mode = match value {
            RegisterValue::U32(code) => ControlMode::from_code(code),
            RegisterValue::F32(_) => None,
        };
        *self
            .mode
            .lock()
            .unwrap_or_else(|poison| poison.into_inner()) = mode;
    }

    fn ensure_mode(&self, command: ControlMode) -> Result<(), DamiaoError> {
        match self.control_mode() {
            Some(mode) if mode != command => Err(DamiaoError::WrongMode {
                motor: self.esc_id,
                bus: self.shared.bus.name().to_owned(),
                mode,
                command,
            }),
            _ => Ok(()),
        }
    }

    /// Send `frame` and wait for the first reply `pick` accepts. Replies left over from
    /// earlier requests are dropped first, so a late answer never answers this request.
    async fn exchange<T>(
        &self,
        request: &'static str,
        frame: CanFrame,
        mut pick: impl FnMut(&Reply) -> Option<T>,
    ) -> Result<T, DamiaoError> {
        let mut replies = self.replies.lock().await;
        while replies.try_recv().is_ok() {}
        self.shared.bus.send(frame).await?;
        let wait = async {
            loop {
                match replies.recv().await {
                    Some(reply) => {
                        if let Some(result) = pick(&reply) {
                            return Ok(result);
                        }
                    }
                    None => return Err(DamiaoError::Closed),
                }
            }
        };
        tokio::time::timeout(self.timeout, wait)
            .await
            .map_err(|_| DamiaoError::Timeout {
                motor: self.esc_id,
                bus: self.shared.bus.name().to_owned(),
                request,
                after: self.timeout,
            })?
    }

    /// Send `frame`, wait for a feedback frame; an error state is a [`MotorError`].
    async fn feedback_request(
        &self,
        request: &'static str,
        frame: CanFrame,
    ) -> Result<Feedback, DamiaoError> {
        let feedback = self
            .exchange(request, frame, |reply| match reply {
                Reply::Feedback(feedback) => Some(*feedback),
                Reply::Register(_) => None,
            })
            .await?;
        if feedback.state.is_error() {
            return Err(MotorError {
                motor: self.esc_id,
                bus: self.shared.bus.name().to_owned(),
                state: feedback.state,
                feedback,
            }
            .into());
        }
        Ok(feedback)
    }

    /// Send `frame` (a register read or write) and wait for the reply with the same operation
    /// and RID; returns the value bytes.
    async fn register_request(
        &self,
        request: &'static str,
        frame: CanFrame,
        operation: u8,
        rid: u8,
    ) -> Result<[u8; 4], DamiaoError> {
        self.exchange(request, frame, |reply| match reply {
            Reply::Register(r) if r.op == operation && r.rid == rid => Some(r.value),
            _ => None,
        })
        .await
    }

    /// Enable (`FC`): the reply must report [`MotorState::Enabled`].
    pub async fn enable(&self) -> Result<Feedback, DamiaoError> {
        let frame = codec::special(self.esc_id, special::ENABLE)?;
        let feedback = self.feedback_request("enable", frame).await?;
        if feedback.state != MotorState::Enabled {
            return Err(DamiaoError::EnableRefused {
                motor: self.esc_id,
                bus: self.shared.bus.name().to_owned(),
                state: feedback.state,
            });
        }
        Ok(feedback)
    }

    /// Disable (`FD`).
    pub async fn disable(&self) -> Result<Feedback, DamiaoError> {
        let frame = codec::special(self.esc_id, special::DISABLE)?;
        self.feedback_request("disable", frame).await
    }

    /// Take the present position as zero (`FE`).
    pub async fn set_zero(&self) -> Result<Feedback, DamiaoError> {
        let frame = codec::special(self.esc_id, special::SET_ZERO)?;
        self.feedback_request("set zero", frame).await
    }

    /// Clear a latched error (`FB`). An error whose cause remains is reported again as a
    /// [`MotorError`].
    pub async fn clear_error(&self) -> Result<Feedback, DamiaoError> {
        let frame = codec::special(self.esc_id, special::CLEAR_ERROR)?;
        self.feedback_request("clear error", frame).await
    }

    /// An MIT command (the motor applies τ = kp·(p_des − p) + kd·(v_des − v) + t_ff) with position `p_des_rad` (±PMAX), velocity
    /// `v_des_rad_s` (±VMAX), gains `kp` (0..=500) and `kd` (0..=5) and feed-forward torque
    /// `t_ff_nm` (±TMAX). Values outside those ranges are refused, not clamped.
    pub async fn mit(
        &self,
        p_des_rad: f32,
        v_des_rad_s: f32,
        kp: f32,
        kd: f32,
        t_ff_nm: f32,
    ) -> Result<Feedback, DamiaoError> {
        let r = self.ranges;
        check("p_des_rad", p_des_rad, -r.pmax, r.pmax)?;
        check("v_des_rad_s", v_des_rad_s, -r.vmax, r.vmax)?;
        check("kp", kp, 0.0, KP_MAX)?;
        check("kd", kd, 0.0, KD_MAX)?;
        check("t_ff_nm", t_ff_nm, -r.tmax, r.tmax)?;
        self.ensure_mode(ControlMode::Mit)?;
        let cmd = MitCommand {
            p_des_rad,
            v_des_rad_s,
            kp,
            kd,
            t_ff_nm,
        };
        let frame = codec::mit(self.esc_id, &cmd, &r)?;
        self.feedback_request("MIT command", frame).await
    }

    /// A position-velocity command: move to `p_des_rad` no faster than `v_limit_rad_s` (≥ 0).
    pub async fn pos_vel(
        &self,
        p_des_rad: f32,
        v_limit_rad_s: f32,
    ) -> Result<Feedback, DamiaoError> {
        check("p_des_rad", p_des_rad, f32::MIN, f32::MAX)?;
        check("v_limit_rad_s", v_limit_rad_s, 0.0, f32::MAX)?;
        self.ensure_mode(ControlMode::PosVel)?;
        let frame = codec::pos_vel(self.esc_id, p_des_rad, v_limit_rad_s)?;
        self.feedback_request("position-velocity command", frame)
            .await
    }

    /// A velocity command (the frame's length is [`crate::damiao::DriverConfig::velocity_len`]).
    pub async fn velocity(&self, v_des_rad_s: f32) -> Result<Feedback, DamiaoError> {
        check("v_des_rad_s", v_des_rad_s, f32::MIN, f32::MAX)?;
        self.ensure_mode(ControlMode::Velocity)?;
        let len = self.shared.config.velocity_len;
        let frame = codec::velocity(self.esc_id, v_des_rad_s, len)?;
        self.feedback_request("velocity command", frame).await
    }

    /// A force-position command: move to `p_des_rad` no faster than `v_limit_rad_s`
    /// (0..=100) with at most `i_limit` (0..=1) of the board's maximum current.
    pub async fn force_position(
        &self,
        p_des_rad: f32,
        v_limit_rad_s: f32,
        i_limit: f32,
    ) -> Result<Feedback, DamiaoError> {
        check("p_des_rad", p_des_rad, f32::MIN, f32::MAX)?;
        check("v_limit_rad_s", v_limit_rad_s, 0.0, FORCE_POS_SPEED_MAX)?;
        check("i_limit", i_limit, 0.0, FORCE_POS_CURRENT_MAX)?;
        self.ensure_mode(ControlMode::ForcePos)?;
        let cmd = ForcePosCommand {
            p_des_rad,
            v_limit_rad_s,
            i_limit,
        };
        let frame = codec::force_position(self.esc_id, &cmd)?;
        self.feedback_request("force-position command", frame).await
    }

    /// Ask for a feedback frame (register operation 0xCC), in any mode.
    pub async fn refresh(&self) -> Result<Feedback, DamiaoError> {
        let frame = codec::refresh(self.esc_id)?;
        self.feedback_request("refresh", frame).await
    }

    /// Read a register.
    pub async fn read_register(&self, register: Register) -> Result<RegisterValue, DamiaoError> {
        let rid = register.rid();
        let frame = codec::read_register(self.esc_id, rid)?;
        let bytes = self
            .register_request("register read", frame, op::READ, rid)
            .await?;
        let value = RegisterValue::from_bytes(register.kind(), bytes);
        if register == Register::CtrlMode {
            self.note_mode(value);
        }
        Ok(value)
    }

    /// Write a register; returns the value the motor stored (its echo). Read-only registers,
    /// values of the wrong type and non-finite reals are refused without sending.
    pub async fn write_register(
        &self,
        register: Register,
        value: RegisterValue,
    ) -> Result<RegisterValue, DamiaoError> {
        if !register.writable() {
            return Err(DamiaoError::ReadOnlyRegister { register });
        }
        if value.kind() != register.kind() {
            return Err(DamiaoError::WrongValueType {
                register,
                expected: register.kind(),
            });
        }
        if let RegisterValue::F32(v) = value {
            check("register value", v, f32::MIN, f32::MAX)?;
        }
        let rid = register.rid();
        let frame = codec::write_register(self.esc_id, rid, value)?;
        let bytes = self
            .register_request("register write", frame, op::WRITE, rid)
            .await?;
        let stored = RegisterValue::from_bytes(register.kind(), bytes);
        if register == Register::CtrlMode {
            self.note_mode(stored);
        }
        Ok(stored)
    }

    /// Save every register to flash (best done while disabled). The firmware does not answer,
    /// so this returns once the frame is queued.
    pub async fn save(&self) -> Result<(), DamiaoError> {
        let frame = codec::save(self.esc_id)?;
        self.shared.bus.send(frame).await?;
        Ok(())
    }

    /// Switch the control mode: write CTRL_MODE, then read it back. A motor that keeps another
    /// mode is [`DamiaoError::ModeNotApplied`].
    pub async fn set_control_mode(&self, mode: ControlMode) -> Result<(), DamiaoError> {
        self.write_register(Register::CtrlMode, RegisterValue::U32(mode.code()))
            .await?;
        match self.read_register(Register::CtrlMode).await? {
            RegisterValue::U32(code) if code == mode.code() => Ok(()),
            other => Err(DamiaoError::ModeNotApplied {
                motor: self.esc_id,
                bus: self.shared.bus.name().to_owned(),
                wanted: mode,
                actual: other.as_f64() as u32,
            }),
        }
    }

    /// Set the CAN timeout (register TIMEOUT, 50 µs units; zero turns the watchdog off).
    /// Returns the timeout the motor stored.
    pub async fn set_can_timeout(&self, timeout: Duration) -> Result<Duration, DamiaoError> {
        let ticks = u32::try_from(timeout.as_micros() / 50).unwrap_or(u32::MAX);
        let stored = self
            .write_register(Register::Timeout, RegisterValue::U32(ticks))
            .await?;
        Ok(Duration::from_micros(stored.as_f64() as u64 * 50))
    }

    /// Read the MIT ranges the motor itself uses (PMAX, VMAX, TMAX), to compare with
    /// [`Self::ranges`].
    pub async fn read_ranges(&self) -> Result<Ranges, DamiaoError> {
        let pmax = self.read_register(Register::Pmax).await?.as_f64() as f32;
        let vmax = self.read_register(Register::Vmax).await?.as_f64() as f32;
        let tmax = self.read_register(Register::Tmax).await?.as_f64() as f32;
        Ok(Ranges::new(pmax, vmax, tmax))
    }
}
