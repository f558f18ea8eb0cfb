//! Cost of the Realman motion core: one 1 kHz plant step (rapier world + computed-torque PD),
//! one IK solve seeded near the answer, and planning a 0.2 m `movel`. Prints µs / ms figures.
//! Run with `cargo bench -p armhil-sim --bench realman_core`.

use std::hint::black_box;
use std::time::Instant;

use sim::realman::kinematics::{forward, inverse, Pose};
use sim::realman::model::ArmModel;
use sim::realman::planner::{plan_linear, CartesianLimits};
use sim::realman::plant::ArmPlant;

fn deg(v: &[f64]) -> Vec<f64> {
    v.iter().map(|d| d.to_radians()).collect()
}

fn bench_plant(
    model: &ArmModel,
    q: &[f64],
    steps: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut plant = ArmPlant::new(model, q)?;
    let zero = vec![0.0; q.len()];
    let start = Instant::now();
    for _ in 0..steps {
        plant.set_target(black_box(q), &zero);
        plant.step();
    }
    let elapsed = start.elapsed();
    println!(
        "{} plant: {steps} steps in {elapsed:.3?} = {:.2} µs/step",
        model.name,
        elapsed.as_secs_f64() * 1e6 / steps as f64
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rm65 = ArmModel::rm65b();
    let q65 = deg(&[10.0, 40.0, 60.0, 20.0, 50.0, 30.0]);
    bench_plant(&rm65, &q65, 20_000)?;
    bench_plant(
        &ArmModel::rm75b(),
        &deg(&[10.0, 40.0, 0.0, 60.0, 20.0, 50.0, 30.0]),
        20_000,
    )?;

    // IK seeded 0.05 rad away from the answer, the planner's typical case.
    let n = 20_000;
    let targets: Vec<Pose> = (0..100)
        .map(|i| {
            let q: Vec<f64> = q65.iter().map(|v| v + 0.01 * i as f64).collect();
            forward(&rm65, &q)
        })
        .collect();
    let seed: Vec<f64> = q65.iter().map(|v| v - 0.05).collect();
    let start = Instant::now();
    for i in 0..n {
        let _ = black_box(inverse(&rm65, &targets[i % targets.len()], &seed));
    }
    println!(
        "RM65-B IK (seed 0.05 rad off): {:.2} µs/solve",
        start.elapsed().as_secs_f64() * 1e6 / n as f64
    );

    let p0 = forward(&rm65, &q65);
    let to = Pose::new(
        [
            p0.position_m[0] + 0.1,
            p0.position_m[1] - 0.1,
            p0.position_m[2] + 0.1,
        ],
        p0.euler_rad,
    );
    let runs = 20;
    let start = Instant::now();
    for _ in 0..runs {
        black_box(plan_linear(
            &rm65,
            &q65,
            &to,
            50.0,
            &CartesianLimits::default(),
        )?);
    }
    println!(
        "RM65-B plan_linear 0.17 m (174 grid points): {:.2} ms/plan",
        start.elapsed().as_secs_f64() * 1e3 / runs as f64
    );
    Ok(())
}
