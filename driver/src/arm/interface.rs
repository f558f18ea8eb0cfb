//! The vendor-neutral [`ArmInterface`] trait and the [`Method`] names used to ask a backend
//! what it can do. Every method has a default that answers `NOT_IMPLEMENTED`; a backend
//! overrides what its arm can do and lists exactly those in [`ArmInterface::capabilities`].

use async_trait::async_trait;

use super::error::{ArmError, ArmResult};
use super::params::Vendor;
use super::realtime::{RealtimeCallback, RealtimeHub, RealtimeSubscription};
use super::types::{
    ErrorFlags, GripperState, IkMode, MoveOptions, PeripheralReadWriteParams, Pose, TrajectoryMode,
};

/// One method of the Arm API, for capability queries.
///
/// A method's name is its variant's name in snake case (`move_joint_position`).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    strum::IntoStaticStr,
    strum::VariantArray,
    strum::EnumCount,
)]
#[strum(serialize_all = "snake_case")]
pub enum Method {
    /// `connect` / `disconnect`.
    Connect,
    /// `move_joint_position`.
    MoveJointPosition,
    /// `move_cartesian_linear`.
    MoveCartesianLinear,
    /// `move_joint_pose`.
    MoveJointPose,
    /// `move_joint_position_canfd`.
    MoveJointPositionCanfd,
    /// `move_cartesian_pose_canfd`.
    MoveCartesianPoseCanfd,
    /// `move_joint_follow`.
    MoveJointFollow,
    /// `move_pose_follow`.
    MovePoseFollow,
    /// `realtime_arm_state_call_back` and [`ArmInterface::subscribe_realtime`].
    #[strum(serialize = "realtime_arm_state_call_back")]
    RealtimeState,
    /// `set_arm_slow_stop`.
    SetArmSlowStop,
    /// `set_arm_stop`.
    SetArmStop,
    /// `set_arm_pause`.
    SetArmPause,
    /// `set_arm_continue`.
    SetArmContinue,
    /// `set_plus_mode`.
    SetPlusMode,
    /// `set_gripper_release`.
    SetGripperRelease,
    /// `set_gripper_pick`.
    SetGripperPick,
    /// `set_gripper_pick_on`.
    SetGripperPickOn,
    /// `set_gripper_position`.
    SetGripperPosition,
    /// `get_gripper_state`.
    GetGripperState,
    /// `set_hand_posture`.
    SetHandPosture,
    /// `set_hand_angle`.
    SetHandAngle,
    /// `set_hand_follow_angle`.
    SetHandFollowAngle,
    /// `set_hand_follow_pos`.
    SetHandFollowPos,
    /// `set_hand_speed`.
    SetHandSpeed,
    /// `set_hand_force`.
    SetHandForce,
    /// `get_joint_degree`.
    GetJointDegree,
    /// `forward_kinematics`.
    ForwardKinematics,
    /// `inverse_kinematics`.
    InverseKinematics,
    /// `set_modbus_mode`.
    SetModbusMode,
    /// `close_modbus_mode`.
    CloseModbusMode,
    /// `write_registers`.
    WriteRegisters,
    /// `get_error_flag`.
    GetErrorFlag,
}

impl Method {
    /// Every method, in the API's order.
    ///
    /// An array, built from the derived variant list, so callers iterate it by value.
    pub const ALL: [Self; <Method as strum::EnumCount>::COUNT] = {
        let variants = <Method as strum::VariantArray>::VARIANTS;
        let mut all = [Method::Connect; <Method as strum::EnumCount>::COUNT];
        let mut i = 0;
        while i < all.len() {
            all[i] = variants[i];
            i += 1;
        }
        all
    };

    /// The API's method name (`move_joint_position`).
    pub fn name(self) -> &'static str {
        self.into()
    }
}

/// A connected (or connectable) robot arm, whatever its vendor. Object safe: hold it as
/// `Arc<dyn ArmInterface>`. Joints are in degrees, poses in metres and radians; a method the
/// vendor cannot do returns `NOT_IMPLEMENTED`; before [`ArmInterface::connect`] the others
/// return `NOT_INITIALIZED`.
#[async_trait]
pub trait ArmInterface: Send + Sync {
    /// The instance name (`arm_name`).
    fn name(&self) -> &str;

    /// The vendor.
    fn vendor(&self) -> Vendor;

    /// The methods this backend implements (the rest answer `NOT_IMPLEMENTED`).
    fn capabilities(&self) -> &'static [Method];

    /// Whether `method` is implemented.
    fn supports(&self, method: Method) -> bool {
        self.capabilities().contains(&method)
    }

    /// The realtime publisher (each backend owns one).
    fn realtime_hub(&self) -> &RealtimeHub;

    /// `NOT_IMPLEMENTED` for `method` on this vendor.
    fn unsupported(&self, method: Method) -> ArmError {
        ArmError::not_implemented(self.vendor().name(), method.name())
    }

    /// Opens the connection and starts the realtime state stream.
    async fn connect(&self) -> ArmResult<()>;

    /// Closes the connection; later calls answer `NOT_INITIALIZED`.
    async fn disconnect(&self);

    /// Joint-space move to `joints_deg`.
    async fn move_joint_position(&self, _joints_deg: &[f64], _opts: MoveOptions) -> ArmResult<()> {
        Err(self.unsupported(Method::MoveJointPosition))
    }

    /// Straight-line Cartesian move to `pose`.
    async fn move_cartesian_linear(&self, _pose: &Pose, _opts: MoveOptions) -> ArmResult<()> {
        Err(self.unsupported(Method::MoveCartesianLinear))
    }

    /// Joint-space move to `pose`.
    async fn move_joint_pose(&self, _pose: &Pose, _opts: MoveOptions) -> ArmResult<()> {
        Err(self.unsupported(Method::MoveJointPose))
    }

    /// Passthrough joint target (no controller planning); `follow` = high-follow.
    async fn move_joint_position_canfd(
        &self,
        _joints_deg: &[f64],
        _follow: bool,
        _mode: TrajectoryMode,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::MoveJointPositionCanfd))
    }

    /// Passthrough Cartesian target.
    async fn move_cartesian_pose_canfd(
        &self,
        _pose: &Pose,
        _follow: bool,
        _mode: TrajectoryMode,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::MoveCartesianPoseCanfd))
    }

    /// Joint-space following (planned online).
    async fn move_joint_follow(&self, _joints_deg: &[f64]) -> ArmResult<()> {
        Err(self.unsupported(Method::MoveJointFollow))
    }

    /// Cartesian following (planned online).
    async fn move_pose_follow(&self, _pose: &Pose) -> ArmResult<()> {
        Err(self.unsupported(Method::MovePoseFollow))
    }

    /// Every realtime state from now on, at the arm's rate.
    fn subscribe_realtime(&self) -> RealtimeSubscription {
        self.realtime_hub().subscribe()
    }

    /// The API's callback form: `callback` receives every realtime state, replacing an earlier
    /// callback. It runs on a task of the current tokio runtime (`INVALID_STATE` outside one).
    fn realtime_arm_state_call_back(&self, callback: RealtimeCallback) -> ArmResult<()> {
        self.realtime_hub().set_callback(callback)
    }

    /// Decelerate and stop along the path.
    async fn set_arm_slow_stop(&self) -> ArmResult<()> {
        Err(self.unsupported(Method::SetArmSlowStop))
    }

    /// Stop at once (the trajectory cannot be resumed).
    async fn set_arm_stop(&self) -> ArmResult<()> {
        Err(self.unsupported(Method::SetArmStop))
    }

    /// Pause on the path (resumable).
    async fn set_arm_pause(&self) -> ArmResult<()> {
        Err(self.unsupported(Method::SetArmPause))
    }

    /// Resume after a pause.
    async fn set_arm_continue(&self) -> ArmResult<()> {
        Err(self.unsupported(Method::SetArmContinue))
    }

    /// End-effector protocol mode (0 off, or a baud rate).
    async fn set_plus_mode(&self, _mode: u32) -> ArmResult<()> {
        Err(self.unsupported(Method::SetPlusMode))
    }

    /// Open the gripper fully at `speed` (1–1000); `timeout_s` bounds a blocking wait.
    async fn set_gripper_release(
        &self,
        _speed: u16,
        _block: bool,
        _timeout_s: u32,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::SetGripperRelease))
    }

    /// Close at `speed` (1–1000) until `force` (50–1000) is reached.
    async fn set_gripper_pick(
        &self,
        _speed: u16,
        _force: u16,
        _block: bool,
        _timeout_s: u32,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::SetGripperPick))
    }

    /// Like [`ArmInterface::set_gripper_pick`], holding the force continuously.
    async fn set_gripper_pick_on(
        &self,
        _speed: u16,
        _force: u16,
        _block: bool,
        _timeout_s: u32,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::SetGripperPickOn))
    }

    /// Move the gripper to aperture `position` (1–1000).
    async fn set_gripper_position(
        &self,
        _position: u16,
        _block: bool,
        _timeout_s: u32,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::SetGripperPosition))
    }

    /// The gripper's state.
    async fn get_gripper_state(&self) -> ArmResult<GripperState> {
        Err(self.unsupported(Method::GetGripperState))
    }

    /// Dexterous hand: run stored gesture `posture_num` (1–40).
    async fn set_hand_posture(
        &self,
        _posture_num: u8,
        _block: bool,
        _timeout_s: u32,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::SetHandPosture))
    }

    /// Dexterous hand: six finger angles 0–1000, -1 keeps a finger.
    async fn set_hand_angle(&self, _hand_angle: [i32; 6]) -> ArmResult<()> {
        Err(self.unsupported(Method::SetHandAngle))
    }

    /// Dexterous hand: angle following; `block_ms` 0 = non-blocking.
    async fn set_hand_follow_angle(&self, _hand_angle: [i32; 6], _block_ms: u32) -> ArmResult<()> {
        Err(self.unsupported(Method::SetHandFollowAngle))
    }

    /// Dexterous hand: position following; `block_ms` 0 = non-blocking.
    async fn set_hand_follow_pos(&self, _hand_pos: [i32; 6], _block_ms: u32) -> ArmResult<()> {
        Err(self.unsupported(Method::SetHandFollowPos))
    }

    /// Dexterous hand: finger speed 1–1000.
    async fn set_hand_speed(&self, _speed: u16) -> ArmResult<()> {
        Err(self.unsupported(Method::SetHandSpeed))
    }

    /// Dexterous hand: finger force 1–1000.
    async fn set_hand_force(&self, _hand_force: u16) -> ArmResult<()> {
        Err(self.unsupported(Method::SetHandForce))
    }

    /// Current joint angles, degrees.
    async fn get_joint_degree(&self) -> ArmResult<Vec<f64>> {
        Err(self.unsupported(Method::GetJointDegree))
    }

    /// Flange pose for `joints_deg`.
    async fn forward_kinematics(&self, _joints_deg: &[f64]) -> ArmResult<Pose> {
        Err(self.unsupported(Method::ForwardKinematics))
    }

    /// Joint angles (degrees) that put the flange at `pose`, starting from `ref_joints_deg`;
    /// `ARM_OUT_OF_RANGE` when no solution within the joint limits exists.
    async fn inverse_kinematics(
        &self,
        _pose: &Pose,
        _ref_joints_deg: &[f64],
        _mode: IkMode,
    ) -> ArmResult<Vec<f64>> {
        Err(self.unsupported(Method::InverseKinematics))
    }

    /// Configure Modbus RTU on `port`.
    async fn set_modbus_mode(
        &self,
        _port: u8,
        _baudrate: u32,
        _timeout_100ms: u32,
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::SetModbusMode))
    }

    /// Leave Modbus RTU mode on `port`.
    async fn close_modbus_mode(&self, _port: u8) -> ArmResult<()> {
        Err(self.unsupported(Method::CloseModbusMode))
    }

    /// Write holding registers of a Modbus peripheral.
    async fn write_registers(
        &self,
        _params: &PeripheralReadWriteParams,
        _values: &[u16],
    ) -> ArmResult<()> {
        Err(self.unsupported(Method::WriteRegisters))
    }

    /// Per-joint error codes and brake states.
    async fn get_error_flag(&self) -> ArmResult<ErrorFlags> {
        Err(self.unsupported(Method::GetErrorFlag))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn method_names_are_unique() {
        let mut names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Method::ALL.len());
    }

    #[test]
    fn method_names_are_the_api_names() {
        assert_eq!(Method::ALL.len(), 32);
        assert_eq!(Method::ALL[0].name(), "connect");
        assert_eq!(
            Method::MoveJointPositionCanfd.name(),
            "move_joint_position_canfd"
        );
        assert_eq!(Method::RealtimeState.name(), "realtime_arm_state_call_back");
        assert_eq!(Method::GetErrorFlag.name(), "get_error_flag");
    }
}
