//! Realman RM65-B / RM75-B arm controller emulator (JSON over TCP, UDP realtime push;
//! protocol in `docs/protocols/realman.md`).
//!
//! The motion core is independent of the wire protocol:
//!
//! - [`model`]: the arm models (MDH table, flange, joint ranges, speeds, masses).
//! - [`kinematics`]: flange forward kinematics ([`kinematics::forward`]) and numerical
//!   inverse kinematics ([`kinematics::inverse`]), poses as x, y, z + intrinsic Z-Y-X Euler.
//! - [`planner`]: `movej` / `movel` / `movec` / `moves` trajectories and blending of
//!   connected segments.
//! - [`plant`]: the physical arm, `urdf/rm65b.urdf` in the rapier world at 1 kHz with
//!   torque-driven joint controllers, brakes, currents, temperatures and bus voltage.
//!
//! ```
//! use sim::realman::{kinematics, model::ArmModel, planner};
//!
//! let arm = ArmModel::rm65b();
//! let home = vec![0.0; 6];
//! let target: Vec<f64> = [10.0_f64, 20.0, 30.0, 40.0, 50.0, 60.0].iter().map(|d| d.to_radians()).collect();
//! let pose = kinematics::forward(&arm, &target);
//! let back = kinematics::inverse(&arm, &pose, &target)?;
//! assert!((back[2] - target[2]).abs() < 1e-6);
//! let movej = planner::plan_joint(&arm, &home, &target, 50.0)?;
//! assert_eq!(movej.kind(), planner::MotionKind::Joint);
//! assert!((movej.sample(movej.duration_s())[0] - target[0]).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// ---- realman-kin: kinematics, planning, physics plant (begin) ----
pub mod kinematics;
pub mod model;
mod path;
pub mod planner;
pub mod plant;
// ---- realman-kin (end) ----
