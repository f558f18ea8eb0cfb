//! Fault behaviour: the active faults and protection latches (thermal, collision, stall) and
//! how injecting or clearing one changes the firmware. The fault table (names, parameters,
//! ranges) and its builder are `crate::piper::faults`.

use super::Firmware;
use crate::piper::codec::host::CtrlMode;
use crate::piper::faults::{driver_bits, FaultError, NtcBoard, PiperFault};
use crate::piper::motor::{JointMotor, DRIVER_OVER_TEMP_C, MOTOR_OVER_TEMP_C, TEMP_HYSTERESIS_C};

/// A motor pinned at its torque limit while (almost) not moving for this long trips the stall
/// protection, ms.
pub const STALL_TIME_MS: u32 = 2000;
/// "Not moving" for the stall protection, rad/s.
const STALL_SPEED_RAD_S: f64 = 0.05;

/// After a joint is enabled, its collision protection waits this long (ms, one tick each)
/// before it judges the residual: the position loop starts from wherever the joint is and
/// first has to catch it. A joint that fell while disabled (the wrist sinks at up to
/// ~2 rad/s) is stopped by its motor's full torque within ~25 ms and back on its reference
/// within ~100 ms; until then the loop's damping term, kd × the joint's own speed (≈ 40 N·m
/// on J5), is not an external disturbance. Without the wait, re-enabling an arm whose
/// wrist is still sinking latched status 0x07 (collision) at any protection level, and the
/// latched fault then refused every motion command, MIT included (issue 20, item 1).
pub const ENABLE_COLLISION_BLANK_MS: u32 = 200;

/// Bus voltage below which the drivers flag under-voltage, V.
pub const UNDER_VOLTAGE_V: f64 = 20.0;

/// Every active fault and protection latch.
#[derive(Debug, Clone, Default)]
pub struct FaultState {
    comm_loss: [bool; 6],
    forced_motor_temp: [Option<f64>; 6],
    forced_driver_temp: [Option<f64>; 6],
    motor_over_temp: [bool; 6],
    driver_over_temp: [bool; 6],
    over_current: [bool; 6],
    driver_error: [bool; 6],
    stall: [bool; 6],
    pub(crate) collision: [bool; 6],
    external_torque_nm: [f64; 6],
    forced_voltage_v: Option<f64>,
    nominal_voltage_v: f64,
    main_ntc: bool,
    resistor_ntc: bool,
    pub(crate) gripper_sensor_fault: bool,
    /// Consecutive ms each motor spent saturated and still.
    stall_ms: [u32; 6],
}

impl FaultState {
    /// No faults, drivers on `nominal_voltage_v`.
    pub fn new(nominal_voltage_v: f64) -> Self {
        Self {
            nominal_voltage_v,
            ..Self::default()
        }
    }

    /// The over-temperature flag of a board's NTC sensor.
    fn ntc(&mut self, board: NtcBoard) -> &mut bool {
        match board {
            NtcBoard::Main => &mut self.main_ntc,
            NtcBoard::BrakeResistor => &mut self.resistor_ntc,
        }
    }

    /// Supply voltage the drivers measure, V.
    pub fn voltage_v(&self) -> f64 {
        self.forced_voltage_v.unwrap_or(self.nominal_voltage_v)
    }

    fn under_voltage(&self) -> bool {
        self.voltage_v() < UNDER_VOLTAGE_V
    }

    fn driver_fault(&self, j: usize) -> bool {
        self.motor_over_temp[j]
            || self.driver_over_temp[j]
            || self.over_current[j]
            || self.driver_error[j]
            || self.stall[j]
            || self.under_voltage()
    }

    /// The arm status a fault forces (0x05, 0x07, 0x09, 0x0E, 0x0F), most severe first.
    pub fn status_code(&self) -> Option<u8> {
        if self.comm_loss.iter().any(|&c| c) {
            Some(0x05)
        } else if self.collision.iter().any(|&c| c) {
            Some(0x07)
        } else if (0..6).any(|j| self.driver_fault(j)) {
            Some(0x09)
        } else if self.main_ntc {
            Some(0x0E)
        } else if self.resistor_ntc {
            Some(0x0F)
        } else {
            None
        }
    }

    /// Motion commands are refused while any fault status is active.
    pub fn blocks_motion(&self) -> Option<u8> {
        self.status_code()
    }

    /// The joint's driver produces no torque (lost, protection tripped, no supply).
    pub fn joint_unpowered(&self, j: usize) -> bool {
        self.comm_loss[j] || self.driver_fault(j)
    }

    /// Whether the joint's 0x25x/0x26x frames are lost.
    pub fn comm_lost(&self, j: usize) -> bool {
        self.comm_loss[j]
    }

    /// 0x2A1 byte 7.
    pub fn comm_bits(&self) -> u8 {
        (0..6).fold(0, |acc, j| acc | (u8::from(self.comm_loss[j]) << j))
    }

    /// Reported winding temperature, °C.
    pub fn motor_temp_c(&self, j: usize, motor: &JointMotor) -> f64 {
        self.forced_motor_temp[j].unwrap_or(motor.motor_temp_c())
    }

    /// Reported driver temperature, °C.
    pub fn driver_temp_c(&self, j: usize, motor: &JointMotor) -> f64 {
        self.forced_driver_temp[j].unwrap_or(motor.driver_temp_c())
    }

    /// 0x26x byte 5 without the enable bit.
    pub fn driver_bits(&self, j: usize) -> u8 {
        let mut b = 0;
        if self.under_voltage() {
            b |= driver_bits::UNDER_VOLTAGE;
        }
        if self.motor_over_temp[j] {
            b |= driver_bits::MOTOR_OVER_TEMP;
        }
        if self.over_current[j] {
            b |= driver_bits::OVER_CURRENT;
        }
        if self.driver_over_temp[j] {
            b |= driver_bits::DRIVER_OVER_TEMP;
        }
        if self.collision[j] {
            b |= driver_bits::COLLISION;
        }
        if self.driver_error[j] {
            b |= driver_bits::DRIVER_ERROR;
        }
        if self.stall[j] {
            b |= driver_bits::STALL;
        }
        b
    }

    /// 0x475 byte 5 / 0x150 reset: clear the latched protections of joint `j`.
    pub fn clear_latched(&mut self, j: usize) {
        self.over_current[j] = false;
        self.driver_error[j] = false;
        self.stall[j] = false;
        self.collision[j] = false;
    }
}

fn joint_index(joint: u8) -> Result<usize, FaultError> {
    if (1..=6).contains(&joint) {
        Ok(usize::from(joint - 1))
    } else {
        Err(FaultError::NoSuchJoint { joint })
    }
}

/// Collision threshold of a joint at protection `level` (1–8, higher = more sensitive), N·m:
/// from ⅔ of the motor's torque limit at level 1 down to 1/12 of it at level 8.
pub fn collision_threshold_nm(torque_limit_nm: f64, level: u8) -> f64 {
    torque_limit_nm * f64::from(9u8.saturating_sub(level)) / 12.0
}

impl Firmware {
    /// Inject a fault.
    pub fn inject(&mut self, fault: PiperFault) -> Result<(), FaultError> {
        // Every caller (scenario, web view, Python, tests) comes through here: refuse a
        // value outside the fault table's range before it reaches the physics.
        fault.check()?;
        tracing::info!(%fault, t_s = self.time_s(), "Piper fault injected");
        let f = &mut self.faults;
        match fault {
            PiperFault::CommLoss { joint } => f.comm_loss[joint_index(joint)?] = true,
            PiperFault::MotorOverTemp { joint, temp_c } => {
                f.forced_motor_temp[joint_index(joint)?] = Some(temp_c);
            }
            PiperFault::DriverOverTemp { joint, temp_c } => {
                f.forced_driver_temp[joint_index(joint)?] = Some(temp_c);
            }
            PiperFault::OverCurrent { joint } => f.over_current[joint_index(joint)?] = true,
            PiperFault::UnderVoltage { voltage_v } => f.forced_voltage_v = Some(voltage_v),
            PiperFault::DriverError { joint } => f.driver_error[joint_index(joint)?] = true,
            PiperFault::Stall { joint } => f.stall[joint_index(joint)?] = true,
            PiperFault::ExternalTorque { joint, torque_nm } => {
                f.external_torque_nm[joint_index(joint)?] = torque_nm;
                self.apply_external_torques();
            }
            PiperFault::Collision { joint } => f.collision[joint_index(joint)?] = true,
            PiperFault::Estop => {
                self.estop = true;
                self.abort_motion();
            }
            PiperFault::NtcOverTemp { board } => *f.ntc(board) = true,
            PiperFault::GripperSensorFault => f.gripper_sensor_fault = true,
            PiperFault::TeachButton => {
                self.ctrl_mode = CtrlMode::Teach;
                self.abort_motion();
            }
        }
        self.check_protections();
        Ok(())
    }

    /// Remove `fault`'s cause (its values, such as a temperature, do not matter; see
    /// [`crate::piper::faults::FaultKind::description`] for what else clears each one).
    pub fn clear(&mut self, fault: PiperFault) -> Result<(), FaultError> {
        tracing::info!(?fault, t_s = self.time_s(), "Piper fault cleared");
        let f = &mut self.faults;
        match fault {
            PiperFault::CommLoss { joint } => f.comm_loss[joint_index(joint)?] = false,
            PiperFault::MotorOverTemp { joint, .. } => {
                f.forced_motor_temp[joint_index(joint)?] = None;
            }
            PiperFault::DriverOverTemp { joint, .. } => {
                f.forced_driver_temp[joint_index(joint)?] = None;
            }
            PiperFault::OverCurrent { joint } => f.over_current[joint_index(joint)?] = false,
            PiperFault::UnderVoltage { .. } => f.forced_voltage_v = None,
            PiperFault::DriverError { joint } => f.driver_error[joint_index(joint)?] = false,
            PiperFault::Stall { joint } => f.stall[joint_index(joint)?] = false,
            PiperFault::ExternalTorque { joint, .. } => {
                f.external_torque_nm[joint_index(joint)?] = 0.0;
                self.apply_external_torques();
            }
            PiperFault::Collision { joint } => f.collision[joint_index(joint)?] = false,
            PiperFault::Estop => self.estop = false,
            PiperFault::NtcOverTemp { board } => *f.ntc(board) = false,
            PiperFault::GripperSensorFault => f.gripper_sensor_fault = false,
            PiperFault::TeachButton => {
                if self.ctrl_mode == CtrlMode::Teach {
                    self.ctrl_mode = CtrlMode::Standby;
                    self.hold_here();
                }
            }
        }
        self.check_protections();
        Ok(())
    }

    fn apply_external_torques(&mut self) {
        let mut tau = vec![0.0; self.world.joints().len()];
        for j in 0..6 {
            tau[self.arm_idx[j]] = self.faults.external_torque_nm[j];
        }
        self.world.set_external_joint_torques(&tau);
    }

    /// Thermal thresholds and collision protection; a tripped driver disables itself and the
    /// arm stops.
    pub(crate) fn check_protections(&mut self) {
        let mut tripped = false;
        for j in 0..6 {
            let motor_t = self.faults.motor_temp_c(j, &self.motors[j]);
            let driver_t = self.faults.driver_temp_c(j, &self.motors[j]);
            let f = &mut self.faults;
            if motor_t >= MOTOR_OVER_TEMP_C && !f.motor_over_temp[j] {
                f.motor_over_temp[j] = true;
                tripped = true;
            } else if motor_t < MOTOR_OVER_TEMP_C - TEMP_HYSTERESIS_C {
                f.motor_over_temp[j] = false;
            }
            if driver_t >= DRIVER_OVER_TEMP_C && !f.driver_over_temp[j] {
                f.driver_over_temp[j] = true;
                tripped = true;
            } else if driver_t < DRIVER_OVER_TEMP_C - TEMP_HYSTERESIS_C {
                f.driver_over_temp[j] = false;
            }
            let level = self.flash.collision_levels[j];
            let armed = self.collision_blank_ticks[j] == 0;
            if level > 0 && armed && self.enabled[j] && !self.faults.collision[j] {
                let threshold = collision_threshold_nm(self.motors[j].torque_limit_nm(), level);
                if self.collision_residual[j].abs() > threshold {
                    tracing::info!(
                        joint = j + 1,
                        residual_nm = self.collision_residual[j],
                        threshold_nm = threshold,
                        "Piper collision protection"
                    );
                    self.faults.collision[j] = true;
                    tripped = true;
                }
            }
        }
        for j in 0..6 {
            let saturated =
                self.motors[j].torque_nm().abs() >= 0.99 * self.motors[j].torque_limit_nm();
            if self.enabled[j] && saturated && self.v_phys(j).abs() < STALL_SPEED_RAD_S {
                self.faults.stall_ms[j] += 1;
                if self.faults.stall_ms[j] >= STALL_TIME_MS && !self.faults.stall[j] {
                    tracing::info!(joint = j + 1, t_s = self.time_s(), "Piper stall protection");
                    self.faults.stall[j] = true;
                    tripped = true;
                }
            } else {
                self.faults.stall_ms[j] = 0;
            }
        }
        for j in 0..6 {
            if self.faults.joint_unpowered(j) && self.enabled[j] {
                self.enabled[j] = false;
                tripped = true;
            }
        }
        if self.faults.gripper_sensor_fault {
            self.gripper.enabled = false;
        }
        if tripped || (self.faults.status_code().is_some() && self.motion.is_some()) {
            self.hold_here();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::piper::PiperConfig;

    #[test]
    fn an_absurd_fault_value_is_refused_and_changes_nothing() {
        let mut fw = Firmware::new(PiperConfig::default()).expect("stock Piper");
        let err = fw
            .inject(PiperFault::ExternalTorque {
                joint: 2,
                torque_nm: 1e308,
            })
            .unwrap_err();
        assert!(matches!(err, FaultError::OutOfRange { .. }), "{err}");
        assert!(fw.world.external_joint_torques().iter().all(|t| *t == 0.0));
        let err = fw
            .inject(PiperFault::MotorOverTemp {
                joint: 2,
                temp_c: 1e308,
            })
            .unwrap_err();
        assert!(matches!(err, FaultError::OutOfRange { .. }), "{err}");
        assert_eq!(fw.faults.forced_motor_temp, [None; 6]);
        for _ in 0..100 {
            fw.tick();
        }
        assert!(fw.physical_joints().iter().all(|q| q.is_finite()));
    }

    #[test]
    fn the_largest_accepted_torque_keeps_the_physics_finite() {
        let mut fw = Firmware::new(PiperConfig::default()).expect("stock Piper");
        for joint in 1..=6 {
            fw.inject(PiperFault::ExternalTorque {
                joint,
                torque_nm: if joint % 2 == 0 { 320.0 } else { -320.0 },
            })
            .expect("within range");
        }
        for _ in 0..2000 {
            fw.tick();
        }
        let snapshot = fw.snapshot();
        assert!(
            snapshot.joint_positions_rad.iter().all(|q| q.is_finite())
                && snapshot
                    .joint_velocities_rad_s
                    .iter()
                    .all(|v| v.is_finite()),
            "{snapshot:?}"
        );
    }
}
