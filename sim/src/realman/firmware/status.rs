//! What the controller reports about the arm: the reported pose (tool frame in the work frame),
//! the error fields in the firmware's form, the state replies shared by several queries and the
//! UDP push datagram (docs/protocols/realman.md §6, §11).

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::super::ioports;
use super::super::kinematics::{self, Pose};
use super::super::params::Frame;
use super::super::wire::{self, Obj};
use super::Controller;

/// The simulation's ground truth at one instant (for tests and the harness).
#[derive(Debug, Clone, PartialEq)]
pub struct ArmSnapshot {
    /// Milliseconds since boot.
    pub time_ms: u64,
    /// Measured joint positions, rad.
    pub joints_rad: Vec<f64>,
    /// Measured joint speeds, rad/s.
    pub speeds_rad_s: Vec<f64>,
    /// Commanded set-point, rad.
    pub setpoint_rad: Vec<f64>,
    /// Reported pose (tool in work frame).
    pub pose: Pose,
    /// Arm power.
    pub power_on: bool,
    /// Per-joint enable.
    pub enabled: Vec<bool>,
    /// Active error codes.
    pub errors: Vec<u16>,
    /// `arm_current_status` string.
    pub status: &'static str,
    /// Moves accepted and not finished.
    pub queued_moves: usize,
}

fn isometry(position_m: [f64; 3], euler_rad: [f64; 3]) -> Isometry3<f64> {
    let rot = Rotation3::from_euler_angles(euler_rad[0], euler_rad[1], euler_rad[2]);
    Isometry3::from_parts(
        Translation3::new(position_m[0], position_m[1], position_m[2]),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

fn frame_isometry(frame: &Frame) -> Isometry3<f64> {
    isometry(frame.position_m, frame.euler_rad)
}

fn pose_of(iso: &Isometry3<f64>) -> Pose {
    let (rx, ry, rz) = iso.rotation.euler_angles();
    let t: Vector3<f64> = iso.translation.vector;
    Pose {
        position_m: [t.x, t.y, t.z],
        euler_rad: [rx, ry, rz],
    }
}

impl Controller {
    /// Tool pose in the current work frame for joints `q`.
    pub(super) fn reported_pose(&self, q: &[f64]) -> Pose {
        let flange = kinematics::forward(&self.model, q);
        let work = &self.params.work_frames[self.params.current_work];
        let tool = &self.params.tool_frames[self.params.current_tool];
        if work.position_m == [0.0; 3]
            && work.euler_rad == [0.0; 3]
            && tool.position_m == [0.0; 3]
            && tool.euler_rad == [0.0; 3]
        {
            return flange;
        }
        let base_tool = isometry(flange.position_m, flange.euler_rad) * frame_isometry(tool);
        pose_of(&(frame_isometry(work).inverse() * base_tool))
    }

    /// A pose given in the current work frame for the tool → the flange pose in the base frame
    /// (what the kinematics solves for).
    pub(super) fn flange_target(&self, tool_in_work: &Pose) -> Pose {
        let work = &self.params.work_frames[self.params.current_work];
        let tool = &self.params.tool_frames[self.params.current_tool];
        if work.position_m == [0.0; 3]
            && work.euler_rad == [0.0; 3]
            && tool.position_m == [0.0; 3]
            && tool.euler_rad == [0.0; 3]
        {
            return *tool_in_work;
        }
        let base_tool =
            frame_isometry(work) * isometry(tool_in_work.position_m, tool_in_work.euler_rad);
        pose_of(&(base_tool * frame_isometry(tool).inverse()))
    }

    /// Measured joints, 0.001°.
    pub(super) fn joints_mdeg(&self) -> Vec<i64> {
        self.plant
            .positions_rad()
            .iter()
            .map(|q| wire::rad_to_mdeg(*q))
            .collect()
    }

    /// Reported pose of the measured joints, wire units.
    pub(super) fn pose_wire(&self) -> [i64; 6] {
        wire::pose_to_wire(&self.reported_pose(&self.plant.positions_rad()))
    }

    /// Append the error fields in the profile's form: `err:[…]` or `arm_err` + `sys_err`.
    pub(super) fn with_errors(&self, obj: Obj) -> Obj {
        let codes = self.errors.codes();
        if self.profile.err_array() {
            let list: Vec<i64> = if codes.is_empty() {
                vec![0]
            } else {
                codes.iter().map(|c| i64::from(*c)).collect()
            };
            obj.ints("err", &list)
        } else {
            let arm = codes.iter().find(|c| (0x1000..0x2000).contains(*c));
            let sys = codes.iter().find(|c| !(0x1000..0x2000).contains(*c));
            obj.int("arm_err", arm.map_or(0, |c| i64::from(*c)))
                .int("sys_err", sys.map_or(0, |c| i64::from(*c)))
        }
    }

    /// `get_current_arm_state` reply.
    pub(super) fn arm_state_reply(&self) -> String {
        let inner = Obj::new()
            .ints("joint", &self.joints_mdeg())
            .ints("pose", &self.pose_wire());
        Obj::state("current_arm_state")
            .obj("arm_state", self.with_errors(inner))
            .finish()
    }

    pub(super) fn en_flags(&self) -> Vec<i64> {
        self.enabled.iter().map(|e| i64::from(*e)).collect()
    }

    pub(super) fn err_flags(&self) -> Vec<i64> {
        self.joint_err.iter().map(|e| i64::from(*e)).collect()
    }

    pub(super) fn temperatures_milli(&self) -> Vec<i64> {
        self.plant
            .temperatures_c()
            .iter()
            .map(|v| wire::milli(*v))
            .collect()
    }

    pub(super) fn currents_milli(&self) -> Vec<i64> {
        self.plant
            .currents_ma()
            .iter()
            .map(|v| wire::milli(*v))
            .collect()
    }

    pub(super) fn voltages_milli(&self) -> Vec<i64> {
        self.plant
            .voltages_v()
            .iter()
            .map(|v| wire::milli(*v))
            .collect()
    }

    /// The realtime push datagram now.
    pub fn push_datagram(&self) -> String {
        let q = self.plant.positions_rad();
        let custom = self.params.push.custom;
        let mut joints = Obj::new()
            .ints("joint_current", &self.currents_milli())
            .ints("joint_en_flag", &self.en_flags())
            .ints("joint_err_code", &self.err_flags())
            .ints("joint_position", &self.joints_mdeg())
            .ints("joint_temperature", &self.temperatures_milli())
            .ints("joint_voltage", &self.voltages_milli());
        if custom.joint_speed {
            // 0.01 °/s (the SDK's reading of this field).
            let speeds: Vec<i64> = self
                .plant
                .speeds_rad_s()
                .iter()
                .map(|s| wire::milli(s.to_degrees() / 10.0))
                .collect();
            joints = joints.ints("joint_speed", &speeds);
        }
        let pose = self.reported_pose(&q);
        let quat: Vec<i64> = pose
            .quaternion_wxyz()
            .iter()
            .map(|c| wire::m_to_um(*c))
            .collect();
        let w = wire::pose_to_wire(&pose);
        let waypoint = Obj::new()
            .ints("euler", &w[3..])
            .ints("position", &w[..3])
            .ints("quat", &quat);
        let mut obj = Obj::state("realtime_arm_joint_state")
            .obj("joint_status", joints)
            .obj("waypoint", waypoint);
        obj = self.with_errors(obj);
        if custom.arm_current_status {
            obj = obj.str("arm_current_status", self.motion.status());
        }
        if custom.hand {
            obj = obj.obj("hand_state", self.hand_state_obj());
        }
        if custom.aloha_state {
            obj = obj.obj(
                "aloha_state",
                Obj::new().int("io1_state", 0).int("io2_state", 0),
            );
        }
        if custom.rm_plus_state {
            obj = obj.int("rm_plus_state", 1);
        }
        if custom.io_state {
            obj = obj.obj("io_state", self.io_state_obj());
        }
        obj.finish()
    }

    /// armhil's push block of the IO ports: the levels each port shows (`DIO`, 1 high), their
    /// modes, the analog outputs (mV), the tool ports and both supply settings.
    fn io_state_obj(&self) -> Obj {
        let io = &self.params.io;
        let levels: Vec<i64> = (0..ioports::DIGITAL_PORTS)
            .map(|i| i64::from(io.level(i)))
            .collect();
        let tool: Vec<i64> = (0..ioports::TOOL_PORTS)
            .map(|i| i64::from(io.tool_level(i)))
            .collect();
        let ints = |v: &[u8]| v.iter().map(|x| i64::from(*x)).collect::<Vec<_>>();
        let mv: Vec<i64> = io.analog_out_mv.iter().map(|x| i64::from(*x)).collect();
        Obj::new()
            .ints("DIO", &levels)
            .ints("IO_Mode", &ints(&io.modes))
            .ints("AO", &mv)
            .int("voltage_type", i64::from(io.supply_type))
            .ints("tool_IO", &tool)
            .ints("tool_IO_Mode", &ints(&io.tool_modes))
            .int("tool_voltage_type", i64::from(io.tool_supply_type))
    }

    fn hand_state_obj(&self) -> Obj {
        let angles: Vec<i64> = self.hand.angles.iter().map(|a| a.round() as i64).collect();
        Obj::new()
            .ints("hand_pos", &angles)
            .ints("hand_angle", &angles)
            .ints("hand_force", &[0; 6])
            .ints("hand_state", &[0; 6])
            .int("hand_err", 0)
    }

    /// Ground truth now.
    pub fn snapshot(&self) -> ArmSnapshot {
        let q = self.plant.positions_rad();
        ArmSnapshot {
            time_ms: self.time_ms,
            pose: self.reported_pose(&q),
            joints_rad: q,
            speeds_rad_s: self.plant.speeds_rad_s(),
            setpoint_rad: self.setpoint_rad.clone(),
            power_on: self.power_on,
            enabled: self.enabled.clone(),
            errors: self.errors.codes(),
            status: self.motion.status(),
            queued_moves: self.motion.plan_count(),
        }
    }
}
