//! The MIT protocol variant (protocol note §12): what a motor speaks after type 25 with
//! F_CMD = 2 and a power cycle, until MIT command 8 switches it back (again after a power
//! cycle). 11-bit identifiers, bits 10..8 the frame kind, bits 7..0 the motor ID, DLC 8.
//!
//! The commands drive the same firmware as the private protocol: MIT mode is run_mode 0 (the
//! command-3 setpoint is the operation-control law), position mode is CSP (run_mode 5:
//! command 10 sets loc_ref and limit_spd), velocity mode is run_mode 2 (command 11 sets
//! spd_ref and limit_cur). Choices where the sources leave it open (also in
//! `docs/protocols/robstride.md` §12):
//! - Response 1 follows the CN manuals: byte 6 carries the mode state (bits 7..6), a fault
//!   flag (bit 5), a warning flag (bit 4) and the high nibble of the 12-bit temperature ×10.
//! - The fault-status reply carries the fault word little-endian in bytes 1..4, as type 21.
//! - Set-ID is marker 0xFA (the manual), not the sample program's 0x01 (that is set-host-ID).
//! - Set-mode is accepted only while stopped (ignored while running, still answered), as the
//!   private run_mode write; set-ID is refused while running (no reply), as type 7.
//! - Parameter read/write (commands 14/15) answer only indices the motor serves; a read of an
//!   unknown index or a refused write gets no reply. A write's reply carries the value stored
//!   (after clamping).
//! - No type-21 frames: a fault shows in Response 1 and the fault-status reply only.

use bus::CanFrame;

use super::{can_id_accepted, host_id_accepted, protocol_accepted, Actuator, ModeState};
use crate::robstride::codec::payload8;
use crate::robstride::params::index;

/// The protocol byte of the MIT variant (type 25 F_CMD, MIT command 8 F_CMD).
pub(super) const PROTOCOL_MIT: u8 = 2;

/// Frame kinds (identifier bits 10..8).
const KIND_COMMAND: u32 = 0;
const KIND_POSITION: u32 = 1;
const KIND_VELOCITY: u32 = 2;
const KIND_READ: u32 = 3;
const KIND_WRITE: u32 = 4;

/// Marker bytes (byte 7) of the fixed-pattern commands.
const MARK_ENABLE_OR_MODE: u8 = 0xFC;
const MARK_STOP_OR_PROTOCOL: u8 = 0xFD;
const MARK_ZERO: u8 = 0xFE;
const MARK_FAULT: u8 = 0xFB;
const MARK_CAN_ID: u8 = 0xFA;
const MARK_HOST_ID: u8 = 0x01;
const MARK_SAVE: u8 = 0xF8;
const MARK_REPORT: u8 = 0xF9;

/// run_mode values the MIT modes map to (MIT 0 → operation control, 1 → CSP, 2 → velocity).
const MIT_MODES: [u8; 3] = [0, 5, 2];

/// Float → unsigned `bits`-bit integer over [min, max] (the manual's clamp-and-truncate).
fn to_uint(value: f64, min: f64, max: f64, bits: u32) -> u16 {
    let top = f64::from((1u32 << bits) - 1);
    if value.is_nan() || max <= min {
        return 0;
    }
    ((value.clamp(min, max) - min) * top / (max - min)) as u16
}

/// Unsigned `bits`-bit integer → float over [min, max].
fn from_uint(raw: u16, min: f64, max: f64, bits: u32) -> f64 {
    let top = f64::from((1u32 << bits) - 1);
    f64::from(raw) * (max - min) / top + min
}

fn standard(id: u32, data: [u8; 8]) -> Option<CanFrame> {
    // Every identifier built here is at most (4 << 8) | 0x7F; `None` cannot happen.
    CanFrame::standard(u16::try_from(id).ok()?, &data).ok()
}

impl Actuator {
    /// React to a frame while the MIT protocol is in force (standard frames only).
    pub(super) fn handle_mit_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame> {
        let mut out = Vec::new();
        if frame.is_extended() || frame.len() != 8 {
            return out;
        }
        let raw = frame.raw_id();
        if raw & 0xFF != u32::from(self.can_id) {
            return out;
        }
        let data = payload8(frame);
        self.since_command_s = 0.0;
        match raw >> 8 {
            KIND_COMMAND => out.extend(self.mit_command(&data)),
            KIND_POSITION => {
                let (angle, speed) = (f32_at(&data, 0), f32_at(&data, 4));
                if let (Some(angle), Some(speed)) = (angle, speed) {
                    self.params.set(index::LOC_REF, angle);
                    self.params.set(index::LIMIT_SPD, speed.abs());
                }
                out.extend(self.mit_status());
            }
            KIND_VELOCITY => {
                let (speed, current) = (f32_at(&data, 0), f32_at(&data, 4));
                if let (Some(speed), Some(current)) = (speed, current) {
                    self.params.set(index::SPD_REF, speed);
                    self.params.set(index::LIMIT_CUR, current.abs());
                }
                out.extend(self.mit_status());
            }
            KIND_READ => {
                let idx = u16::from_le_bytes([data[0], data[1]]);
                out.extend(self.mit_param_reply(KIND_READ, idx));
            }
            KIND_WRITE => {
                let idx = u16::from_le_bytes([data[0], data[1]]);
                let value = [data[4], data[5], data[6], data[7]];
                // The private write path applies ranges, read-only rows and the run_mode rule;
                // its type-17 answer means refused.
                let refused = self
                    .write_param(idx, value)
                    .is_some_and(|reply| reply.raw_id() >> 24 == 17);
                if !refused {
                    out.extend(self.mit_param_reply(KIND_WRITE, idx));
                }
            }
            _ => {}
        }
        out
    }

    fn mit_command(&mut self, data: &[u8; 8]) -> Option<CanFrame> {
        if data[..6] != [0xFF; 6] {
            self.op = self.decode_mit_setpoint(data);
            return self.mit_status();
        }
        let (f_cmd, marker) = (data[6], data[7]);
        match (marker, f_cmd) {
            (MARK_ENABLE_OR_MODE, 0xFF) => {
                self.enable();
                self.mit_status()
            }
            (MARK_ENABLE_OR_MODE, mode @ 0..=2) => {
                if self.mode != ModeState::Run {
                    let run_mode = f64::from(MIT_MODES[usize::from(mode)]);
                    if self.params.set(index::RUN_MODE, run_mode).is_some() {
                        self.reset_loops();
                    }
                }
                self.mit_status()
            }
            (MARK_STOP_OR_PROTOCOL, 0xFF) => {
                self.stop();
                self.mit_status()
            }
            (MARK_STOP_OR_PROTOCOL, protocol) if protocol_accepted(protocol) => {
                self.pending_protocol = protocol;
                self.persist_requested = true;
                self.mit_uid_reply()
            }
            (MARK_ZERO, 0xFF) => {
                // Not in position mode (spec §12); the private path already skips PP.
                if self.run_mode() != MIT_MODES[1] {
                    self.set_zero();
                }
                self.mit_status()
            }
            (MARK_FAULT, 0xFF) => {
                self.clear_faults();
                self.mit_status()
            }
            (MARK_FAULT, _) => self.mit_fault_reply(),
            (MARK_CAN_ID, new_id) => {
                if self.mode == ModeState::Run || !can_id_accepted(new_id) {
                    return None;
                }
                tracing::info!(
                    old = self.can_id,
                    new = new_id,
                    "robstride MIT: CAN ID changed"
                );
                self.can_id = new_id;
                self.persist_requested = true;
                self.mit_uid_reply()
            }
            (MARK_HOST_ID, host) if host_id_accepted(host) => {
                self.master_id = host;
                self.mit_uid_reply()
            }
            (MARK_SAVE, 0xFF) => {
                self.saved_params = self.params.saved_values();
                self.persist_requested = true;
                self.mit_uid_reply()
            }
            (MARK_REPORT, on @ 0..=1) => {
                self.active_report = on == 1;
                self.report_elapsed_ms = 0;
                self.mit_status()
            }
            _ => None,
        }
    }

    fn decode_mit_setpoint(&self, d: &[u8; 8]) -> crate::robstride::control::OpCommand {
        let r = &self.ranges;
        let (p, v, t) = (
            f64::from(r.angle_rad),
            f64::from(r.speed_rad_s),
            f64::from(r.torque_nm),
        );
        let angle = u16::from_be_bytes([d[0], d[1]]);
        let speed = (u16::from(d[2]) << 4) | u16::from(d[3] >> 4);
        let kp = (u16::from(d[3] & 0x0F) << 8) | u16::from(d[4]);
        let kd = (u16::from(d[5]) << 4) | u16::from(d[6] >> 4);
        let torque = (u16::from(d[6] & 0x0F) << 8) | u16::from(d[7]);
        crate::robstride::control::OpCommand {
            angle_rad: from_uint(angle, -p, p, 16),
            speed_rad_s: from_uint(speed, -v, v, 12),
            kp: from_uint(kp, 0.0, f64::from(r.kp_max), 12),
            kd: from_uint(kd, 0.0, f64::from(r.kd_max), 12),
            torque_nm: from_uint(torque, -t, t, 12),
        }
    }

    /// Response 1: the status frame, to the host ID.
    pub(super) fn mit_status(&self) -> Option<CanFrame> {
        let r = &self.ranges;
        let p = f64::from(r.angle_rad);
        let angle = to_uint(super::frames::wrap_angle(self.angle_rad(), p), -p, p, 16);
        let v = f64::from(r.speed_rad_s);
        let speed = to_uint(self.plant.velocity_rad_s(), -v, v, 12);
        let t = f64::from(r.torque_nm);
        let torque = to_uint(self.torque_nm, -t, t, 12);
        let temp = (self.temperature_c * 10.0).round().clamp(0.0, 4095.0) as u16;
        let flags = (self.mode.bits() << 6)
            | (u16::from(self.fault_word != 0) << 5)
            | (u16::from(self.warning_word != 0) << 4);
        let [a_hi, a_lo] = angle.to_be_bytes();
        let data = [
            self.can_id,
            a_hi,
            a_lo,
            (speed >> 4) as u8,
            (((speed & 0x0F) << 4) | (torque >> 8)) as u8,
            (torque & 0xFF) as u8,
            (flags | (temp >> 8)) as u8,
            (temp & 0xFF) as u8,
        ];
        standard(u32::from(self.master_id), data)
    }

    /// Response 2: the MCU UID, from the motor's ID.
    fn mit_uid_reply(&self) -> Option<CanFrame> {
        standard(u32::from(self.can_id), self.uid)
    }

    /// Command 5 with F_CMD ≠ 0xFF: motor ID and the fault word (bytes 1..4, little-endian).
    fn mit_fault_reply(&self) -> Option<CanFrame> {
        let mut data = [0u8; 8];
        data[0] = self.can_id;
        data[1..5].copy_from_slice(&self.fault_word.to_le_bytes());
        standard(u32::from(self.master_id), data)
    }

    /// Commands 14/15: same identifier, index echoed, the value in bytes 4..7.
    fn mit_param_reply(&self, kind: u32, idx: u16) -> Option<CanFrame> {
        let value = self.param_bytes(idx)?;
        let [lo, hi] = idx.to_le_bytes();
        let data = [lo, hi, 0, 0, value[0], value[1], value[2], value[3]];
        standard((kind << 8) | u32::from(self.can_id), data)
    }
}

/// A finite little-endian f32 at `offset`.
fn f32_at(data: &[u8; 8], offset: usize) -> Option<f64> {
    let value = f32::from_le_bytes([
        data[offset],
        data[offset + 1],
        data[offset + 2],
        data[offset + 3],
    ]);
    value.is_finite().then_some(f64::from(value))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn twelve_bit_scaling_spans_the_range() {
        assert_eq!(to_uint(0.0, -20.0, 20.0, 12), 2047);
        assert_eq!(to_uint(20.0, -20.0, 20.0, 12), 4095);
        assert_eq!(to_uint(-99.0, -20.0, 20.0, 12), 0);
        assert_eq!(to_uint(f64::NAN, -20.0, 20.0, 12), 0);
        assert!((from_uint(4095, -20.0, 20.0, 12) - 20.0).abs() < 1e-9);
        assert!((from_uint(2047, -20.0, 20.0, 12)).abs() < 0.01);
    }
}
