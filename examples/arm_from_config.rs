//! Pick and place through the vendor-neutral Arm API, with the arm created from a JSON
//! configuration file.
//!
//! Run it against the Realman emulator (two terminals):
//!
//! ```text
//! cargo run --release -- sim realman                 # listens on 127.0.0.1:8080
//! cargo run --release --example arm_from_config      # uses examples/realman_arm.json
//! cargo run --release --example arm_from_config -- path/to/other_arm.json
//! ```
//!
//! The configuration names the controller (`ip`, `port`) and where the realtime state is to be
//! pushed (`udp_ip`, `udp_port`, every `udp_cycle` × 5 ms); every value is a string. The same
//! program drives a real Realman arm when the file points at it.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;
use driver::arm::{create_arm_from_config, ArmInterface, MoveOptions, Pose};

/// Joint configurations (degrees) the poses are taken from, so they are reachable.
const HOME_DEG: [f64; 6] = [0.0, 20.0, 70.0, 0.0, 90.0, 0.0];
const PICK_DEG: [f64; 6] = [-30.0, 35.0, 75.0, 0.0, 70.0, -30.0];
const PLACE_DEG: [f64; 6] = [30.0, 35.0, 75.0, 0.0, 70.0, 30.0];
/// How far above the object the gripper approaches, metres.
const APPROACH_M: f64 = 0.05;

fn above(p: &Pose, dz_m: f64) -> Pose {
    let mut q = *p;
    q.position_m[2] += dz_m;
    q
}

/// Approach from above, go straight down, act on the gripper, go straight up.
async fn visit(
    arm: &dyn ArmInterface,
    at: &Pose,
    grip: impl std::future::Future<Output = driver::arm::ArmResult<()>>,
) -> anyhow::Result<()> {
    arm.move_joint_pose(&above(at, APPROACH_M), MoveOptions::blocking(40))
        .await
        .context("approach")?;
    arm.move_cartesian_linear(at, MoveOptions::blocking(20))
        .await
        .context("descend")?;
    grip.await.context("gripper")?;
    arm.move_cartesian_linear(&above(at, APPROACH_M), MoveOptions::blocking(20))
        .await
        .context("retreat")?;
    Ok(())
}

#[tokio::main]
async fn main() -> anyhow::Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "examples/realman_arm.json".to_string());
    let arm = create_arm_from_config(&path)?;
    println!("{} arm {:?} from {path}", arm.vendor(), arm.name());
    arm.connect()
        .await
        .context("connect (is `armhil sim realman` running?)")?;

    // The API's callback form: count the realtime states while the task runs.
    let states = Arc::new(AtomicUsize::new(0));
    let counter = states.clone();
    arm.realtime_arm_state_call_back(Box::new(move |_| {
        counter.fetch_add(1, Ordering::Relaxed);
    }))?;
    let started = Instant::now();

    arm.move_joint_position(&HOME_DEG, MoveOptions::blocking(50))
        .await
        .context("home")?;
    let pick = arm.forward_kinematics(&PICK_DEG).await?;
    let place = arm.forward_kinematics(&PLACE_DEG).await?;
    arm.set_gripper_release(500, true, 5)
        .await
        .context("open")?;
    visit(arm.as_ref(), &pick, arm.set_gripper_pick(500, 300, true, 5)).await?;
    println!("picked at {:?} m", pick.position_m);
    visit(arm.as_ref(), &place, arm.set_gripper_release(500, true, 5)).await?;
    println!("placed at {:?} m", place.position_m);
    arm.move_joint_position(&HOME_DEG, MoveOptions::blocking(50))
        .await
        .context("home")?;

    let joints = arm.get_joint_degree().await?;
    let gripper = arm.get_gripper_state().await?;
    let secs = started.elapsed().as_secs_f64();
    let n = states.load(Ordering::Relaxed);
    println!(
        "back home at {joints:.2?} deg, gripper aperture {}",
        gripper.actpos
    );
    println!(
        "{n} realtime states in {secs:.1} s ({:.0}/s)",
        n as f64 / secs
    );
    arm.disconnect().await;
    Ok(())
}
