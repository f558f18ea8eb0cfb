//! The laws every [`Solver`] obeys, on the URDFs the project ships: one suite run against
//! both implementations of [`World`], so that a robot file's `physics:` changes the cost and
//! the numerics of a run, never its physics. Each law prints its figure per solver and URDF
//! (`cargo test -p armhil-sim conformance -- --nocapture`).
//!
//! Contacts are held to one law (a dropped robot rests on the ground), though their shape is
//! not part of [`World`]: the articulated solver has the ground plane, rapier's world an
//! obstacle standing in for it.

use nalgebra::{DVector, Point3};

use super::{Solver, World, WorldConfig, DEFAULT_GRAVITY_M_S2};
use crate::description::Description;

const PIPER: &str = include_str!("../../../urdf/piper.urdf");
const RM65B: &str = include_str!("../../../urdf/rm65b.urdf");
const RM75B: &str = include_str!("../../../urdf/rm75b.urdf");
const ARM6: &str = include_str!("../../../urdf/robstride_arm6.urdf");
const RIG: &str = include_str!("../../../urdf/robstride_rig.urdf");
const HUMANOID: &str = include_str!("../../../urdf/humanoid.urdf");

/// The shipped URDFs, by name.
const SHIPPED: [(&str, &str); 6] = [
    ("piper", PIPER),
    ("rm65b", RM65B),
    ("rm75b", RM75B),
    ("robstride_arm6", ARM6),
    ("robstride_rig", RIG),
    ("humanoid", HUMANOID),
];

fn load(solver: Solver, urdf: &str, config: WorldConfig) -> Box<dyn World> {
    let (description, geometry) =
        Description::load_for_physics(urdf.to_owned(), Default::default()).expect("a URDF");
    solver
        .load(&description, &geometry, config)
        .unwrap_or_else(|e| panic!("{} loads: {e}", solver.word()))
}

fn fixed(solver: Solver, urdf: &str) -> Box<dyn World> {
    load(solver, urdf, WorldConfig::default())
}

/// `urdf` with no damping and no friction (`<dynamics>` attributes renamed away).
fn undamped(urdf: &str) -> String {
    urdf.replace("damping=", "data-damping=")
        .replace("friction=", "data-friction=")
}

/// `urdf` with no damping, no friction and limits so far out that no joint reaches a stop
/// (stops are inelastic): a conservative system.
pub(super) fn conservative(urdf: &str) -> String {
    let mut out = undamped(urdf);
    for (attribute, value) in [("lower=\"", "-100"), ("upper=\"", "100")] {
        let mut rest = out.as_str();
        let mut done = String::with_capacity(out.len());
        while let Some(at) = rest.find(attribute) {
            let start = at + attribute.len();
            let end = start + rest[start..].find('"').expect("a closing quote");
            done.push_str(&rest[..start]);
            done.push_str(value);
            rest = &rest[end..];
        }
        done.push_str(rest);
        out = done;
    }
    out
}

/// A pose inside every joint's limits, different per joint, away from the stops.
fn pose(world: &dyn World) -> Vec<f64> {
    world
        .joints()
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let t = ((i * 7 % 11) as f64 / 10.0) * 0.6 + 0.2;
            let (lo, hi) = (j.lower.max(-3.0), j.upper.min(3.0));
            lo + (hi - lo) * t
        })
        .collect()
}

/// Mass-weighted height of every link (m) times the total mass: the potential energy over g.
fn mass_height(world: &dyn World) -> f64 {
    let model = world.model();
    let poses = model.link_poses(&world.joint_positions()).expect("a pose");
    poses
        .iter()
        .zip(model.inertials())
        .map(|(pose, inertial)| (pose * Point3::from(inertial.com_m)).z * inertial.mass_kg)
        .sum()
}

/// Joints that lead (no mimic of their own): the ones a test drives.
fn leaders(world: &dyn World) -> Vec<usize> {
    (0..world.joints().len())
        .filter(|&i| world.joints()[i].mimic.is_none())
        .collect()
}

/// The model's gravity torques, computed without either solver, hold every shipped arm still
/// in a pose away from its stops, with damping and friction taken out (which would hold it by
/// themselves): each solver's gravity is the model's. Without them, the same arm moves.
#[test]
fn the_models_gravity_torques_hold_every_arm_still() {
    for (name, urdf) in SHIPPED {
        let urdf = conservative(urdf);
        for solver in Solver::ALL {
            let drift = |hold: bool| {
                let mut world = fixed(solver, &urdf);
                let q = pose(world.as_ref());
                world.set_joint_positions(&q).expect("a pose");
                let q = world.joint_positions();
                let torques = world
                    .model()
                    .gravity_torques(&q, DEFAULT_GRAVITY_M_S2)
                    .expect("torques");
                let torques = if hold { torques } else { vec![0.0; q.len()] };
                let mut drift = 0.0_f64;
                for _ in 0..500 {
                    world.step(&torques);
                    for (got, want) in world.joint_positions().iter().zip(&q) {
                        drift = drift.max((got - want).abs());
                    }
                }
                world.check_finite().expect("finite");
                drift
            };
            let (held, let_go) = (drift(true), drift(false));
            println!(
                "conformance: gravity hold  {name:<15} {:<11} drift {held:.2e} rad in 0.5 s ({let_go:.2} let go)",
                solver.word()
            );
            assert!(held < 2e-3, "{name} on {}: drifted {held}", solver.word());
            assert!(
                let_go > 0.05,
                "{name} on {}: gravity moved nothing",
                solver.word()
            );
        }
    }
}

/// With damping, friction and stops taken out, an arm swinging under gravity keeps its energy
/// (kinetic by the model's mass matrix plus potential): within 5 % of the peak kinetic energy
/// over a second. (Both integrate semi-implicitly at 1 ms; rapier's single solver iteration
/// drifts more than the articulated solver's two substeps: see the printed figures.)
#[test]
fn an_arm_swinging_without_damping_keeps_its_energy() {
    for (name, urdf) in [("robstride_arm6", ARM6), ("rm65b", RM65B), ("rm75b", RM75B)] {
        let urdf = conservative(urdf);
        for solver in Solver::ALL {
            let mut world = fixed(solver, &urdf);
            let mut q = vec![0.0; world.joints().len()];
            q[1] = 1.0;
            world.set_joint_positions(&q).expect("a pose");
            let g = -DEFAULT_GRAVITY_M_S2[2];
            let energy = |w: &dyn World| {
                let q = w.joint_positions();
                let qd = DVector::from_vec(w.joint_velocities());
                let m = w.model().mass_matrix(&q).expect("a mass matrix");
                0.5 * qd.dot(&(m * &qd)) + g * mass_height(w)
            };
            let start = energy(world.as_ref());
            let (mut peak_kinetic, mut drift) = (0.0_f64, 0.0_f64);
            for _ in 0..1000 {
                world.step(&[]);
                let e = energy(world.as_ref());
                peak_kinetic = peak_kinetic.max(e - g * mass_height(world.as_ref()));
                drift = drift.max((e - start).abs());
            }
            let share = drift / peak_kinetic;
            println!(
                "conformance: energy        {name:<15} {:<11} drift {:.3} % of {peak_kinetic:.1} J in 1 s",
                solver.word(),
                share * 100.0
            );
            assert!(peak_kinetic > 1.0, "{name}: it swings ({peak_kinetic} J)");
            assert!(
                share < 0.05,
                "{name} on {}: energy drifted {drift} J",
                solver.word()
            );
        }
    }
}

/// A joint pushed into its upper stop, the others held where they are, ends on the stop: not
/// past it and not short of it. (Damping and friction taken out: on a light wrist the URDF's
/// damping outweighs a loop sized by the link's own inertia.)
#[test]
fn a_joint_pushed_into_its_stop_rests_on_it() {
    for (name, urdf) in [("robstride_arm6", ARM6), ("rm65b", RM65B), ("piper", PIPER)] {
        let urdf = undamped(urdf);
        let urdf = urdf.as_str();
        for solver in Solver::ALL {
            let mut worst_past = 0.0_f64;
            let mut worst_short = 0.0_f64;
            let probe = fixed(solver, urdf);
            for joint in leaders(probe.as_ref()) {
                let info = probe.joints()[joint].clone();
                if info.upper - info.lower > 10.0 {
                    continue; // continuous: no stop
                }
                let mut world = fixed(solver, urdf);
                let q = pose(world.as_ref());
                world.set_joint_positions(&q).expect("a pose");
                let q = world.joint_positions();
                for _ in 0..1000 {
                    let now = world.joint_positions();
                    let speed = world.joint_velocities();
                    let inertia = world.mass_matrix_diagonal();
                    let mut tau = world
                        .model()
                        .gravity_torques(&now, DEFAULT_GRAVITY_M_S2)
                        .expect("torques");
                    for (i, t) in tau.iter_mut().enumerate() {
                        // Stiffness and damping for a 5 Hz loop on each joint's own inertia:
                        // the others held at their pose, this one pushed towards a target
                        // well past its stop.
                        let omega = 2.0 * std::f64::consts::PI * 5.0;
                        let target = if i == joint { info.upper + 0.5 } else { q[i] };
                        *t += inertia[i]
                            * (omega * omega * (target - now[i]) - 2.0 * omega * speed[i]);
                    }
                    world.step(&tau);
                }
                world.check_finite().expect("finite");
                let at = world.joint_positions()[joint];
                worst_past = worst_past.max(at - info.upper);
                worst_short = worst_short.max(info.upper - at);
            }
            println!(
                "conformance: joint stop    {name:<15} {:<11} past {worst_past:.1e}, short {worst_short:.1e} (rad or m)",
                solver.word()
            );
            assert!(
                worst_past <= 1e-3,
                "{name} on {}: {worst_past} past a stop",
                solver.word()
            );
            assert!(
                worst_short <= 2e-2,
                "{name} on {}: {worst_short} short of a stop",
                solver.word()
            );
        }
    }
}

/// The Piper's second finger mimics its first: whatever the leader does, the follower sits at
/// multiplier · leader + offset.
#[test]
fn a_mimic_follower_sits_where_its_leader_puts_it() {
    for solver in Solver::ALL {
        let mut world = fixed(solver, PIPER);
        let (follower, mimic) = world
            .joints()
            .iter()
            .enumerate()
            .find_map(|(i, j)| Some((i, j.mimic.clone()?)))
            .expect("the Piper's fingers mimic");
        let leader = mimic.leader_index;
        let q = pose(world.as_ref());
        world.set_joint_positions(&q).expect("a pose");
        let (mut worst, mut travel) = (0.0_f64, 0.0_f64);
        let start = world.joint_positions()[leader];
        let effort = world.joints()[leader].effort_limit;
        for step in 0..400 {
            let now = world.joint_positions();
            let mut tau = world
                .model()
                .gravity_torques(&now, DEFAULT_GRAVITY_M_S2)
                .expect("torques");
            tau[leader] += if step < 200 { 0.3 } else { -0.3 } * effort;
            world.step(&tau);
            let q = world.joint_positions();
            worst = worst.max((q[follower] - (mimic.multiplier * q[leader] + mimic.offset)).abs());
            travel = travel.max((q[leader] - start).abs());
        }
        println!(
            "conformance: mimic         piper           {:<11} off by {worst:.1e} over {travel:.4} of travel",
            solver.word()
        );
        assert!(
            travel > 1e-3,
            "{}: the leader moved {travel}",
            solver.word()
        );
        assert!(
            worst < 1e-4,
            "{}: the follower was off by {worst}",
            solver.word()
        );
    }
}

/// A floating humanoid far above anything falls at g, its joints unmoved.
#[test]
fn a_free_robot_falls_at_g() {
    for solver in Solver::ALL {
        let config = WorldConfig {
            floating_base_height_m: Some(100.0),
            ..WorldConfig::default()
        };
        let mut world = load(solver, HUMANOID, config);
        let q = pose(world.as_ref());
        world.set_joint_positions(&q).expect("a pose");
        let q = world.joint_positions();
        let height = |w: &dyn World| {
            w.link_pose(w.model().root_link_name())
                .expect("the root")
                .translation
                .z
        };
        let start = height(world.as_ref());
        for _ in 0..200 {
            world.step(&[]);
        }
        let t = 0.2;
        let exact = -DEFAULT_GRAVITY_M_S2[2] * t * t / 2.0;
        let fallen = start - height(world.as_ref());
        let joints_moved = world
            .joint_positions()
            .iter()
            .zip(&q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "conformance: free fall     humanoid        {:<11} {fallen:.5} m in 0.2 s (g·t²/2 = {exact:.5}), joints moved {joints_moved:.1e}",
            solver.word()
        );
        assert!(
            (fallen - exact).abs() < 0.005 * exact,
            "{}: fell {fallen} m, not {exact}",
            solver.word()
        );
        assert!(
            joints_moved < 1e-3,
            "{}: joints moved {joints_moved}",
            solver.word()
        );
    }
}

/// Both solvers load every shipped URDF with the same joints in the same order, and agree on
/// each joint's inertia at the start pose (the model's composite inertia).
#[test]
fn both_solvers_see_the_same_joints() {
    for (name, urdf) in SHIPPED {
        let worlds: Vec<Box<dyn World>> = Solver::ALL.iter().map(|&s| fixed(s, urdf)).collect();
        let names = |w: &dyn World| {
            w.joints()
                .iter()
                .map(|j| j.name.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(
            names(worlds[0].as_ref()),
            names(worlds[1].as_ref()),
            "{name}"
        );
        let (a, b) = (
            worlds[0].mass_matrix_diagonal(),
            worlds[1].mass_matrix_diagonal(),
        );
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(1.0),
                "{name}: {a:?} vs {b:?}"
            );
        }
    }
}

/// Contacts: the humanoid dropped unpowered from 0.9 m comes down onto the ground, its
/// lowest collision point on the plane z = 0 (the articulated solver's ground; rapier's, a
/// slab obstacle whose top is that plane), neither through it nor above it.
#[test]
fn a_dropped_robot_comes_to_rest_on_the_ground() {
    use crate::physics::{ObstacleShape, RapierWorld};
    let (description, geometry) =
        Description::load_for_physics(HUMANOID.to_owned(), Default::default()).expect("a URDF");
    let config = WorldConfig {
        floating_base_height_m: Some(0.9),
        ..WorldConfig::default()
    };
    for solver in Solver::ALL {
        let mut world: Box<dyn World> = match solver {
            Solver::Rapier => {
                let mut world = RapierWorld::from_description(&description, &geometry, config)
                    .expect("the humanoid loads");
                world.add_obstacle(
                    ObstacleShape::Box {
                        half_extents_m: [5.0, 5.0, 0.5],
                    },
                    [0.0, 0.0, -0.5],
                );
                Box::new(world)
            }
            Solver::Articulated => solver.load(&description, &geometry, config).expect("loads"),
        };
        for _ in 0..3000 {
            world.step(&[]);
        }
        world.check_finite().expect("finite");
        let poses: Vec<_> = world
            .model()
            .link_names()
            .iter()
            .map(|name| world.link_pose(name).expect("a link"))
            .collect();
        let (_, lowest) = geometry.lowest_point(&poses).expect("collision shapes");
        let root = world.model().root_link_name().to_owned();
        let base = world.link_pose(&root).expect("the root").translation.z;
        println!(
            "conformance: contacts      humanoid        {:<11} lowest point {lowest:+.4} m, pelvis at {base:.3} m after 3 s",
            solver.word()
        );
        assert!(
            lowest.abs() < 0.01,
            "{}: lowest collision point at {lowest} m",
            solver.word()
        );
        assert!(base < 0.85, "{}: it came down ({base} m)", solver.word());
    }
}
