//! The OpenArm (`robots/openarm.yaml`: 16 Damiao motors on two buses) driven by our Damiao
//! driver (virtual buses, paused clock): both arms hold against gravity in MIT mode with the
//! vendor's default gains, an arm whose motors are disabled falls, and a robot mixing
//! RobStride and Damiao actuators answers each on its own protocol.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::{CanBus, CanFrame};
use driver::damiao::{DamiaoDriver, DamiaoMotor, DriverConfig, Model as DModel, MotorState};
use sim::robot::{RobotConfig, RobotEmulator, RobotHandle};

/// The vendor's default MIT gains per joint (J1..J7, gripper): kp, kd.
const GAINS: [(f32, f32); 8] = [
    (70.0, 2.75),
    (70.0, 2.5),
    (70.0, 2.0),
    (60.0, 2.0),
    (10.0, 0.7),
    (10.0, 0.6),
    (10.0, 0.5),
    (10.0, 0.2),
];

fn openarm() -> RobotConfig {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/openarm.yaml");
    armhil::robots::load_robot_file(&file)
        .expect("robots/openarm.yaml loads")
        .config
}

struct Running {
    robot: RobotHandle,
    /// Per bus, its motors in robot-file order (J1..J7, gripper).
    motors: Vec<Vec<DamiaoMotor>>,
    _drivers: Vec<DamiaoDriver>,
    buses: Vec<VirtualBus>,
}

fn start(config: RobotConfig) -> Running {
    let buses: Vec<VirtualBus> = config
        .buses
        .iter()
        .map(|b| {
            VirtualBus::new(VirtualBusConfig {
                bitrate_bps: b.bitrate_bps,
                data_bitrate_bps: b.data_bitrate_bps,
                ..VirtualBusConfig::default()
            })
        })
        .collect();
    let nodes = buses
        .iter()
        .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
        .collect();
    let drivers: Vec<DamiaoDriver> = buses
        .iter()
        .map(|b| DamiaoDriver::new(Arc::new(b.attach("host")), DriverConfig::default()))
        .collect();
    let motors = (0..config.buses.len())
        .map(|bus| {
            config
                .actuators
                .iter()
                .filter(|a| a.bus == bus)
                .map(|a| {
                    let id = a.actuator.can_id() as u16;
                    let model = DModel::parse(a.actuator.model().name).expect("a driver model");
                    drivers[bus]
                        .motor(id, id + 0x10, model)
                        .expect("a motor handle")
                })
                .collect()
        })
        .collect();
    let robot = RobotEmulator::spawn(config, nodes).expect("the robot starts");
    Running {
        robot,
        motors,
        _drivers: drivers,
        buses,
    }
}

/// One MIT command to every motor of `bus`: hold `targets` (per joint, rad).
async fn hold(running: &Running, bus: usize, targets: &[f32]) {
    for (k, motor) in running.motors[bus].iter().enumerate() {
        let (kp, kd) = GAINS[k];
        motor.mit(targets[k], 0.0, kp, kd, 0.0).await.expect("MIT");
    }
}

/// Elbow (joint4, the fourth motor of each arm) angle the arms lift their forearms to (rad).
const ELBOW_UP_RAD: f32 = 1.2;

#[tokio::test(start_paused = true)]
async fn both_arms_lift_and_hold_their_forearms_and_a_disabled_arm_falls() {
    let running = start(openarm());
    let first = running.robot.snapshot().await.unwrap();
    // The arms start hanging: gravity loads no joint.
    for joint in &first.joints {
        assert!(joint.actuator.torque_nm.abs() < 1e-9, "{}", joint.joint);
    }
    let start_rad: Vec<f32> = first
        .joints
        .iter()
        .map(|j| j.actuator.angle_rad as f32)
        .collect();
    for bus in 0..2 {
        for motor in &running.motors[bus] {
            let feedback = motor.enable().await.expect("enable");
            assert_eq!(feedback.state, MotorState::Enabled);
        }
    }
    // Lift both forearms over 1 s, then hold 1 s; commands at 200 Hz.
    let target = |step: u32, bus: usize| -> Vec<f32> {
        let mut t = start_rad[bus * 8..bus * 8 + 8].to_vec();
        t[3] = ELBOW_UP_RAD * (step as f32 / 200.0).min(1.0);
        t
    };
    for step in 0..400 {
        for bus in 0..2 {
            hold(&running, bus, &target(step, bus)).await;
        }
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let held = running.robot.snapshot().await.unwrap();
    for (k, joint) in held.joints.iter().enumerate() {
        let goal = f64::from(target(400, k / 8)[k % 8]);
        // The MIT law holds a loaded joint short of its target by torque / kp.
        let sag = joint.actuator.torque_nm.abs() / f64::from(GAINS[k % 8].0);
        assert!(joint.actuator.enabled, "{}", joint.joint);
        assert!(
            (joint.actuator.angle_rad - goal).abs() < sag + 0.01
                && joint.velocity_rad_s.abs() < 0.05,
            "{} at {} for {goal} (sag {sag})",
            joint.joint,
            joint.actuator.angle_rad
        );
    }
    for elbow in ["right_joint4", "left_joint4"] {
        let torque = held.joint(elbow).unwrap().actuator.torque_nm.abs();
        // About 2 kg of forearm and hand, its centre some 0.15 m out: a few N·m.
        assert!(
            (1.0..10.0).contains(&torque),
            "{elbow} carries {torque} N·m"
        );
    }
    // The left arm lets go: its forearm falls while the right one holds.
    for motor in &running.motors[1] {
        motor.disable().await.expect("disable");
    }
    for _ in 0..200 {
        hold(&running, 0, &target(400, 0)).await;
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let after = running.robot.snapshot().await.unwrap();
    let moved = |name: &str| {
        let now = after.joint(name).unwrap().position_rad;
        let then = held.joint(name).unwrap().position_rad;
        (now - then).abs()
    };
    assert!(moved("left_joint4") > 0.2, "the left forearm falls");
    assert!(moved("right_joint4") < 0.01, "the right one holds");
    running.robot.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn a_robot_mixes_robstride_and_damiao_actuators_each_on_its_protocol() {
    // The 6-DoF RobStride arm with its wrist roll a Damiao DM4310 on id 10.
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/robstride_arm6.yaml");
    let mut config = armhil::robots::load_robot_file(&file).unwrap().config;
    let wrist = config
        .actuators
        .iter_mut()
        .find(|a| a.joint == "wrist_roll")
        .unwrap();
    wrist.actuator = sim::actuator::configure("DM4310", 10).unwrap();
    let wrist_bus = wrist.bus;
    let buses: Vec<VirtualBus> = config
        .buses
        .iter()
        .map(|_| VirtualBus::new(VirtualBusConfig::default()))
        .collect();
    let nodes = buses
        .iter()
        .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
        .collect();
    let robot = RobotEmulator::spawn(config, nodes).expect("a mixed robot starts");
    let host = buses[wrist_bus].attach("host");
    // A Damiao enable on id 10 is answered on 0x1A with state 1 (enabled).
    host.send(CanFrame::standard(10, &[0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC]).unwrap())
        .await
        .unwrap();
    let reply = tokio::time::timeout(Duration::from_millis(50), host.recv())
        .await
        .expect("a reply")
        .unwrap();
    assert_eq!(reply.frame.raw_id(), 0x1A);
    assert_eq!(
        reply.frame.data()[0],
        0x1A,
        "state 1, id 10 in the low nibble"
    );
    // The RobStride wrist pitch (id 5) on the same bus still answers its private protocol.
    let enable_5 = CanFrame::extended((3 << 24) | (0xFD << 8) | 5, &[0; 8]).unwrap();
    host.send(enable_5).await.unwrap();
    let reply = tokio::time::timeout(Duration::from_millis(50), host.recv())
        .await
        .expect("a reply")
        .unwrap();
    assert!(reply.frame.id().is_extended());
    assert_eq!(
        (reply.frame.raw_id() >> 24) & 0x1F,
        2,
        "a type-2 status frame"
    );
    let snapshot = robot.snapshot().await.unwrap();
    let kinds: Vec<(&str, bool)> = ["wrist_roll", "wrist_pitch", "shoulder_yaw"]
        .iter()
        .map(|j| {
            let a = &snapshot.joint(j).unwrap().actuator;
            (a.kind, a.enabled)
        })
        .collect();
    assert_eq!(
        kinds,
        [("damiao", true), ("robstride", true), ("robstride", false)]
    );
    robot.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn the_openarm_answers_a_can_fd_frame_in_can_fd_and_a_classic_one_in_classic() {
    let config = openarm();
    assert_eq!(
        config.buses[0].data_bitrate_bps,
        Some(5_000_000),
        "CAN FD at 1/5 Mbit/s"
    );
    let running = start(config);
    let host = running.buses[1].attach("fd host");
    let enable = [0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC];
    let brs = bus::FdFlags {
        brs: true,
        esi: false,
    };
    host.send(CanFrame::fd(bus::CanId::standard(3).unwrap(), &enable, brs).unwrap())
        .await
        .unwrap();
    let reply = tokio::time::timeout(Duration::from_millis(50), host.recv())
        .await
        .expect("a reply")
        .unwrap()
        .frame;
    assert_eq!(reply.raw_id(), 0x13);
    assert!(
        reply.is_fd() && reply.brs(),
        "answered in CAN FD with BRS: {reply:?}"
    );
    assert_eq!(reply.data()[0], 0x13, "enabled, motor 3");
    let disable = [0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFD];
    host.send(CanFrame::standard(3, &disable).unwrap())
        .await
        .unwrap();
    let reply = tokio::time::timeout(Duration::from_millis(50), host.recv())
        .await
        .expect("a reply")
        .unwrap()
        .frame;
    assert!(!reply.is_fd(), "a classic request gets a classic reply");
    assert_eq!(reply.data()[0], 0x03, "disabled, motor 3");
    running.robot.shutdown().await;
}
