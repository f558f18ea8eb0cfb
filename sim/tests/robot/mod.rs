//! Whole robots on the virtual bus (paused clock): one world, several buses, the actuators'
//! firmware driving the joints against gravity and each other.

use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame};
use sim::actuator::ActuatorConfig;
use sim::fault_args::{FaultArgValue, FaultArgs};
use sim::physics::ArmModel;
use sim::robot::{
    Base, BusConfig, JointActuator, RobotConfig, RobotConfigError, RobotEmulator, RobotError,
    RobotHandle,
};
use sim::robstride::{ModeState, Model, MotorConfig};

const ARM_URDF: &str = include_str!("../../../urdf/robstride_arm6.urdf");
const HOST: u32 = 0xFD;

/// The 6-DoF arm: shoulder and elbow (ids 1–3) on `can0`, the wrist (ids 4–6) on `can1`.
fn arm_config(start: &[(&str, f64)]) -> RobotConfig {
    let joints = [
        ("shoulder_yaw", Model::RS03, 0),
        ("shoulder_pitch", Model::RS04, 0),
        ("elbow_pitch", Model::RS03, 0),
        ("wrist_roll", Model::RS02, 1),
        ("wrist_pitch", Model::RS02, 1),
        ("flange_roll", Model::RS02, 1),
    ];
    RobotConfig {
        name: "robstride_arm6".into(),
        urdf: ARM_URDF.into(),
        urdf_paths: Default::default(),
        missing_meshes: Default::default(),
        collision: None,
        self_collision: None,
        convex_decomposition: Vec::new(),
        base: Base::Fixed,
        gantry: Default::default(),
        physics: Default::default(),
        buses: ["can0", "can1"]
            .iter()
            .map(|name| BusConfig {
                name: (*name).into(),
                bitrate_bps: 1_000_000,
                data_bitrate_bps: None,
            })
            .collect(),
        actuators: joints
            .iter()
            .enumerate()
            .map(|(k, (joint, model, bus))| JointActuator {
                joint: (*joint).into(),
                bus: *bus,
                actuator: ActuatorConfig::new(MotorConfig::new(k as u8 + 1, *model)),
                direction: 1.0,
                zero_offset_rad: 0.0,
            })
            .collect(),
        start_positions_rad: start.iter().map(|(j, q)| ((*j).into(), *q)).collect(),
        state_file: None,
        host_id: HOST as u8,
    }
}

struct Rig {
    robot: RobotHandle,
    hosts: Vec<VirtualNode>,
    _buses: Vec<VirtualBus>,
}

fn spawn(config: RobotConfig) -> Rig {
    let buses: Vec<VirtualBus> = config
        .buses
        .iter()
        .map(|_| VirtualBus::new(VirtualBusConfig::default()))
        .collect();
    let nodes: Vec<Arc<dyn CanBus>> = buses
        .iter()
        .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
        .collect();
    let hosts = buses.iter().map(|b| b.attach("host")).collect();
    let robot = RobotEmulator::spawn(config, nodes).expect("the robot starts");
    Rig {
        robot,
        hosts,
        _buses: buses,
    }
}

fn ext(comm: u32, data2: u32, motor: u32, data: [u8; 8]) -> CanFrame {
    CanFrame::extended((comm << 24) | (data2 << 8) | motor, &data).unwrap()
}

/// Type 18: write a float parameter.
fn write_f32(index: u16, value: f32, motor: u32) -> CanFrame {
    let [lo, hi] = index.to_le_bytes();
    let v = value.to_le_bytes();
    ext(0x12, HOST, motor, [lo, hi, 0, 0, v[0], v[1], v[2], v[3]])
}

/// Type 18: write a byte parameter.
fn write_u8(index: u16, value: u8, motor: u32) -> CanFrame {
    let [lo, hi] = index.to_le_bytes();
    ext(0x12, HOST, motor, [lo, hi, 0, 0, value, 0, 0, 0])
}

/// Drains what the host has received so far.
async fn drain(host: &VirtualNode) {
    while let Ok(Ok(_)) = tokio::time::timeout(Duration::from_millis(1), host.recv()).await {}
}

/// Puts motor `motor` on `host`'s bus in CSP (run_mode 5), enabled, targeting `target_rad`.
async fn csp_hold(host: &VirtualNode, motor: u32, target_rad: f32) {
    send(host, write_u8(0x7005, 5, motor)).await;
    send(host, ext(0x03, HOST, motor, [0; 8])).await;
    send(host, write_f32(0x7017, 3.0, motor)).await; // limit_spd
    send(host, write_f32(0x7016, target_rad, motor)).await; // loc_ref
}

/// Sends one frame and lets the bus carry it (a host's transmit queue is ten frames deep).
async fn send(host: &VirtualNode, frame: CanFrame) {
    host.send(frame).await.unwrap();
    tokio::time::sleep(Duration::from_micros(200)).await;
}

#[tokio::test(start_paused = true)]
async fn the_arm_holds_a_pose_against_gravity_with_the_torque_its_urdf_needs() {
    holds_a_pose_against_gravity(sim::physics::Solver::Articulated).await;
}

/// The same robot on rapier's multibody (`physics: rapier`): the firmware cannot tell.
#[tokio::test(start_paused = true)]
async fn on_rapier_the_arm_holds_the_same_pose_with_the_same_torques() {
    holds_a_pose_against_gravity(sim::physics::Solver::Rapier).await;
}

async fn holds_a_pose_against_gravity(physics: sim::physics::Solver) {
    let start = [
        ("shoulder_pitch", 1.0),
        ("elbow_pitch", 0.6),
        ("wrist_pitch", 0.3),
    ];
    let config = RobotConfig {
        physics,
        ..arm_config(&start)
    };
    let rig = spawn(config);
    let targets = [0.0, 1.0, 0.6, 0.0, 0.3, 0.0];
    for (k, target) in targets.iter().enumerate() {
        let bus = usize::from(k >= 3);
        csp_hold(&rig.hosts[bus], k as u32 + 1, *target as f32).await;
    }
    tokio::time::sleep(Duration::from_secs(4)).await;
    for host in &rig.hosts {
        drain(host).await;
    }
    let snap = rig.robot.snapshot().await.unwrap();
    assert!((snap.time_s - 4.0).abs() < 0.05, "{}", snap.time_s);
    let model = ArmModel::from_urdf_str(ARM_URDF).unwrap();
    let q: Vec<f64> = snap.joints.iter().map(|j| j.position_rad).collect();
    let gravity = model.gravity_torques(&q, [0.0, 0.0, -9.81]).unwrap();
    for (k, joint) in snap.joints.iter().enumerate() {
        assert_eq!(
            joint.actuator.mode,
            ModeState::Run.name(),
            "{}",
            joint.joint
        );
        assert!(
            (joint.position_rad - targets[k]).abs() < 0.02,
            "{} at {} rad, target {}",
            joint.joint,
            joint.position_rad,
            targets[k]
        );
        // The motor carries the gravity load (our own Jacobian-transpose reference): 5 %
        // or 0.1 N·m for the nearly unloaded wrist.
        let tolerance = (0.05 * gravity[k].abs()).max(0.1);
        assert!(
            (joint.actuator.torque_nm - gravity[k]).abs() <= tolerance,
            "{}: motor torque {} N·m, gravity needs {} N·m",
            joint.joint,
            joint.actuator.torque_nm,
            gravity[k]
        );
    }
    assert!(
        gravity[1].abs() > 8.0,
        "the shoulder carries the arm: {}",
        gravity[1]
    );
    rig.robot.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn an_unpowered_arm_topples_from_upright_and_the_shorted_windings_brake_it() {
    // q = 0 is the arm straight up: unpowered, it topples forward, slowed by the drive's
    // short-circuit brake, and comes to rest on the shoulder's stop (2 rad).
    let rig = spawn(arm_config(&[("shoulder_pitch", 0.3)]));
    let mut fastest: f64 = 0.0;
    for _ in 0..30 {
        tokio::time::sleep(Duration::from_millis(100)).await;
        let snap = rig.robot.snapshot().await.unwrap();
        fastest = fastest.max(snap.joint("shoulder_pitch").unwrap().velocity_rad_s.abs());
    }
    let snap = rig.robot.snapshot().await.unwrap();
    let shoulder = snap.joint("shoulder_pitch").unwrap();
    assert_eq!(shoulder.actuator.mode, ModeState::Reset.name());
    assert!(
        (shoulder.position_rad - 2.0).abs() < 0.01,
        "on its stop: {}",
        shoulder.position_rad
    );
    assert!(
        shoulder.velocity_rad_s.abs() < 0.05,
        "at rest: {}",
        shoulder.velocity_rad_s
    );
    // A free fall of 1.7 rad would reach ~6 rad/s; the brake holds it well below.
    assert!(fastest > 0.1 && fastest < 3.0, "fastest {fastest} rad/s");
    rig.robot.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn a_lost_bus_stops_its_actuators_by_their_watchdog_and_the_others_hold() {
    let rig = spawn(arm_config(&[("shoulder_pitch", 0.5)]));
    for (k, target) in [0.0f32, 0.5, 0.0, 0.0, 0.0, 0.0].iter().enumerate() {
        let bus = usize::from(k >= 3);
        let host = &rig.hosts[bus];
        let motor = k as u32 + 1;
        // canTimeout 0x7028: 20 000 ticks = 1 s.
        send(
            host,
            ext(0x12, HOST, motor, [0x28, 0x70, 0, 0, 0x20, 0x4E, 0, 0]),
        )
        .await;
        csp_hold(host, motor, *target).await;
    }
    rig.robot.set_bus_lost("can1", true).await.unwrap();
    // The host keeps commanding both buses every 100 ms; can1's frames are lost.
    for _ in 0..30 {
        for (k, host) in rig.hosts.iter().enumerate() {
            let first = k as u32 * 3 + 1;
            for motor in first..first + 3 {
                send(host, ext(0x02, HOST, motor, [0; 8])).await;
            }
            drain(host).await;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let snap = rig.robot.snapshot().await.unwrap();
    assert_eq!(snap.lost_buses, ["can1"]);
    for joint in &snap.joints {
        let expected = if joint.bus == "can1" {
            ModeState::Reset
        } else {
            ModeState::Run
        };
        assert_eq!(
            joint.actuator.mode,
            expected.name(),
            "{} on {}",
            joint.joint,
            joint.bus
        );
    }
    let shoulder = snap.joint("shoulder_pitch").unwrap();
    assert!(
        (shoulder.position_rad - 0.5).abs() < 0.03,
        "{}",
        shoulder.position_rad
    );
    assert!(matches!(
        rig.robot.set_bus_lost("can7", true).await,
        Err(RobotError::UnknownBus { .. })
    ));
    rig.robot.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn configuration_mistakes_are_named() {
    let mut twice = arm_config(&[]);
    twice.actuators[1].actuator = ActuatorConfig::new(MotorConfig::new(1, Model::RS03));
    let nodes = || -> Vec<Arc<dyn CanBus>> {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        vec![Arc::new(bus.attach("a")), Arc::new(bus.attach("b"))]
    };
    match RobotEmulator::spawn(twice, nodes()) {
        Err(RobotError::Config(RobotConfigError::DuplicateCanId {
            bus,
            can_id: 1,
            first,
            second,
        })) => {
            assert_eq!(
                (bus.as_str(), first.as_str(), second.as_str()),
                ("can0", "shoulder_yaw", "shoulder_pitch")
            );
        }
        other => panic!("{other:?}"),
    }
    let mut unknown = arm_config(&[]);
    unknown.actuators[0].joint = "shoulder_yew".into();
    let error = RobotEmulator::spawn(unknown, nodes())
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("`shoulder_yew`") && error.contains("shoulder_yaw, shoulder_pitch"),
        "{error}"
    );
    let error = RobotEmulator::spawn(arm_config(&[]), nodes()[..1].to_vec()).unwrap_err();
    assert!(
        matches!(
            error,
            RobotError::BusCount {
                expected: 2,
                given: 1
            }
        ),
        "{error}"
    );
}

#[tokio::test(start_paused = true)]
async fn a_fault_reaches_the_joints_actuator_through_its_kinds_table() {
    let rig = spawn(arm_config(&[]));
    let error = rig
        .robot
        .inject("wrist_pitch", "melt", FaultArgs::new())
        .await
        .unwrap_err();
    assert!(
        matches!(&error, RobotError::Fault { joint, .. } if joint == "wrist_pitch"),
        "{error:?}"
    );
    assert!(error.to_string().contains("melt"), "{error}");
    let glitch = FaultArgs::new().with("counts", FaultArgValue::Number(1e6));
    let error = rig
        .robot
        .inject("wrist_pitch", "encoder_glitch", glitch)
        .await
        .unwrap_err();
    assert!(error.to_string().contains("counts"), "{error}");
    rig.robot
        .inject("wrist_pitch", "over_temperature", FaultArgs::new())
        .await
        .unwrap();
    let wrist = rig.robot.snapshot().await.unwrap();
    let wrist = &wrist.joint("wrist_pitch").unwrap().actuator;
    assert_eq!(
        (wrist.kind, wrist.faults.as_slice()),
        ("robstride", ["over_temperature".to_owned()].as_slice())
    );
    rig.robot.shutdown().await;
}

/// The shipped humanoid (20 actuators on four buses, floating base) with `gantry`.
fn humanoid(gantry: sim::robot::Gantry) -> RobotConfig {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/humanoid.yaml");
    let mut config = sim::robot::file::load_robot_file(&file)
        .expect("the humanoid loads")
        .config;
    config.gantry = gantry;
    config
}

/// Type 3: enable motor `motor`.
fn enable(motor: u32) -> CanFrame {
    ext(0x03, HOST, motor, [0; 8])
}

#[tokio::test(start_paused = true)]
async fn a_humanoid_on_its_gantry_hangs_until_every_actuator_is_enabled() {
    let config = humanoid(sim::robot::Gantry::UntilEnabled);
    let ids: Vec<(usize, u32)> = config
        .actuators
        .iter()
        .map(|a| (a.bus, a.actuator.can_id()))
        .collect();
    let rig = spawn(config);
    tokio::time::sleep(Duration::from_millis(1000)).await;
    let hanging = rig.robot.snapshot().await.unwrap();
    assert!(hanging.gantry_holds);
    // Unpowered, its legs hang and swing; the pelvis stays where the stand holds it.
    assert_eq!(hanging.base_position_m[2], 0.81);
    // Every actuator but the last enabled: still held.
    for &(bus, id) in &ids[..ids.len() - 1] {
        send(&rig.hosts[bus], enable(id)).await;
    }
    tokio::time::sleep(Duration::from_millis(50)).await;
    assert!(rig.robot.snapshot().await.unwrap().gantry_holds);
    let (bus, id) = ids[ids.len() - 1];
    send(&rig.hosts[bus], enable(id)).await;
    tokio::time::sleep(Duration::from_millis(10)).await;
    let released = rig.robot.snapshot().await.unwrap();
    assert!(!released.gantry_holds, "released once all 20 are enabled");
    // Enabled where they hung, the actuators hold that pose; the base now moves.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let after = rig.robot.snapshot().await.unwrap();
    assert_ne!(after.base_position_m[2], 0.81);
    assert!(
        !rig.robot.monitor().release_gantry().await.unwrap(),
        "nothing holds it any more"
    );
}

#[tokio::test(start_paused = true)]
async fn a_humanoid_held_until_released_falls_when_let_go() {
    let rig = spawn(humanoid(sim::robot::Gantry::UntilReleased));
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert_eq!(rig.robot.snapshot().await.unwrap().base_position_m[2], 0.81);
    assert!(rig.robot.monitor().release_gantry().await.unwrap());
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let fallen = rig.robot.snapshot().await.unwrap();
    assert!(!fallen.gantry_holds);
    assert!(
        fallen.base_position_m[2] < 0.5,
        "{:?}",
        fallen.base_position_m
    );
}

/// A state file in which a host moved the shoulder yaw's actuator (can0, ID 1) onto the
/// shoulder pitch's ID: the robot refuses to power on rather than answer twice on ID 2, and
/// the error names the bus, both joints and the file (scenarios and Python start robots
/// here, not through `armhil sim robot`).
#[tokio::test(start_paused = true)]
async fn a_state_file_putting_two_actuators_on_one_id_is_refused_at_spawn() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = dir.path().join("arm.json");
    let mut config = arm_config(&[]);
    config.state_file = Some(path.clone());
    let mut kept = sim::robstride::state_file::StateFile::default();
    let moved = config.actuators[0]
        .actuator
        .downcast_ref::<MotorConfig>()
        .expect("a RobStride actuator");
    kept.motors.insert(
        sim::robstride::state_file::uid_key(moved.effective_uid()),
        sim::robstride::PersistedMotor {
            can_id: 2,
            master_id: sim::robstride::DEFAULT_HOST_ID,
            zero_offset_rad: 0.0,
            params: Default::default(),
            baud_code: 1,
            protocol: 0,
        },
    );
    kept.save(&path).expect("state file written");
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let buses: Vec<Arc<dyn CanBus>> = (0..2)
        .map(|k| Arc::new(bus.attach(&format!("robot{k}"))) as Arc<dyn CanBus>)
        .collect();
    let error = RobotEmulator::spawn(config, buses)
        .expect_err("two actuators on ID 2 of can0")
        .to_string();
    for part in [
        "bus `can0`",
        "shoulder_yaw",
        "shoulder_pitch",
        "ID 2",
        "arm.json",
    ] {
        assert!(error.contains(part), "{part:?} missing from: {error}");
    }
}

/// The same refusal for any kind: the wrist's actuators made Damiao motors (can1, ESC_IDs 4
/// and 5), and the state file keeps the wrist pitch's motor moved to ESC_ID 4 (a host wrote
/// ESC_ID and saved): the robot refuses, naming the bus, both joints, the id and the file.
#[tokio::test(start_paused = true)]
async fn a_state_file_putting_two_damiao_motors_on_one_id_is_refused_at_spawn() {
    use sim::actuator::ActuatorFirmware;
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = dir.path().join("arm.json");
    let mut config = arm_config(&[]);
    config.state_file = Some(path.clone());
    for a in config.actuators.iter_mut().filter(|a| a.bus == 1) {
        let id = a.actuator.can_id();
        a.actuator = sim::actuator::configure("DM4310", id).expect("a Damiao model");
    }
    // What the wrist pitch's motor (ESC_ID 5) flashes after a host moved it to ESC_ID 4.
    let mut moved = sim::damiao::MotorConfig::new(4, sim::damiao::Model::DM4310);
    moved.mst_id = 0x15;
    let image = sim::damiao::DamiaoMotor::new(moved).persisted();
    let mut kept = sim::robstride::state_file::StateFile::default();
    kept.actuators.insert("damiao:can1:5".into(), image);
    kept.save(&path).expect("state file written");
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let buses: Vec<Arc<dyn CanBus>> = (0..2)
        .map(|k| Arc::new(bus.attach(&format!("robot{k}"))) as Arc<dyn CanBus>)
        .collect();
    let error = RobotEmulator::spawn(config, buses)
        .expect_err("two Damiao motors on ESC_ID 4 of can1")
        .to_string();
    for part in [
        "bus `can1`",
        "wrist_roll",
        "wrist_pitch",
        "CAN ID 4",
        "arm.json",
    ] {
        assert!(error.contains(part), "{part:?} missing from: {error}");
    }
}

/// An encoder glitch on the elbow's actuator: its loop holds the shifted reading at the
/// target, so the joint itself settles the glitch's angle away (1024 counts of 16,384: π/8),
/// while the actuator reports the target; cleared, the joint comes back.
#[tokio::test(start_paused = true)]
async fn an_encoder_glitch_moves_the_joint_by_its_angle_while_the_actuator_reads_the_target() {
    let start = [
        ("shoulder_pitch", 1.0),
        ("elbow_pitch", 0.6),
        ("wrist_pitch", 0.3),
    ];
    let rig = spawn(arm_config(&start));
    let targets = [0.0, 1.0, 0.6, 0.0, 0.3, 0.0];
    for (k, target) in targets.iter().enumerate() {
        let bus = usize::from(k >= 3);
        csp_hold(&rig.hosts[bus], k as u32 + 1, *target as f32).await;
    }
    tokio::time::sleep(Duration::from_secs(2)).await;
    let elbow = |snap: &sim::robot::RobotSnapshot| {
        let j = snap.joint("elbow_pitch").expect("the elbow");
        (j.position_rad, j.actuator.angle_rad)
    };
    let (held, _) = elbow(&rig.robot.snapshot().await.unwrap());
    assert!((held - 0.6).abs() < 0.02, "held at {held}");
    rig.robot
        .inject(
            "elbow_pitch",
            "encoder_glitch",
            FaultArgs::new().with("counts", FaultArgValue::Number(1024.0)),
        )
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_secs(3)).await;
    let (truth, reading) = elbow(&rig.robot.snapshot().await.unwrap());
    let glitch = std::f64::consts::PI / 8.0;
    assert!(
        (truth - (0.6 - glitch)).abs() < 0.02,
        "the joint at {truth}, expected {}",
        0.6 - glitch
    );
    assert!((reading - 0.6).abs() < 0.02, "the actuator reads {reading}");
    rig.robot
        .clear("elbow_pitch", "encoder_glitch", FaultArgs::new())
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_secs(3)).await;
    let (back, _) = elbow(&rig.robot.snapshot().await.unwrap());
    assert!((back - 0.6).abs() < 0.02, "back at {back}");
    for host in &rig.hosts {
        drain(host).await;
    }
    rig.robot.shutdown().await;
}

/// A humanoid hanging unpowered on its gantry settles and then rests: its world is no longer
/// stepped (time goes on, the pose stands exactly), and a torque from an actuator wakes it
/// and moves the joint as before.
#[test]
fn a_robot_at_rest_is_not_stepped_until_a_torque_changes() {
    use sim::robstride::Plant as _;
    let config = humanoid(sim::robot::Gantry::UntilEnabled);
    let elbow = config
        .actuators
        .iter()
        .position(|a| a.joint == "left_elbow")
        .expect("a left elbow");
    let (mut world, mut plants) = sim::robot::RobotWorld::new(&config).expect("the world");
    for _ in 0..6000 {
        world.step().expect("finite");
    }
    let stepped = world.world().steps();
    assert!(stepped < 6000, "it came to rest: {stepped} steps of 6000");
    let pose = world.world().joint_positions();
    for _ in 0..1000 {
        world.step().expect("finite");
    }
    assert_eq!(world.world().steps(), stepped, "at rest, not stepped");
    assert_eq!(world.world().joint_positions(), pose);
    assert!((world.time_s() - 7.0).abs() < 1e-9, "{}", world.time_s());
    // The elbow's actuator pushes: the world wakes and the elbow moves.
    let index = world.joint_index(elbow).expect("its world joint");
    for _ in 0..200 {
        plants[elbow].step(2.0, 0.001);
        world.step().expect("finite");
    }
    assert!(world.world().steps() > stepped);
    let moved = world.world().joint_positions()[index] - pose[index];
    assert!(moved.abs() > 0.01, "the elbow moved {moved} rad");
}
