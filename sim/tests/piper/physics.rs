//! Physics acceptance tests of the Piper model in the rapier world.
//!
//! - Holding torques: a PD + integral controller holds the arm still at three poses; the
//!   torque it settles on for J2 and J3 must agree within 5 % with the gravity torque computed
//!   from the URDF inertials by our own Jacobian-transpose code (no rapier). That comparison
//!   runs without the joints' dry friction, which would let the arm stand still with any
//!   torque within ±friction of the gravity torque.
//! - Joint limits: a torque-limited PD controller driving a joint toward a target past its
//!   limit never takes it past the URDF limit.

use sim::physics::{JointInfo, RapierWorld, WorldConfig};
use sim::piper::kinematics::PIPER_URDF;

/// Per-joint PD + integral gains (kp N·m/rad, kd N·m·s/rad, ki N·m/(rad·s)), scaled to each
/// joint's inertia so an explicit 1 kHz loop stays stable (the wrist links weigh grams·m²).
const GAINS: [(f64, f64, f64); 8] = [
    (300.0, 8.0, 600.0),
    (300.0, 8.0, 600.0),
    (300.0, 8.0, 600.0),
    (20.0, 0.3, 40.0),
    (20.0, 0.3, 40.0),
    (20.0, 0.3, 40.0),
    (200.0, 2.0, 400.0),
    (200.0, 2.0, 400.0),
];

struct Controller {
    target: Vec<f64>,
    integral: Vec<f64>,
    dt_s: f64,
}

impl Controller {
    fn new(target: &[f64], dt_s: f64) -> Self {
        Self {
            target: target.to_vec(),
            integral: vec![0.0; target.len()],
            dt_s,
        }
    }

    /// PD + integral torque, clamped to each joint's URDF effort limit (with anti-windup).
    fn torques(&mut self, q: &[f64], v: &[f64], joints: &[JointInfo]) -> Vec<f64> {
        (0..q.len())
            .map(|i| {
                let (kp, kd, ki) = GAINS[i];
                let error = self.target[i] - q[i];
                let unclamped =
                    kp * error - kd * v[i] + ki * (self.integral[i] + error * self.dt_s);
                let limit = joints[i].effort_limit;
                if unclamped.abs() < limit {
                    self.integral[i] += error * self.dt_s;
                }
                unclamped.clamp(-limit, limit)
            })
            .collect()
    }
}

fn piper_world() -> RapierWorld {
    RapierWorld::from_urdf_str(PIPER_URDF, WorldConfig::default()).expect("the Piper URDF loads")
}

/// The Piper world with every `<dynamics friction>` set to 0.
fn frictionless_piper_world() -> RapierWorld {
    let mut urdf = String::with_capacity(PIPER_URDF.len());
    let mut rest = PIPER_URDF;
    while let Some(i) = rest.find("friction=\"") {
        let value_start = i + "friction=\"".len();
        urdf.push_str(&rest[..value_start]);
        urdf.push('0');
        let Some(end) = rest[value_start..].find('"') else {
            break;
        };
        rest = &rest[value_start + end..];
    }
    urdf.push_str(rest);
    let world = RapierWorld::from_urdf_str(&urdf, WorldConfig::default()).expect("loads");
    assert!(world.joints().iter().all(|j| j.friction == 0.0));
    world
}

/// Holds `pose` for 3 s and returns the mean controller torque over the last 0.5 s and the
/// largest position error over that window.
fn settle_holding_torques(world: &mut RapierWorld, pose: &[f64]) -> (Vec<f64>, f64) {
    world.set_joint_positions(pose).expect("pose within limits");
    let joints = world.joints().to_vec();
    let mut controller = Controller::new(pose, world.config().step_s);
    let total_steps = 3000;
    let window = 500;
    let mut sum = vec![0.0; pose.len()];
    let mut worst_error: f64 = 0.0;
    for k in 0..total_steps {
        let tau = controller.torques(&world.joint_positions(), &world.joint_velocities(), &joints);
        world.step(&tau);
        if k >= total_steps - window {
            for (s, t) in sum.iter_mut().zip(&tau) {
                *s += t / window as f64;
            }
            let q = world.joint_positions();
            for i in 0..6 {
                worst_error = worst_error.max((q[i] - pose[i]).abs());
            }
        }
    }
    (sum, worst_error)
}

#[test]
fn holding_torques_of_j2_and_j3_match_the_urdf_inertials() {
    let poses: [[f64; 8]; 3] = [
        [0.0, 1.0, -1.0, 0.0, 0.3, 0.0, 0.0, 0.0],
        [0.5, 1.6, -0.6, 0.3, -0.4, 0.2, 0.01, -0.01],
        [-0.8, 0.6, -1.8, -0.5, 0.6, 1.0, 0.02, -0.02],
    ];
    for pose in poses {
        let mut world = frictionless_piper_world();
        let reference = world.gravity_torques(&pose).expect("valid pose");
        let (held, worst_error) = settle_holding_torques(&mut world, &pose);
        assert!(worst_error < 1e-3, "arm not held still: {worst_error} rad");
        for j in [1, 2] {
            let rel = (held[j] - reference[j]).abs() / reference[j].abs();
            eprintln!(
                "pose {pose:?} J{}: controller {:.4} N·m, URDF inertials {:.4} N·m, diff {:.3} %",
                j + 1,
                held[j],
                reference[j],
                100.0 * rel
            );
            assert!(
                reference[j].abs() > 0.3,
                "pose gives too small a load to compare"
            );
            assert!(rel < 0.05, "J{}: {} vs {}", j + 1, held[j], reference[j]);
        }
    }
}

/// Drives joint `joint` toward `target` (past its limit) with the clamped PD controller while
/// holding the others, and returns the extreme position it reached (the minimum if the target
/// is below the lower limit, the maximum otherwise).
fn drive_past_limit(joint: usize, start: &[f64], target: f64) -> (f64, JointInfo) {
    let mut world = piper_world();
    world
        .set_joint_positions(start)
        .expect("start within limits");
    let info = world.joints()[joint].clone();
    let joints = world.joints().to_vec();
    let mut goal = start.to_vec();
    goal[joint] = target;
    let mut controller = Controller::new(&goal, world.config().step_s);
    let below = target < info.lower;
    let mut extreme = start[joint];
    for _ in 0..3000 {
        let tau = controller.torques(&world.joint_positions(), &world.joint_velocities(), &joints);
        world.step(&tau);
        let q = world.joint_positions()[joint];
        extreme = if below {
            extreme.min(q)
        } else {
            extreme.max(q)
        };
    }
    (extreme, info)
}

#[test]
fn torque_limited_pd_never_drives_a_joint_past_its_urdf_limit() {
    // The world keeps joints on their stops; allow only f32 rounding (rapier works in f32).
    let tolerance = 1e-5;
    let home = [0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let cases = [
        (0, 3.5),  // J1 past +150°
        (1, -0.6), // J2 below 0, with gravity
        (2, 0.5),  // J3 above 0
        (3, -2.5), // J4 past −89° (8 N·m motor)
        (5, 4.0),  // J6 past +180°
        (6, 0.06), // gripper finger past 35 mm
    ];
    for (joint, target) in cases {
        let (extreme, info) = drive_past_limit(joint, &home, target);
        eprintln!(
            "{}: target {target}, limits [{:.4}, {:.4}], reached {extreme:.5}",
            info.name, info.lower, info.upper
        );
        if target < info.lower {
            assert!(
                extreme >= info.lower - tolerance,
                "{}: {extreme}",
                info.name
            );
            assert!(
                extreme < info.lower + 0.05,
                "{} did not reach its stop",
                info.name
            );
        } else {
            assert!(
                extreme <= info.upper + tolerance,
                "{}: {extreme}",
                info.name
            );
            assert!(
                extreme > info.upper - 0.05 * info.upper.abs().max(0.1),
                "{} did not reach its stop",
                info.name
            );
        }
    }
}

#[test]
fn arm_stops_on_an_obstacle_and_reports_the_touching_link() {
    let mut world = piper_world();
    let home = [0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    world
        .set_joint_positions(&home)
        .expect("home within limits");
    // A post where the gripper would be after turning J1 by +0.6 rad.
    let mut turned = home;
    turned[0] = 0.6;
    let gripper = world
        .model()
        .link_pose("gripper_base", &turned)
        .expect("valid pose")
        .expect("gripper_base exists");
    let p = gripper * nalgebra::Point3::new(0.0, 0.0, 0.06);
    let post = world.add_obstacle(
        sim::physics::ObstacleShape::Cylinder {
            radius_m: 0.03,
            half_height_m: 0.3,
        },
        [p.x, p.y, p.z],
    );
    assert!(world.contacts().is_empty(), "{:?}", world.contacts());
    let mut goal = home;
    goal[0] = 1.2;
    let joints = world.joints().to_vec();
    let mut controller = Controller::new(&goal, world.config().step_s);
    for _ in 0..3000 {
        let tau = controller.torques(&world.joint_positions(), &world.joint_velocities(), &joints);
        world.step(&tau);
    }
    let q1 = world.joint_positions()[0];
    assert!(q1 > 0.2 && q1 < 0.6, "J1 blocked by the post, at {q1}");
    let contacts = world.contacts();
    assert!(!contacts.is_empty());
    let hand = ["link5", "link6", "gripper_base", "link7", "link8"];
    for c in &contacts {
        assert_eq!(c.obstacle, post);
        assert!(hand.contains(&c.link.as_str()), "{c:?}");
    }
    assert!(
        contacts.iter().any(|c| c.normal_force_n > 1.0),
        "{contacts:?}"
    );
    eprintln!("J1 stopped at {q1:.3} rad; contacts {contacts:?}");
}
