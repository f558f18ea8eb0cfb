//! Whole robots from their robot files, driven by our RobStride driver on every bus (virtual
//! buses, paused clock): the humanoid stands while its 20 actuators hold and falls when they
//! do not.

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::CanBus;
use driver::robstride::{DriverConfig, Model as DModel, OpControl, RobstrideDriver};
use sim::robot::{RobotEmulator, RobotHandle, RobotSnapshot};

/// The robot of `robots/NAME.yaml` on virtual buses, and a driver per bus.
fn start(name: &str) -> (RobotHandle, Vec<RobstrideDriver>, Vec<VirtualBus>) {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("robots/{name}.yaml"));
    let loaded = armhil::robots::load_robot_file(&file).expect("the robot file loads");
    let buses: Vec<VirtualBus> = loaded
        .config
        .buses
        .iter()
        .map(|_| VirtualBus::new(VirtualBusConfig::default()))
        .collect();
    let nodes = buses
        .iter()
        .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
        .collect();
    let robot = RobotEmulator::spawn(loaded.config, nodes).expect("the robot starts");
    let drivers = buses
        .iter()
        .map(|b| {
            let host: Arc<dyn CanBus> = Arc::new(b.attach("host"));
            RobstrideDriver::new(host, DriverConfig::default())
        })
        .collect();
    (robot, drivers, buses)
}

fn driver_model(model: &str) -> DModel {
    model.parse().expect("the driver knows every model")
}

/// Every actuator of the snapshot enabled in operation control (the private protocol's MIT
/// mode), holding where it is with stiffness `kp` and damping `kd`: the legs first, as they
/// carry the robot (until its drive is enabled a joint is held only by its shorted windings).
async fn hold_all(snapshot: &RobotSnapshot, drivers: &[RobstrideDriver], bus_names: &[&str]) {
    let legs_first = snapshot
        .joints
        .iter()
        .filter(|j| j.bus == "can2" || j.bus == "can3")
        .chain(
            snapshot
                .joints
                .iter()
                .filter(|j| j.bus == "can0" || j.bus == "can1"),
        );
    for joint in legs_first {
        let bus = bus_names.iter().position(|b| *b == joint.bus).unwrap();
        let motor = drivers[bus]
            .motor(
                joint.actuator.can_id as u8,
                driver_model(joint.actuator.model),
            )
            .unwrap();
        let leg = joint.bus == "can2" || joint.bus == "can3";
        motor.enable().await.unwrap();
        motor
            .op_control(OpControl {
                angle_rad: joint.actuator.angle_rad as f32,
                speed_rad_s: 0.0,
                kp: if leg { 300.0 } else { 50.0 },
                kd: if leg { 5.0 } else { 1.0 },
                torque_nm: 0.0,
            })
            .await
            .unwrap();
    }
}

#[tokio::test(start_paused = true)]
async fn the_unpowered_humanoid_falls_and_comes_to_rest_on_the_ground() {
    let (robot, _drivers, _buses) = start("humanoid");
    let first = robot.snapshot().await.unwrap();
    assert_eq!(first.joints.len(), 20);
    assert!((first.base_position_m[2] - 0.81).abs() < 1e-6, "{first:?}");
    let mut lowest: f64 = 1.0;
    for _ in 0..50 {
        tokio::time::sleep(Duration::from_millis(100)).await;
        let s = robot.snapshot().await.unwrap();
        lowest = lowest.min(s.base_position_m[2]);
    }
    let fallen = robot.snapshot().await.unwrap();
    assert!(
        fallen.base_position_m[2] < 0.4,
        "the pelvis came down: {:?}",
        fallen.base_position_m
    );
    assert!(
        fallen.base_position_m[2] > 0.0 && lowest > 0.0,
        "above the ground: {lowest}"
    );
    let moving = fallen
        .joints
        .iter()
        .map(|j| j.velocity_rad_s.abs())
        .fold(0.0, f64::max);
    assert!(moving < 0.5, "and came to rest: {moving} rad/s");
    robot.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn the_humanoid_stands_while_its_20_actuators_hold_in_operation_control() {
    let (robot, drivers, _buses) = start("humanoid");
    let first = robot.snapshot().await.unwrap();
    hold_all(&first, &drivers, &["can0", "can1", "can2", "can3"]).await;
    tokio::time::sleep(Duration::from_secs(5)).await;
    let standing = robot.snapshot().await.unwrap();
    let [x, y, z] = standing.base_position_m;
    // The soles are 0.806 m below the pelvis in the start pose, which began 4 mm higher.
    assert!((z - 0.805).abs() < 0.005, "the pelvis stays up: {z} m");
    assert!(x.abs() < 0.02 && y.abs() < 0.02, "and in place: {x} {y}");
    for (joint, start) in standing.joints.iter().zip(&first.joints) {
        assert!(joint.actuator.enabled, "{}", joint.joint);
        // kp 300 N·m/rad: the knees carrying the body sag by its torque / kp (~0.02 rad).
        let sag = joint.actuator.torque_nm.abs() / 300.0;
        assert!(
            (joint.position_rad - start.position_rad).abs() < 0.005 + sag
                && joint.velocity_rad_s.abs() < 0.05,
            "{} holds {}: {joint:?}",
            joint.joint,
            start.position_rad
        );
    }
    let knee = standing.joint("left_knee").unwrap();
    assert!(
        knee.actuator.torque_nm.abs() > 2.0,
        "the bent knee carries weight: {knee:?}"
    );
    robot.shutdown().await;
}
