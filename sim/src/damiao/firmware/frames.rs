//! The motor's answer to every frame it is addressed by: commands in the four modes, the
//! special commands, and register requests on 0x7FF.

use bus::CanFrame;

use super::{ControlMode, DamiaoMotor, MAX_ID};
use crate::damiao::codec::{
    self, MitCommand, PosForceCommand, PosVelCommand, RegisterCmd, RegisterRequest, Special,
    VelocityCommand, REGISTER_ID,
};
use crate::damiao::registers::{self, rid, RegValue, WriteOutcome};

/// Which of the motor's identifiers a frame came on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Addressed {
    /// ESC_ID or ESC_ID + 0x100/0x200/0x300: a command of that mode.
    Command(ControlMode),
    /// 0x7FF with the motor's ESC_ID in D0..D1.
    Register,
}

impl DamiaoMotor {
    /// React to a frame from the bus; returns what the motor sends in reply (at most one
    /// frame). Extended frames and frames for other motors get nothing.
    pub fn handle_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame> {
        if frame.is_extended() {
            return Vec::new();
        }
        let data = frame.data();
        let Some(addressed) = u16::try_from(frame.raw_id())
            .ok()
            .and_then(|id| self.addressed(id, data))
        else {
            return Vec::new();
        };
        // Every frame on the motor's identifiers reaches its receive handler, well formed or
        // not: each one feeds the CAN timeout.
        self.quiet_us = 0;
        let reply = match addressed {
            Addressed::Command(mode) => self.on_command(mode, data),
            Addressed::Register => self.on_register(data),
        };
        reply.into_iter().collect()
    }

    fn addressed(&self, id: u16, data: &[u8]) -> Option<Addressed> {
        let esc = self.esc_id();
        if id == REGISTER_ID {
            let target = data.get(..2).map(|d| u16::from_le_bytes([d[0], d[1]]));
            return (target == Some(esc)).then_some(Addressed::Register);
        }
        ControlMode::ALL
            .into_iter()
            .find(|mode| u32::from(esc) + u32::from(mode.id_offset()) == u32::from(id))
            .map(Addressed::Command)
    }

    /// A command on ESC_ID or a mode's identifier. Specials on ESC_ID work in every mode; a
    /// setpoint for a mode other than CTRL_MODE, or too short for its layout, is ignored
    /// without a reply.
    fn on_command(&mut self, mode: ControlMode, data: &[u8]) -> Option<CanFrame> {
        if mode == ControlMode::Mit {
            if let Some(special) = Special::parse(data) {
                self.on_special(special);
                return self.feedback();
            }
        }
        if mode != self.control_mode() {
            return None;
        }
        match mode {
            ControlMode::Mit => {
                let payload: [u8; 8] = data.try_into().ok()?;
                self.targets.mit = MitCommand::unpack(&payload, &self.registers.ranges());
            }
            ControlMode::PosVel => {
                let command = PosVelCommand::parse(data)?;
                // A NaN or infinite field leaves the setpoint as it was (still answered).
                if command.p_des_rad.is_finite() && command.v_des_rad_s.is_finite() {
                    self.targets.position_rad = f64::from(command.p_des_rad);
                    self.targets.speed_limit_rad_s = f64::from(command.v_des_rad_s).abs();
                }
            }
            ControlMode::Velocity => {
                let command = VelocityCommand::parse(data)?;
                if command.v_des_rad_s.is_finite() {
                    self.targets.velocity_rad_s = f64::from(command.v_des_rad_s);
                }
            }
            ControlMode::PosForce => {
                let command = PosForceCommand::parse(data)?;
                if command.p_des_rad.is_finite() {
                    self.targets.position_rad = f64::from(command.p_des_rad);
                    self.targets.speed_limit_rad_s = command.v_des_rad_s;
                    self.targets.current_fraction = command.current_fraction;
                }
            }
        }
        self.feedback()
    }

    fn on_special(&mut self, special: Special) {
        match special {
            Special::Enable => {
                // Refused while an error is latched: the reply shows the error instead.
                if self.latched.is_empty() && !self.enabled {
                    self.enabled = true;
                    self.hold();
                }
            }
            Special::Disable => {
                self.enabled = false;
                self.torque_nm = 0.0;
                self.hold();
            }
            Special::SetZero => {
                // Taken only while disabled (clients zero a limp joint); ignored, still
                // answered, while enabled so a running loop never sees its position jump.
                if !self.enabled {
                    self.zero_offset_rad = self.plant.position_rad();
                    self.flash.zero_offset_rad = self.zero_offset_rad;
                    self.persist_requested = true;
                    self.hold();
                }
            }
            Special::ClearError => self.clear_errors(),
        }
    }

    /// A request on 0x7FF for this motor.
    fn on_register(&mut self, data: &[u8]) -> Option<CanFrame> {
        let request = RegisterRequest::parse(data)?;
        match request.cmd {
            RegisterCmd::Read => {
                let rid = request.rid?;
                let value = self.read_register(rid)?;
                self.register_reply(RegisterCmd::Read, rid, value, self.esc_id(), self.mst_id())
            }
            RegisterCmd::Write => {
                let (rid, bytes) = (request.rid?, request.value?);
                // The echo goes out on the ids the host addressed, even when the write moves
                // them: the host is waiting there.
                let (esc, mst) = (self.esc_id(), self.mst_id());
                let mode_before = self.control_mode();
                let value = match self.registers.write(rid, bytes) {
                    WriteOutcome::Unknown => return None,
                    WriteOutcome::Refused(held) => held,
                    WriteOutcome::Stored(value) => {
                        if rid == rid::CTRL_MODE && self.control_mode() != mode_before {
                            // The new mode starts from where the joint is.
                            self.hold();
                        }
                        value
                    }
                };
                self.register_reply(RegisterCmd::Write, rid, value, esc, mst)
            }
            RegisterCmd::Save => {
                // Meant for the disabled state (note §6.1): ignored while enabled. No reply
                // either way: none is documented, and damiao-motor would read one as feedback.
                if !self.enabled {
                    self.flash.registers = self.registers.saved();
                    self.persist_requested = true;
                }
                None
            }
            RegisterCmd::Refresh => self.feedback(),
        }
    }

    /// A register's value as a read answers it: live registers from the present state.
    fn read_register(&self, rid: u8) -> Option<RegValue> {
        registers::spec(rid)?;
        let live = |x: f64| Some(RegValue::F32(x as f32));
        match rid {
            rid::VBUS => live(self.causes.bus_voltage_v),
            rid::TPCB => live(self.causes.mos_temp_c),
            rid::TMTR => live(self.causes.coil_temp_c),
            rid::P_M => live(self.angle_rad() * self.spec.gear_ratio),
            rid::XOUT => live(self.angle_rad()),
            _ => self.registers.get(rid),
        }
    }

    fn register_reply(
        &self,
        cmd: RegisterCmd,
        rid: u8,
        value: RegValue,
        esc: u16,
        mst: u16,
    ) -> Option<CanFrame> {
        let data = codec::register_payload(esc, cmd.byte(), rid, value.to_le_bytes());
        codec::standard_frame(mst & MAX_ID, &data)
    }
}
