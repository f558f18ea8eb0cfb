//! The Arm API's data types. Units follow the API: joints in degrees, joint speeds in RPM,
//! currents in mA, gripper values 0–1000, force sensor values in 0.001 N (N·m), and a
//! Cartesian pose in metres and radians.

use std::time::SystemTime;

use super::error::{ArmError, ArmResult};

/// A Cartesian pose of the flange in the arm's base frame: position in metres, orientation as
/// intrinsic Z-Y-X Euler angles (R = Rz(rz)·Ry(ry)·Rx(rx)) in radians.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// x, y, z in metres.
    pub position_m: [f64; 3],
    /// rx, ry, rz in radians.
    pub euler_rad: [f64; 3],
}

impl Pose {
    /// A pose from position (m) and Euler angles (rad).
    pub fn new(position_m: [f64; 3], euler_rad: [f64; 3]) -> Self {
        Self {
            position_m,
            euler_rad,
        }
    }

    /// `INVALID_ARGUMENT` unless every component is finite.
    pub fn check_finite(&self) -> ArmResult<()> {
        if self
            .position_m
            .iter()
            .chain(&self.euler_rad)
            .all(|v| v.is_finite())
        {
            Ok(())
        } else {
            Err(ArmError::new(
                super::AbcErrorCode::InvalidArgument,
                format!("pose {self:?} has a non-finite component"),
            ))
        }
    }
}

/// The planning options of `move_joint_position`, `move_cartesian_linear` and
/// `move_joint_pose`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MoveOptions {
    /// `v`: percent of the maximum speed and acceleration, 1–100.
    pub speed_percent: u8,
    /// `r`: blend radius, percent 0–100 (0 = none; only effective for queued moves).
    pub blend_radius: u8,
    /// `trajectory_connect`: false = plan and run now; true = queue with the next move.
    pub trajectory_connect: bool,
    /// `block`: wait until the arm arrives (or the move fails).
    pub block: bool,
}

impl MoveOptions {
    /// Run now at `speed_percent`, blocking until arrival.
    pub fn blocking(speed_percent: u8) -> Self {
        Self {
            speed_percent,
            blend_radius: 0,
            trajectory_connect: false,
            block: true,
        }
    }

    /// Run now at `speed_percent`, returning once the command is accepted.
    pub fn non_blocking(speed_percent: u8) -> Self {
        Self {
            block: false,
            ..Self::blocking(speed_percent)
        }
    }

    /// `PARAM_OUT_OF_RANGE` unless `v` is 1–100 and `r` is 0–100.
    pub fn validate(&self) -> ArmResult<()> {
        if !(1..=100).contains(&self.speed_percent) {
            return Err(ArmError::out_of_range("v", self.speed_percent, "1..=100"));
        }
        if self.blend_radius > 100 {
            return Err(ArmError::out_of_range("r", self.blend_radius, "0..=100"));
        }
        Ok(())
    }
}

/// `trajectory_mode` and `radio` of the passthrough (`*_canfd`) moves in high-follow mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TrajectoryMode {
    /// 0: full passthrough.
    #[default]
    Passthrough,
    /// 1: curve fitting with smoothing coefficient 0–100.
    CurveFitting(u16),
    /// 2: filtering with filter parameter 0–1000.
    Filtering(u16),
}

impl TrajectoryMode {
    /// From the API's `(trajectory_mode, radio)` integers; `PARAM_OUT_OF_RANGE` when either is
    /// outside its range.
    pub fn from_api(trajectory_mode: i32, radio: i32) -> ArmResult<Self> {
        match trajectory_mode {
            0 => Ok(Self::Passthrough),
            1 if (0..=100).contains(&radio) => Ok(Self::CurveFitting(radio as u16)),
            1 => Err(ArmError::out_of_range("radio", radio, "0..=100")),
            2 if (0..=1000).contains(&radio) => Ok(Self::Filtering(radio as u16)),
            2 => Err(ArmError::out_of_range("radio", radio, "0..=1000")),
            other => Err(ArmError::out_of_range("trajectory_mode", other, "0, 1, 2")),
        }
    }
}

/// Inverse-kinematics solution mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IkMode {
    /// 0: one solve from the reference joints.
    #[default]
    SingleStep,
    /// 1: iterative search from several starting points.
    IterativeSearch,
}

/// Per-joint state, in the API's units.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointState {
    /// Joint angles, degrees.
    pub joint_position: Vec<f64>,
    /// Joint speeds, RPM (empty when the arm does not report them).
    pub joint_speed: Vec<f64>,
    /// Joint currents, mA.
    pub joint_current: Vec<f64>,
    /// Joint temperatures, °C.
    pub joint_temperature: Vec<f64>,
    /// Joint voltages, V.
    pub joint_voltage: Vec<f64>,
    /// Joint error codes (0 = none).
    pub joint_err_code: Vec<u32>,
    /// Joint enable flags.
    pub joint_en_flag: Vec<bool>,
}

/// Force sensor data in 0.001 N (forces) and 0.001 N·m (torques).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ArmForceSensor {
    /// Raw sensor reading.
    pub force: Vec<f64>,
    /// External force after zeroing.
    pub zero_force: Vec<f64>,
    /// Frame of `zero_force`: 0 sensor, 1 work, 2 tool.
    pub coordinate: i32,
}

/// What the arm is doing, reduced to what every vendor can tell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ArmCurrentStatus {
    /// Not known (the arm does not report it).
    #[default]
    Unknown,
    /// At rest.
    Idle,
    /// Executing a motion.
    Moving,
    /// Paused on a trajectory.
    Paused,
    /// Stopping or stopped by a stop command.
    Stopped,
    /// In an error or emergency-stop state.
    Error,
}

/// Gripper state in the API's units.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GripperState {
    /// 0 offline, 1 online, -1 online but disabled.
    pub status: i32,
    /// Error bits: bit 0 locked rotor, 1 over-temperature, 2 over-current, 3 driver, 4 comms.
    pub error: u32,
    /// 1 open idle, 2 closed idle, 3 stopped idle, 4 closing, 5 opening, 6 stopped by force.
    pub mode: i32,
    /// Force, grams.
    pub current_force: i32,
    /// Temperature, °C.
    pub temperature: i32,
    /// Aperture 0 (closed) – 1000 (fully open).
    pub actpos: i32,
}

/// One realtime state sample.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmRealtimeState {
    /// The arm's name.
    pub name: String,
    /// When the sample was received (wall clock).
    pub timestamp: SystemTime,
    /// Time since `connect` on the tokio clock (virtual under a paused clock, so runs in
    /// virtual time are reproducible).
    pub since_connect: std::time::Duration,
    /// Joint states.
    pub joint_status: JointState,
    /// Force sensor (empty vectors when the arm has none).
    pub force_sensor: ArmForceSensor,
    /// Motion status.
    pub arm_current_status: ArmCurrentStatus,
    /// Gripper state (`None` when the gripper is not enabled or not yet read).
    pub gripper_state: Option<GripperState>,
    /// Flange pose.
    pub ee_pose: Pose,
}

/// Modbus read/write parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PeripheralReadWriteParams {
    /// 0 controller RS485, 1 end-effector RS485, 3 controller Modbus TCP.
    pub port: u8,
    /// Starting data address.
    pub address: u16,
    /// Peripheral device address.
    pub device: u8,
    /// Number of data items.
    pub num: u16,
}

/// `get_error_flag`: per-joint error codes and brake states.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ErrorFlags {
    /// Error code per joint (0 = none).
    pub joint_errors: Vec<u32>,
    /// Brake engaged (not released) per joint.
    pub brake_engaged: Vec<bool>,
}

/// `PARAM_OUT_OF_RANGE` unless `value` is in `lo..=hi`; returns it as u16.
pub(crate) fn in_range(field: &str, value: i64, lo: i64, hi: i64) -> ArmResult<u16> {
    if (lo..=hi).contains(&value) {
        Ok(value as u16)
    } else {
        Err(ArmError::out_of_range(
            field,
            value,
            &format!("{lo}..={hi}"),
        ))
    }
}

/// `INVALID_ARGUMENT` unless `joints_deg` has `dof` finite values; returns them in radians.
pub(crate) fn joints_to_rad(joints_deg: &[f64], dof: usize) -> ArmResult<Vec<f64>> {
    if joints_deg.len() != dof {
        return Err(ArmError::new(
            super::AbcErrorCode::InvalidArgument,
            format!("{} joint values given, the arm has {dof}", joints_deg.len()),
        ));
    }
    if let Some(bad) = joints_deg.iter().find(|v| !v.is_finite()) {
        return Err(ArmError::new(
            super::AbcErrorCode::InvalidArgument,
            format!("joint value {bad} is not finite"),
        ));
    }
    Ok(joints_deg.iter().map(|d| d.to_radians()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::AbcErrorCode;

    #[test]
    fn move_options_check_v_and_r() {
        assert!(MoveOptions::blocking(1).validate().is_ok());
        assert!(MoveOptions::blocking(100).validate().is_ok());
        for v in [0, 101] {
            let e = MoveOptions::blocking(v).validate().unwrap_err();
            assert_eq!(e.code, AbcErrorCode::ParamOutOfRange, "v = {v}");
        }
        let r = MoveOptions {
            blend_radius: 101,
            ..MoveOptions::blocking(50)
        };
        assert!(r.validate().unwrap_err().message.contains("r = 101"));
    }

    #[test]
    fn trajectory_modes_check_radio_per_mode() {
        assert_eq!(
            TrajectoryMode::from_api(1, 100).unwrap(),
            TrajectoryMode::CurveFitting(100)
        );
        assert_eq!(
            TrajectoryMode::from_api(2, 1000).unwrap(),
            TrajectoryMode::Filtering(1000)
        );
        assert!(TrajectoryMode::from_api(1, 101).is_err());
        assert!(TrajectoryMode::from_api(2, -1).is_err());
        assert!(TrajectoryMode::from_api(3, 0).is_err());
    }

    #[test]
    fn joint_vectors_need_the_arm_dof_and_finite_values() {
        let rad = joints_to_rad(&[90.0, 0.0], 2).unwrap();
        assert!((rad[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(
            joints_to_rad(&[0.0; 5], 6).unwrap_err().code,
            AbcErrorCode::InvalidArgument
        );
        assert!(joints_to_rad(&[f64::NAN, 0.0], 2).is_err());
    }
}
