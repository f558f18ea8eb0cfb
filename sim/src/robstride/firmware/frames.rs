//! Frame handling: the private protocol's reply to every communication type (the MIT and
//! CANopen variants are handed to `mit` and `canopen`).

use bus::CanFrame;

use super::{
    baud_code_bps, can_id_accepted, canopen, host_id_accepted, mit, protocol_accepted, Actuator,
    ModeState, TYPE0_DST,
};
use crate::robstride::codec::{self, CommType, ExtId};
use crate::robstride::control::{OpCommand, Profile, SpeedLoop};
use crate::robstride::faults::{self, Fault};
use crate::robstride::host_params;
use crate::robstride::params::{self, index, Access};

impl Actuator {
    /// React to a frame from the bus; returns the frames the motor sends in reply.
    pub fn handle_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame> {
        let mut out = Vec::new();
        if self.listening && self.protocol == canopen::PROTOCOL_CANOPEN {
            return self.handle_canopen_frame(frame);
        }
        if self.listening && self.protocol == mit::PROTOCOL_MIT {
            return self.handle_mit_frame(frame);
        }
        if !self.listening || !frame.is_extended() {
            return out;
        }
        let id = ExtId::parse(frame.raw_id());
        if id.dst != self.can_id {
            return out;
        }
        let data = codec::payload8(frame);
        self.since_command_s = 0.0;
        let host = id.low_data2();
        match id.comm {
            CommType::GetId => {
                self.note_host(host);
                out.extend(self.type0_reply());
            }
            CommType::OpControl => {
                self.op = self.decode_op(id.data2, &data);
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::Status => {
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::Enable => {
                self.note_host(host);
                self.enable();
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::Stop => {
                self.note_host(host);
                self.stop();
                if data[0] == 0 && data[1] == 0xC4 {
                    out.extend(self.version_reply());
                } else {
                    if data[0] == 1 {
                        self.clear_faults();
                    }
                    out.extend(self.status_frame(CommType::Status));
                }
            }
            CommType::Calibrate => {
                self.note_host(host);
                if self.mode != ModeState::Run {
                    self.mode = ModeState::Calibration;
                    self.calibration_left_ms = 1000;
                }
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::SetZero => {
                self.note_host(host);
                if data[0] == 1 {
                    self.set_zero();
                }
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::SetCanId => {
                self.note_host(host);
                let new_id = id.high_data2();
                // Refused while enabled (no reply), as hosts report; 0 and >127 are invalid.
                if self.mode != ModeState::Run && can_id_accepted(new_id) {
                    tracing::info!(old = self.can_id, new = new_id, "robstride: CAN ID changed");
                    self.can_id = new_id;
                    self.persist_requested = true;
                    out.extend(self.type0_reply());
                }
            }
            CommType::ReadParam => {
                self.note_host(host);
                out.extend(self.read_param(u16::from_le_bytes([data[0], data[1]])));
            }
            CommType::WriteParam => {
                self.note_host(host);
                let value = [data[4], data[5], data[6], data[7]];
                out.extend(self.write_param(u16::from_le_bytes([data[0], data[1]]), value));
            }
            CommType::Save => {
                self.note_host(host);
                if data == [1, 2, 3, 4, 5, 6, 7, 8] {
                    self.saved_params = self.params.saved_values();
                    self.persist_requested = true;
                    out.extend(self.status_frame(CommType::Status));
                }
            }
            CommType::Baud => {
                self.note_host(host);
                if codec::has_magic_prefix(&data) && baud_code_bps(data[6]).is_some() {
                    self.pending_baud = data[6];
                    self.persist_requested = true;
                    out.extend(self.type0_reply());
                }
            }
            CommType::ActiveReport => {
                self.note_host(host);
                if codec::has_magic_prefix(&data) && data[6] <= 1 {
                    self.active_report = data[6] == 1;
                    self.report_elapsed_ms = 0;
                }
            }
            CommType::Protocol => {
                self.note_host(host);
                if codec::has_magic_prefix(&data) && protocol_accepted(data[6]) {
                    self.pending_protocol = data[6];
                    self.persist_requested = true;
                    out.extend(self.type0_reply());
                }
            }
            CommType::Fault | CommType::Unknown(_) => {}
        }
        out
    }

    fn note_host(&mut self, host: u8) {
        // Host ID 0 would make replies unaddressable; keep the last real one.
        if host_id_accepted(host) && host != self.can_id {
            self.master_id = host;
        }
    }

    fn decode_op(&self, data2: u16, data: &[u8; 8]) -> OpCommand {
        let r = &self.ranges;
        let f = |raw: u16, min: f32, max: f32| f64::from(codec::u16_to_float(raw, min, max));
        OpCommand {
            angle_rad: f(codec::be_u16(data, 0), -r.angle_rad, r.angle_rad),
            speed_rad_s: f(codec::be_u16(data, 2), -r.speed_rad_s, r.speed_rad_s),
            kp: f(codec::be_u16(data, 4), 0.0, r.kp_max),
            kd: f(codec::be_u16(data, 6), 0.0, r.kd_max),
            torque_nm: f(data2, -r.torque_nm, r.torque_nm),
        }
    }

    pub(super) fn enable(&mut self) {
        if self.fault_word != 0 || self.encoder_uncalibrated || self.mode == ModeState::Calibration
        {
            tracing::debug!(
                motor = self.can_id,
                faults = self.fault_word,
                "robstride: enable refused"
            );
            return;
        }
        if self.mode == ModeState::Run {
            return;
        }
        self.mode = ModeState::Run;
        self.reset_loops();
        // Hold where we are: position targets start at the current angle so enabling never
        // makes the joint jump toward a stale target.
        let angle = self.angle_rad();
        self.params.set(index::LOC_REF, angle);
        self.profile = Profile::at_rest(angle);
    }

    pub(super) fn stop(&mut self) {
        self.mode = if self.encoder_uncalibrated {
            ModeState::Calibration
        } else {
            ModeState::Reset
        };
        self.reset_loops();
    }

    pub(super) fn reset_loops(&mut self) {
        self.speed_loop = SpeedLoop::default();
        self.speed_ramp_rad_s = self.plant.velocity_rad_s();
        self.iq_a = 0.0;
        self.torque_nm = 0.0;
    }

    /// Clear latched faults whose cause is gone (type 4 with byte0 = 1).
    pub(super) fn clear_faults(&mut self) {
        let mut still = 0;
        if self.temperature_c >= self.spec.over_temp_fault_c {
            still |= Fault::OverTemperature.word_bit();
        }
        if self.bus_voltage_v < self.spec.under_voltage_v {
            still |= Fault::UnderVoltage.word_bit();
        }
        if self.bus_voltage_v > self.spec.over_voltage_v {
            still |= Fault::OverVoltage.word_bit();
        }
        if self.encoder_uncalibrated {
            still |= Fault::EncoderNotCalibrated.word_bit();
        }
        self.fault_word &= still;
        self.overload_a2s = 0.0;
    }

    pub(super) fn set_zero(&mut self) {
        // Newer firmware ignores zeroing in PP mode (spec §5.6).
        if self.run_mode() == 1 {
            return;
        }
        // Zero is where the encoder reads, glitch and all.
        self.zero_offset_rad = self.plant.position_rad() + self.encoder_glitch_rad;
        // The internal targets move with the zero so the joint does not jump.
        self.params.set(index::LOC_REF, 0.0);
        self.op.angle_rad = 0.0;
        self.profile = Profile::at_rest(0.0);
        self.persist_requested = true;
    }

    fn read_param(&self, idx: u16) -> Option<CanFrame> {
        // 0x70xx and the host tables (0x20xx/0x30xx); see `host.rs`.
        let Some(bytes) = self.param_bytes(idx) else {
            // Failure echo as captured on hardware: status 1, zero payload.
            return codec::frame(
                CommType::ReadParam,
                self.reply_data2(1),
                self.master_id,
                [0; 8],
            );
        };
        let [lo, hi] = idx.to_le_bytes();
        let data = [lo, hi, 0, 0, bytes[0], bytes[1], bytes[2], bytes[3]];
        codec::frame(
            CommType::ReadParam,
            self.reply_data2(0),
            self.master_id,
            data,
        )
    }

    pub(super) fn write_param(&mut self, idx: u16, bytes: [u8; 4]) -> Option<CanFrame> {
        if let Some(row) = host_params::lookup(self.config.model, idx) {
            return self.write_host_param(row, bytes);
        }
        let spec = self.params.spec(idx).copied();
        // Not documented for writes: the type-17 failure flag with the index echoed.
        let refusal = || self.write_refusal(idx);
        let Some(spec) = spec.filter(|spec| spec.access == Access::ReadWrite) else {
            return refusal();
        };
        let Some(value) = params::decode_value(spec.ty, bytes) else {
            return refusal();
        };
        if idx == index::RUN_MODE && self.mode == ModeState::Run {
            // Mode changes only while stopped: ignored, still acknowledged (spec §17 choice).
            tracing::debug!(
                motor = self.can_id,
                "robstride: run_mode write ignored while running"
            );
            return self.status_frame(CommType::Status);
        }
        let old_mode = self.run_mode();
        if let Some(stored) = self.params.set(idx, value) {
            match idx {
                index::RUN_MODE if self.run_mode() != old_mode => self.reset_loops(),
                index::LOC_REF => self.profile.target_rad = stored,
                _ => {}
            }
        }
        self.status_frame(CommType::Status)
    }

    pub(super) fn reply_data2(&self, status: u8) -> u16 {
        (u16::from(status) << 8) | u16::from(self.can_id)
    }

    fn type0_reply(&self) -> Option<CanFrame> {
        codec::frame(CommType::GetId, u16::from(self.can_id), TYPE0_DST, self.uid)
    }

    fn status_data2(&self) -> u16 {
        let faults = u16::from(faults::status_bits(self.fault_word) & 0x3F);
        (self.mode.bits() << 14) | (faults << 8) | u16::from(self.can_id)
    }

    pub(super) fn status_frame(&self, comm: CommType) -> Option<CanFrame> {
        let data = codec::status_payload(
            wrap_angle(self.angle_rad(), f64::from(self.ranges.angle_rad)) as f32,
            self.plant.velocity_rad_s() as f32,
            self.torque_nm as f32,
            self.temperature_c as f32,
            &self.ranges,
        );
        codec::frame(comm, self.status_data2(), self.master_id, data)
    }

    fn version_reply(&self) -> Option<CanFrame> {
        let v = self.spec.firmware_version;
        let data = [0x00, 0xC4, 0x56, v[0], v[1], v[2], v[3], 0x00];
        codec::frame(CommType::Status, self.status_data2(), self.master_id, data)
    }

    pub(super) fn fault_frame(&self) -> Option<CanFrame> {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&self.fault_word.to_le_bytes());
        data[4..].copy_from_slice(&self.warning_word.to_le_bytes());
        codec::frame(
            CommType::Fault,
            u16::from(self.can_id),
            self.master_id,
            data,
        )
    }

    pub(super) fn run_mode(&self) -> u8 {
        self.params.get(index::RUN_MODE) as u8
    }

    pub(super) fn angle_rad(&self) -> f64 {
        self.plant.position_rad() + self.encoder_glitch_rad - self.zero_offset_rad
    }
}

/// Wrap into [−range, range) the way type-2 angles are periodic (spec §3.3).
pub(super) fn wrap_angle(angle: f64, range: f64) -> f64 {
    if angle >= -range && angle < range {
        return angle;
    }
    (angle + range).rem_euclid(2.0 * range) - range
}
