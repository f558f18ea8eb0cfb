//! CAN identifiers of the Piper protocol (11-bit), before any leader/follower offset.

/// Joint LED control (host → arm).
pub const LED: u16 = 0x121;
/// Motion control 1: quick stop / resume, trajectory, drag teach.
pub const MOTION_CTRL_1: u16 = 0x150;
/// Motion control 2: control mode, MOVE mode, speed %, MIT flag, install position.
pub const MODE_CTRL: u16 = 0x151;
/// End-pose target X, Y.
pub const END_POSE_XY: u16 = 0x152;
/// End-pose target Z, RX.
pub const END_POSE_ZRX: u16 = 0x153;
/// End-pose target RY, RZ.
pub const END_POSE_RYRZ: u16 = 0x154;
/// Joint target J1, J2.
pub const JOINT_12: u16 = 0x155;
/// Joint target J3, J4.
pub const JOINT_34: u16 = 0x156;
/// Joint target J5, J6.
pub const JOINT_56: u16 = 0x157;
/// MOVE C point index.
pub const MOVE_C_POINT: u16 = 0x158;
/// Gripper control.
pub const GRIPPER_CTRL: u16 = 0x159;
/// MIT command for joint 1 (joint n = id − 0x159).
pub const MIT_FIRST: u16 = 0x15A;
/// MIT command for joint 6.
pub const MIT_LAST: u16 = 0x15F;
/// CPV parameter read/write, motor 1 (motor n = id − 0x180, 7 = gripper).
pub const CPV_FIRST: u16 = 0x181;
/// CPV parameter read/write, motor 7 (gripper).
pub const CPV_LAST: u16 = 0x187;
/// Leader-arm homing request.
pub const LEADER_HOME: u16 = 0x191;
/// Firmware-upgrade bus mode.
pub const UPGRADE_MODE: u16 = 0x422;
/// Leader/follower configuration and ID offsets.
pub const LINKAGE_CONFIG: u16 = 0x470;
/// Motor enable / disable.
pub const MOTOR_ENABLE: u16 = 0x471;
/// Query joint limits (→ 0x473) or max acceleration (→ 0x47C).
pub const JOINT_QUERY: u16 = 0x472;
/// Joint limit / max speed reply.
pub const JOINT_LIMIT_REPLY: u16 = 0x473;
/// Set joint angle limits / max speed.
pub const SET_JOINT_LIMITS: u16 = 0x474;
/// Joint configuration: set zero, max acceleration, clear error.
pub const JOINT_CONFIG: u16 = 0x475;
/// Set-command acknowledgement (arm → host).
pub const SET_ACK: u16 = 0x476;
/// Parameter query and settings.
pub const PARAM_QUERY: u16 = 0x477;
/// End-effector max velocity/acceleration reply.
pub const END_VEL_ACC_REPLY: u16 = 0x478;
/// Set end-effector max velocity/acceleration.
pub const SET_END_VEL_ACC: u16 = 0x479;
/// Set collision-protection levels.
pub const SET_COLLISION: u16 = 0x47A;
/// Collision-protection levels reply.
pub const COLLISION_REPLY: u16 = 0x47B;
/// Joint max acceleration reply.
pub const JOINT_ACC_REPLY: u16 = 0x47C;
/// Set gripper / teach-pendant parameters.
pub const SET_GRIPPER_TEACH: u16 = 0x47D;
/// Gripper / teach-pendant parameters reply.
pub const GRIPPER_TEACH_REPLY: u16 = 0x47E;
/// Per-joint end velocity/acceleration feedback, joint 1 (joint n = id − 0x480).
pub const END_VEL_FIRST: u16 = 0x481;
/// Set joint assistance levels ((AGX) only).
pub const SET_ASSIST: u16 = 0x487;
/// Firmware version query (host → arm) and reply (arm → host).
pub const FIRMWARE: u16 = 0x4AF;
/// Arm status feedback.
pub const ARM_STATUS: u16 = 0x2A1;
/// End pose X, Y feedback.
pub const FB_END_POSE_XY: u16 = 0x2A2;
/// End pose Z, RX feedback.
pub const FB_END_POSE_ZRX: u16 = 0x2A3;
/// End pose RY, RZ feedback.
pub const FB_END_POSE_RYRZ: u16 = 0x2A4;
/// Joint angles J1, J2 feedback.
pub const FB_JOINT_12: u16 = 0x2A5;
/// Joint angles J3, J4 feedback.
pub const FB_JOINT_34: u16 = 0x2A6;
/// Joint angles J5, J6 feedback.
pub const FB_JOINT_56: u16 = 0x2A7;
/// Gripper feedback.
pub const FB_GRIPPER: u16 = 0x2A8;
/// High-speed driver feedback, joint 1 (joint n = id − 0x250).
pub const HIGH_SPEED_FIRST: u16 = 0x251;
/// Low-speed driver feedback, joint 1 (joint n = id − 0x260).
pub const LOW_SPEED_FIRST: u16 = 0x261;
