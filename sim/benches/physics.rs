//! Cost of one 1 kHz step of the Piper world (6 joints + 2 fingers, gravity, a PD controller
//! computing the torques), in µs per step. Run with `cargo bench -p armhil-sim --bench physics`.

use std::hint::black_box;
use std::time::Instant;

use sim::physics::articulated::{ArticulatedWorld, SUBSTEPS};
use sim::physics::{ObstacleShape, RapierWorld, WorldConfig};
use sim::piper::kinematics::PIPER_URDF;

fn measure(label: &str, world: &mut RapierWorld, steps: usize) {
    let target = world.joint_positions();
    let start = Instant::now();
    for _ in 0..steps {
        let q = world.joint_positions();
        let v = world.joint_velocities();
        let mut tau = world
            .gravity_torques(&q)
            .unwrap_or_else(|_| vec![0.0; q.len()]);
        for i in 0..tau.len() {
            tau[i] += 20.0 * (target[i] - q[i]) - 0.3 * v[i];
        }
        world.step(black_box(&tau));
    }
    let elapsed = start.elapsed();
    let per_step_us = elapsed.as_secs_f64() * 1e6 / steps as f64;
    println!("{label}: {steps} steps in {elapsed:.3?} = {per_step_us:.2} µs/step");
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let steps = 20_000;
    let pose = [0.2, 1.2, -1.1, 0.1, 0.4, 0.0, 0.01, -0.01];

    let mut world = RapierWorld::from_urdf_str(PIPER_URDF, WorldConfig::default())?;
    world.set_joint_positions(&pose)?;
    measure(
        "piper, free space, PD + gravity feed-forward",
        &mut world,
        steps,
    );

    let mut world = RapierWorld::from_urdf_str(PIPER_URDF, WorldConfig::default())?;
    world.set_joint_positions(&pose)?;
    world.add_obstacle(
        ObstacleShape::Box {
            half_extents_m: [0.5, 0.5, 0.01],
        },
        [0.0, 0.0, -0.011],
    );
    world.add_obstacle(ObstacleShape::Sphere { radius_m: 0.05 }, [0.35, 0.0, 0.2]);
    measure("piper, two obstacles", &mut world, steps);

    let mut world = RapierWorld::from_urdf_str(PIPER_URDF, WorldConfig::default())?;
    world.set_joint_positions(&pose)?;
    let zero = vec![0.0; world.joints().len()];
    let start = Instant::now();
    for _ in 0..steps {
        world.step(black_box(&zero));
    }
    let per_step_us = start.elapsed().as_secs_f64() * 1e6 / steps as f64;
    println!("piper, falling under gravity, no torques: {per_step_us:.2} µs/step (step only)");

    humanoid_on_the_ground()?;
    Ok(())
}

/// The unpowered humanoid (floating base, 20 joints, ground contact) falling and lying for
/// 10 s, in each physics: rapier's multibody (what `RapierWorld` builds) and the articulated-body
/// solver (`ArticulatedWorld`).
fn humanoid_on_the_ground() -> Result<(), Box<dyn std::error::Error>> {
    const URDF: &str = include_str!("../../urdf/humanoid.urdf");
    let steps = 10_000;
    let config = WorldConfig {
        floating_base_height_m: Some(0.81),
        ..WorldConfig::default()
    };
    let mut world = RapierWorld::from_urdf_str(URDF, config)?;
    world.add_obstacle(
        ObstacleShape::Box {
            half_extents_m: [50.0, 50.0, 0.5],
        },
        [0.0, 0.0, -0.5],
    );
    let zero = vec![0.0; world.joints().len()];
    let start = Instant::now();
    for _ in 0..steps {
        world.step(black_box(&zero));
    }
    let rapier_us = start.elapsed().as_secs_f64() * 1e6 / steps as f64;
    println!("humanoid on the ground, rapier multibody: {rapier_us:.1} µs/step");

    let mut world = ArticulatedWorld::from_urdf_str(URDF, config)?;
    let start = Instant::now();
    for _ in 0..steps {
        world.step(black_box(&zero));
    }
    let aba_us = start.elapsed().as_secs_f64() * 1e6 / steps as f64;
    println!(
        "humanoid on the ground, articulated-body solver ({SUBSTEPS} substeps): {aba_us:.1} µs/step ({:.1}x faster)",
        rapier_us / aba_us
    );
    Ok(())
}
