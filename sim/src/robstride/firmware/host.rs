//! Parameter reads and writes beyond the 0x70xx store: the host-tool tables 0x20xx/0x30xx
//! ([`crate::robstride::host_params`]) with values from the running motor, and the one place
//! that turns any readable index into its four value bytes (types 17/18 and MIT commands
//! 14/15 share it).

use std::f64::consts::{PI, TAU};

use bus::CanFrame;

use super::Actuator;
use crate::robstride::codec::{self, CommType};
use crate::robstride::host_params::{self, HostParam, Live, Source};
use crate::robstride::params::{self, index};

impl Actuator {
    /// The value bytes (`data[4..8]`) of a readable index: a 0x70xx parameter or a host-table
    /// row; `None` for an index the motor does not serve (strings 0x0000/0x1000.., gaps).
    pub(super) fn param_bytes(&self, idx: u16) -> Option<[u8; 4]> {
        if let Some(spec) = self.params.spec(idx) {
            let value = match idx {
                index::MECH_POS => self.angle_rad(),
                index::IQF => self.iq_a,
                index::MECH_VEL => self.plant.velocity_rad_s(),
                index::VBUS => self.bus_voltage_v,
                _ => self.params.get(idx),
            };
            return Some(params::encode_value(spec.ty, value));
        }
        let row = host_params::lookup(self.config.model, idx)?;
        let value = match row.source {
            Source::Mirror(target) => self.params.get(target),
            Source::Live(live) => self.live_value(live),
            Source::Const(value) => value,
        };
        Some(host_params::encode(row.ty, value))
    }

    /// A type-18 write to a host-table row: a mirror of a 0x70xx parameter is written through
    /// to it (same range, same reply); every other row is refused with the failure flag.
    pub(super) fn write_host_param(&mut self, row: HostParam, bytes: [u8; 4]) -> Option<CanFrame> {
        let Source::Mirror(target) = row.source else {
            return self.write_refusal(row.index);
        };
        let (Some(spec), Some(value)) = (
            self.params.spec(target).copied(),
            host_params::decode(row.ty, bytes),
        ) else {
            return self.write_refusal(row.index);
        };
        self.write_param(target, params::encode_value(spec.ty, value))
    }

    /// The answer to a refused write: the type-17 failure flag with the index echoed.
    pub(super) fn write_refusal(&self, idx: u16) -> Option<CanFrame> {
        let [lo, hi] = idx.to_le_bytes();
        codec::frame(
            CommType::ReadParam,
            self.reply_data2(1),
            self.master_id,
            [lo, hi, 0, 0, 0, 0, 0, 0],
        )
    }

    fn live_value(&self, live: Live) -> f64 {
        let angle = self.angle_rad();
        let run_mode = self.run_mode();
        match live {
            Live::CanId => f64::from(self.can_id),
            Live::CanMaster => f64::from(self.master_id),
            Live::BaudCode => f64::from(self.pending_baud),
            Live::Protocol => f64::from(self.pending_protocol),
            Live::MechOffset => (self.zero_offset_rad + PI).rem_euclid(TAU) - PI,
            Live::MechPos => angle,
            Live::MechVel => self.plant.velocity_rad_s(),
            Live::ModPos => angle.rem_euclid(TAU),
            Live::Rotation => (angle / TAU).floor(),
            Live::TorqueFdb | Live::CmdTorque => self.torque_nm,
            Live::Iq => self.iq_a,
            Live::Id => 0.0,
            Live::CmdLocRef => match run_mode {
                0 => self.op.angle_rad,
                1 => self.profile.angle_rad,
                _ => self.params.get(index::LOC_REF),
            },
            Live::CmdSpdRef => match run_mode {
                0 => self.op.speed_rad_s,
                1 => self.profile.speed_rad_s,
                2 => self.speed_ramp_rad_s,
                _ => 0.0,
            },
            Live::CmdPos => self.op.angle_rad,
            Live::CmdVel => self.op.speed_rad_s,
            Live::Vbus => self.bus_voltage_v,
            Live::VbusMv => self.bus_voltage_v * 1000.0,
            Live::McuTemp10 | Live::BoardTemp10 => self.config.ambient_c * 10.0,
            Live::MotorTemp10 => self.temperature_c * 10.0,
            Live::FaultSta => f64::from(self.fault_word),
            Live::WarnSta => f64::from(self.warning_word),
        }
    }
}
