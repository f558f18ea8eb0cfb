//! The object dictionary: which objects exist, their types and access, the units the drive
//! speaks in (16384 counts per revolution, 0.1 rpm, 0.1 % of rated torque, mA, mV) and how a
//! read or write reaches the firmware core.

use std::f64::consts::TAU;

use super::cia402::{self, DriveState};
use super::sdo::{Abort, Address};
use super::Mode;
use crate::robstride::firmware::Actuator;
use crate::robstride::model::Model;
use crate::robstride::params::index;

/// Position unit: counts per output revolution.
const COUNTS_PER_REV: f64 = 16384.0;
/// Velocity unit: 0.1 rpm, so rad/s × 600/2π.
const DECI_RPM_PER_RAD_S: f64 = 600.0 / TAU;
/// CiA-402 device type: profile 402, additional information 0x0002 (servo drive).
const DEVICE_TYPE: u32 = 0x0002_0192;
/// Identity 0x1018 sub 1–3 as the vendor's EDS (`driver_v1.1.eds`) gives them.
const VENDOR_ID: u32 = 0x0000_0556;
/// Product code from the vendor's EDS.
const PRODUCT_CODE: u32 = 0x0000_4644;
/// Revision number from the vendor's EDS.
const REVISION: u32 = 0x0000_0500;
/// Within this many counts of the target (about 1°) a position move has reached it.
const POSITION_WINDOW_COUNTS: f64 = 45.0;
/// Within this speed error (rad/s) the velocity target is reached.
const VELOCITY_WINDOW_RAD_S: f64 = 0.1;

/// Wire type of an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum DataType {
    /// UNSIGNED8.
    U8,
    /// UNSIGNED16.
    U16,
    /// UNSIGNED32.
    U32,
    /// INTEGER8.
    I8,
    /// INTEGER16.
    I16,
    /// INTEGER32.
    I32,
}

impl DataType {
    /// Size in bytes.
    pub(super) fn size(self) -> usize {
        match self {
            DataType::U8 | DataType::I8 => 1,
            DataType::U16 | DataType::I16 => 2,
            DataType::U32 | DataType::I32 => 4,
        }
    }

    fn bounds(self) -> (i64, i64) {
        match self {
            DataType::U8 => (0, i64::from(u8::MAX)),
            DataType::U16 => (0, i64::from(u16::MAX)),
            DataType::U32 => (0, i64::from(u32::MAX)),
            DataType::I8 => (i64::from(i8::MIN), i64::from(i8::MAX)),
            DataType::I16 => (i64::from(i16::MIN), i64::from(i16::MAX)),
            DataType::I32 => (i64::from(i32::MIN), i64::from(i32::MAX)),
        }
    }

    /// Little-endian bytes of `value`, saturated into the type's range.
    pub(super) fn encode(self, value: i64) -> Vec<u8> {
        let (lo, hi) = self.bounds();
        let bytes = value.clamp(lo, hi).to_le_bytes();
        bytes[..self.size()].to_vec()
    }

    /// The value of the first `size()` bytes (sign-extended for signed types).
    pub(super) fn decode(self, bytes: [u8; 4]) -> i64 {
        match self {
            DataType::U8 => i64::from(bytes[0]),
            DataType::U16 => i64::from(u16::from_le_bytes([bytes[0], bytes[1]])),
            DataType::U32 => i64::from(u32::from_le_bytes(bytes)),
            DataType::I8 => i64::from(bytes[0] as i8),
            DataType::I16 => i64::from(i16::from_le_bytes([bytes[0], bytes[1]])),
            DataType::I32 => i64::from(i32::from_le_bytes(bytes)),
        }
    }
}

/// Every object this node serves. Anything else is answered "object does not exist".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Object {
    /// 0x1000 device type.
    DeviceType,
    /// 0x1001 error register.
    ErrorRegister,
    /// 0x1017 producer heartbeat time (ms).
    HeartbeatTime,
    /// 0x1018 sub 0: highest subindex (4).
    IdentityCount,
    /// 0x1018 sub 1.
    VendorId,
    /// 0x1018 sub 2.
    ProductCode,
    /// 0x1018 sub 3.
    Revision,
    /// 0x1018 sub 4: the low 32 bits of the MCU UID.
    Serial,
    /// 0x1200 sub 0: highest subindex (2).
    SdoServerCount,
    /// 0x1200 sub 1: COB-ID client→server.
    SdoRxCobId,
    /// 0x1200 sub 2: COB-ID server→client.
    SdoTxCobId,
    /// 0x603F error code.
    ErrorCode,
    /// 0x6040 controlword.
    Controlword,
    /// 0x6041 statusword.
    Statusword,
    /// 0x6060 modes of operation.
    ModesOfOperation,
    /// 0x6061 modes of operation display.
    ModesDisplay,
    /// 0x6064 position actual value (counts).
    PositionActual,
    /// 0x606C velocity actual value (0.1 rpm).
    VelocityActual,
    /// 0x6071 target torque (0.1 % of rated).
    TargetTorque,
    /// 0x6077 torque actual value (0.1 % of rated).
    TorqueActual,
    /// 0x6078 current actual value (mA).
    CurrentActual,
    /// 0x6079 DC link voltage (mV).
    DcLinkVoltage,
    /// 0x607A target position (counts).
    TargetPosition,
    /// 0x6081 profile velocity (0.1 rpm).
    ProfileVelocity,
    /// 0x6083 profile acceleration (0.1 rpm/s).
    ProfileAcceleration,
    /// 0x6099 sub 0: highest subindex (1).
    WatchdogCount,
    /// 0x6099 sub 1: CAN watchdog (20000 = 1 s, 0 = off).
    Watchdog,
    /// 0x60FF target velocity (0.1 rpm).
    TargetVelocity,
}

/// The object at an address, or the abort that says why there is none.
pub(super) fn lookup(at: Address) -> Result<Object, Abort> {
    use Object as O;
    let (object, subs) = match at.index {
        0x1000 => (O::DeviceType, 0),
        0x1001 => (O::ErrorRegister, 0),
        0x1017 => (O::HeartbeatTime, 0),
        0x1018 => {
            let object = [
                O::IdentityCount,
                O::VendorId,
                O::ProductCode,
                O::Revision,
                O::Serial,
            ]
            .get(usize::from(at.sub))
            .copied();
            return object.ok_or(Abort::NoSubindex);
        }
        0x1200 => {
            let object = [O::SdoServerCount, O::SdoRxCobId, O::SdoTxCobId]
                .get(usize::from(at.sub))
                .copied();
            return object.ok_or(Abort::NoSubindex);
        }
        0x603F => (O::ErrorCode, 0),
        0x6040 => (O::Controlword, 0),
        0x6041 => (O::Statusword, 0),
        0x6060 => (O::ModesOfOperation, 0),
        0x6061 => (O::ModesDisplay, 0),
        0x6064 => (O::PositionActual, 0),
        0x606C => (O::VelocityActual, 0),
        0x6071 => (O::TargetTorque, 0),
        0x6077 => (O::TorqueActual, 0),
        0x6078 => (O::CurrentActual, 0),
        0x6079 => (O::DcLinkVoltage, 0),
        0x607A => (O::TargetPosition, 0),
        0x6081 => (O::ProfileVelocity, 0),
        0x6083 => (O::ProfileAcceleration, 0),
        0x6099 => {
            return match at.sub {
                0 => Ok(O::WatchdogCount),
                1 => Ok(O::Watchdog),
                _ => Err(Abort::NoSubindex),
            }
        }
        0x60FF => (O::TargetVelocity, 0),
        _ => return Err(Abort::NoObject),
    };
    if at.sub != subs {
        return Err(Abort::NoSubindex);
    }
    Ok(object)
}

impl Object {
    /// Wire type.
    pub(super) fn data_type(self) -> DataType {
        use Object as O;
        match self {
            O::ErrorRegister | O::IdentityCount | O::SdoServerCount | O::WatchdogCount => {
                DataType::U8
            }
            O::HeartbeatTime | O::ErrorCode | O::Controlword | O::Statusword => DataType::U16,
            O::ModesOfOperation | O::ModesDisplay => DataType::I8,
            O::TargetTorque | O::TorqueActual | O::CurrentActual => DataType::I16,
            O::PositionActual | O::VelocityActual | O::TargetPosition | O::TargetVelocity => {
                DataType::I32
            }
            O::DeviceType
            | O::VendorId
            | O::ProductCode
            | O::Revision
            | O::Serial
            | O::SdoRxCobId
            | O::SdoTxCobId
            | O::DcLinkVoltage
            | O::ProfileVelocity
            | O::ProfileAcceleration
            | O::Watchdog => DataType::U32,
        }
    }

    /// Whether a client may write it.
    pub(super) fn writable(self) -> bool {
        use Object as O;
        matches!(
            self,
            O::HeartbeatTime
                | O::Controlword
                | O::ModesOfOperation
                | O::TargetTorque
                | O::TargetPosition
                | O::ProfileVelocity
                | O::ProfileAcceleration
                | O::Watchdog
                | O::TargetVelocity
        )
    }
}

/// Rated torque (N·m) of each model (spec §6.3): the 100 % (1000) of the torque objects.
pub(super) fn rated_torque_nm(model: Model) -> f64 {
    match model {
        Model::RS00 => 5.0,
        Model::RS01 | Model::RS02 => 6.0,
        Model::RS03 => 20.0,
        Model::RS04 => 40.0,
        Model::RS05 => 1.6,
        Model::RS06 => 11.0,
        Model::EL05 => 1.8,
    }
}

/// Angle (rad) → counts, rounded (saturates at the i32 range when encoded).
pub(super) fn rad_to_counts(angle_rad: f64) -> i64 {
    round_i64(angle_rad * COUNTS_PER_REV / TAU)
}

fn counts_to_rad(counts: i64) -> f64 {
    counts as f64 * TAU / COUNTS_PER_REV
}

fn round_i64(value: f64) -> i64 {
    // NaN reads 0; `as` saturates the infinities.
    if value.is_nan() {
        0
    } else {
        value.round() as i64
    }
}

// Reads and writes against the firmware core.
impl Actuator {
    /// The present value of an object.
    pub(super) fn read_object(&self, object: Object) -> i64 {
        use Object as O;
        let node = &self.canopen;
        let rated = rated_torque_nm(self.config.model);
        match object {
            O::DeviceType => i64::from(DEVICE_TYPE),
            O::ErrorRegister => i64::from(self.error_register()),
            O::HeartbeatTime => i64::from(node.heartbeat_ms),
            O::IdentityCount => 4,
            O::VendorId => i64::from(VENDOR_ID),
            O::ProductCode => i64::from(PRODUCT_CODE),
            O::Revision => i64::from(REVISION),
            O::Serial => {
                let uid = self.uid;
                i64::from(u32::from_le_bytes([uid[0], uid[1], uid[2], uid[3]]))
            }
            O::SdoServerCount => 2,
            O::SdoRxCobId => i64::from(super::sdo::RX_BASE) + i64::from(self.can_id),
            O::SdoTxCobId => i64::from(super::sdo::TX_BASE) + i64::from(self.can_id),
            O::ErrorCode => i64::from(node.error_code),
            O::Controlword => i64::from(node.controlword),
            O::Statusword => i64::from(self.statusword()),
            O::ModesOfOperation | O::ModesDisplay => i64::from(node.mode.code()),
            O::PositionActual => rad_to_counts(self.angle_rad()),
            O::VelocityActual => round_i64(self.plant.velocity_rad_s() * DECI_RPM_PER_RAD_S),
            O::TargetTorque => i64::from(node.target_torque_permille),
            O::TorqueActual => round_i64(self.torque_nm / rated * 1000.0),
            O::CurrentActual => round_i64(self.iq_a * 1000.0),
            O::DcLinkVoltage => round_i64(self.bus_voltage_v * 1000.0),
            O::TargetPosition => node.target_position_counts,
            O::ProfileVelocity => round_i64(self.params.get(index::VEL_MAX) * DECI_RPM_PER_RAD_S),
            O::ProfileAcceleration => {
                round_i64(self.params.get(index::ACC_SET) * DECI_RPM_PER_RAD_S)
            }
            O::WatchdogCount => 1,
            O::Watchdog => round_i64(self.params.get(index::CAN_TIMEOUT)),
            O::TargetVelocity => node.target_velocity_deci_rpm,
        }
    }

    /// Write a (type-checked) value; the abort says why it was refused.
    pub(super) fn write_object(&mut self, object: Object, value: i64) -> Result<(), Abort> {
        use Object as O;
        match object {
            O::HeartbeatTime => {
                self.canopen.heartbeat_ms = value as u16;
                self.canopen.heartbeat_elapsed_ms = 0;
            }
            O::Controlword => self.apply_controlword(value as u16),
            O::ModesOfOperation => {
                let mode = Mode::from_code(value).ok_or(Abort::ValueRange)?;
                // The drive changes mode only while disabled (spec §8).
                if cia402::energised(self.canopen.drive) {
                    return Err(Abort::DeviceState);
                }
                self.canopen.mode = mode;
                self.params.set(index::RUN_MODE, f64::from(mode.run_mode()));
            }
            O::TargetPosition => {
                self.canopen.target_position_counts = value;
                self.apply_targets();
            }
            O::TargetVelocity => {
                let speed = value as f64 / DECI_RPM_PER_RAD_S;
                self.check_range(index::SPD_REF, speed)?;
                self.canopen.target_velocity_deci_rpm = value;
                self.apply_targets();
            }
            O::TargetTorque => {
                let torque = value as f64 / 1000.0 * rated_torque_nm(self.config.model);
                self.check_range(index::IQ_REF, torque / self.spec.torque_constant_nm_per_a)?;
                self.canopen.target_torque_permille = value as i16;
                self.apply_targets();
            }
            O::ProfileVelocity => {
                let speed = value as f64 / DECI_RPM_PER_RAD_S;
                self.check_range(index::VEL_MAX, speed)?;
                self.params.set(index::VEL_MAX, speed);
            }
            O::ProfileAcceleration => {
                // Without 0x6084 the profile brakes as it accelerates.
                let acceleration = value as f64 / DECI_RPM_PER_RAD_S;
                self.check_range(index::ACC_SET, acceleration)?;
                self.params.set(index::ACC_SET, acceleration);
                self.params.set(index::DCC_SET, acceleration);
            }
            O::Watchdog => {
                self.check_range(index::CAN_TIMEOUT, value as f64)?;
                self.params.set(index::CAN_TIMEOUT, value as f64);
            }
            _ => return Err(Abort::WriteOfReadOnly),
        }
        Ok(())
    }

    /// Out-of-range values are refused, not clamped as the private protocol does: CiA-301
    /// has an abort for it.
    fn check_range(&self, idx: u16, value: f64) -> Result<(), Abort> {
        let spec = self.params.spec(idx).ok_or(Abort::NoObject)?;
        if value.is_finite() && (spec.min..=spec.max).contains(&value) {
            Ok(())
        } else {
            Err(Abort::ValueRange)
        }
    }

    /// Hand the targets of the selected mode to the firmware while operation is enabled.
    pub(super) fn apply_targets(&mut self) {
        if self.canopen.drive != DriveState::OperationEnabled {
            return;
        }
        let node = &self.canopen;
        match node.mode {
            Mode::ProfilePosition => {
                let target = counts_to_rad(node.target_position_counts);
                self.params.set(index::LOC_REF, target);
                self.profile.target_rad = target;
            }
            Mode::CyclicPosition => {
                let target = counts_to_rad(node.target_position_counts);
                self.params.set(index::LOC_REF, target);
            }
            Mode::Velocity => {
                let speed = node.target_velocity_deci_rpm as f64 / DECI_RPM_PER_RAD_S;
                self.params.set(index::SPD_REF, speed);
            }
            Mode::Torque => {
                let torque = f64::from(node.target_torque_permille) / 1000.0
                    * rated_torque_nm(self.config.model);
                self.params
                    .set(index::IQ_REF, torque / self.spec.torque_constant_nm_per_a);
            }
            Mode::None | Mode::Homing => {}
        }
    }

    /// Statusword: the state bits, voltage enabled, warning, remote, target reached and (in
    /// homing) homing attained.
    pub(super) fn statusword(&self) -> u16 {
        let node = &self.canopen;
        let mut word = cia402::state_bits(node.drive);
        if self.bus_voltage_v >= self.spec.under_voltage_v {
            word |= 1 << 4;
        }
        if self.warning_word != 0 {
            word |= 1 << 7;
        }
        // Remote: the controlword is obeyed (there is no local control).
        word |= 1 << 9;
        if self.target_reached() {
            word |= 1 << 10;
        }
        if node.mode == Mode::Homing && node.homed {
            word |= 1 << 12;
        }
        word
    }

    fn target_reached(&self) -> bool {
        let node = &self.canopen;
        let speed = self.plant.velocity_rad_s();
        match node.drive {
            DriveState::QuickStopActive => speed.abs() < VELOCITY_WINDOW_RAD_S,
            DriveState::OperationEnabled => match node.mode {
                Mode::ProfilePosition | Mode::CyclicPosition => {
                    let error = node
                        .target_position_counts
                        .saturating_sub(rad_to_counts(self.angle_rad()));
                    (error.unsigned_abs() as f64) <= POSITION_WINDOW_COUNTS
                        && speed.abs() < VELOCITY_WINDOW_RAD_S
                }
                Mode::Velocity => {
                    let target = node.target_velocity_deci_rpm as f64 / DECI_RPM_PER_RAD_S;
                    (target - speed).abs() < VELOCITY_WINDOW_RAD_S
                }
                Mode::Torque | Mode::None => true,
                Mode::Homing => node.homed,
            },
            _ => false,
        }
    }

    /// 0x1001: bit 0 generic, 1 current, 2 voltage, 3 temperature, 4 communication (watchdog),
    /// 7 manufacturer-specific (gate driver, encoder).
    pub(super) fn error_register(&self) -> u8 {
        use crate::robstride::faults::Fault;
        let word = self.fault_word;
        let has = |fault: Fault| word & fault.word_bit() != 0;
        let mut register = 0u8;
        let current = [
            Fault::PhaseOverCurrent(crate::robstride::faults::Phase::A),
            Fault::PhaseOverCurrent(crate::robstride::faults::Phase::B),
            Fault::PhaseOverCurrent(crate::robstride::faults::Phase::C),
            Fault::StallOverload,
        ];
        if current.into_iter().any(has) {
            register |= 1 << 1;
        }
        if has(Fault::UnderVoltage) || has(Fault::OverVoltage) {
            register |= 1 << 2;
        }
        if has(Fault::OverTemperature) {
            register |= 1 << 3;
        }
        if self.canopen.watchdog_expired {
            register |= 1 << 4;
        }
        if has(Fault::GateDriver) || has(Fault::EncoderNotCalibrated) {
            register |= 1 << 7;
        }
        if register != 0 || word != 0 {
            register |= 1;
        }
        register
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_section_13_object_is_in_the_dictionary() {
        for index in [
            0x6040u16, 0x6041, 0x603F, 0x6060, 0x6061, 0x6064, 0x606C, 0x6077, 0x6071, 0x6078,
            0x6079, 0x607A, 0x6081, 0x6083, 0x60FF, 0x1000, 0x1001, 0x1017,
        ] {
            assert!(lookup(Address { index, sub: 0 }).is_ok(), "{index:#x}");
        }
        assert_eq!(
            lookup(Address {
                index: 0x6099,
                sub: 1
            }),
            Ok(Object::Watchdog)
        );
        assert_eq!(
            lookup(Address {
                index: 0x6099,
                sub: 2
            }),
            Err(Abort::NoSubindex)
        );
        assert_eq!(
            lookup(Address {
                index: 0x6041,
                sub: 1
            }),
            Err(Abort::NoSubindex)
        );
        // PDO parameters are not served (SDO-only node).
        assert_eq!(
            lookup(Address {
                index: 0x1800,
                sub: 1
            }),
            Err(Abort::NoObject)
        );
    }

    #[test]
    fn values_saturate_into_their_type_and_sign_extend_back() {
        assert_eq!(DataType::I16.encode(40_000), vec![0xFF, 0x7F]);
        assert_eq!(DataType::U8.encode(-3), vec![0]);
        assert_eq!(DataType::I8.decode([0xFB, 0, 0, 0]), -5);
        assert_eq!(DataType::I32.decode((-16384i32).to_le_bytes()), -16384);
        assert_eq!(DataType::U32.decode([0x20, 0x4E, 0, 0]), 20_000);
    }

    #[test]
    fn one_revolution_is_16384_counts() {
        assert_eq!(rad_to_counts(TAU), 16384);
        assert_eq!(rad_to_counts(-TAU / 4.0), -4096);
        assert!((counts_to_rad(8192) - TAU / 2.0).abs() < 1e-12);
        // 1 rad/s ≈ 9.55 rpm = 95.5 units of 0.1 rpm.
        assert_eq!(round_i64(DECI_RPM_PER_RAD_S), 95);
    }
}
