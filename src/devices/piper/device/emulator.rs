//! The in-process Piper emulator behind the harness's [`EmulatorControl`] seam.

use std::sync::{Arc, Mutex, PoisonError};

use async_trait::async_trait;
use bus::CanBus;
use sim::physics::ObstacleShape as SimShape;
use sim::piper::{
    FirmwareProfile, Flash, LinkageRole, PiperConfig, PiperEmulator, PiperFault, PiperHandle,
    PiperSimState,
};

use super::EmulatorControl;
use crate::devices::piper::model::{ObstacleShape, PiperSettings, Role};

/// A running in-process Piper emulator.
pub(crate) struct PiperSim {
    handle: Mutex<Option<PiperHandle>>,
    /// Faults injected and not yet cleared, so `clear_faults` can undo all of them.
    active: Mutex<Vec<PiperFault>>,
}

impl PiperSim {
    /// Start an emulator for `settings` on `bus`.
    pub fn spawn(bus: Arc<dyn CanBus>, settings: &PiperSettings) -> Result<Self, String> {
        let firmware: FirmwareProfile = settings.firmware.parse().map_err(|e| format!("{e}"))?;
        let mut flash = Flash::default();
        if let Some(mm) = settings.gripper_max_mm {
            flash.gripper_max_stroke_mm = mm;
        }
        if let Some(levels) = settings.collision_levels {
            flash.collision_levels = levels;
        }
        flash.linkage_role = match settings.role {
            Role::Leader => LinkageRole::Leader,
            Role::Follower => LinkageRole::Follower,
        };
        let config = PiperConfig {
            firmware,
            initial_joints_rad: settings.initial_joints_deg.map(f64::to_radians),
            urdf_path: settings.urdf.clone(),
            flash: Some(flash),
            ..PiperConfig::default()
        };
        let handle = PiperEmulator::spawn(bus, config).map_err(|e| e.to_string())?;
        for obstacle in &settings.obstacles {
            let shape = match obstacle.shape {
                ObstacleShape::Box { size_m } => SimShape::Box {
                    half_extents_m: size_m.map(|s| s / 2.0),
                },
                ObstacleShape::Sphere { radius_m } => SimShape::Sphere { radius_m },
            };
            handle.add_obstacle(shape, obstacle.at_m);
        }
        Ok(Self {
            handle: Mutex::new(Some(handle)),
            active: Mutex::new(Vec::new()),
        })
    }

    fn with<T>(&self, f: impl FnOnce(&PiperHandle) -> Result<T, String>) -> Result<T, String> {
        let guard = self.handle.lock().unwrap_or_else(PoisonError::into_inner);
        match guard.as_ref() {
            Some(h) => f(h),
            None => Err("the emulator has stopped".to_owned()),
        }
    }
}

#[async_trait]
impl EmulatorControl for PiperSim {
    fn inject(&self, fault: &PiperFault) -> Result<(), String> {
        self.with(|h| h.inject(*fault).map_err(|e| e.to_string()))?;
        self.active
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(*fault);
        Ok(())
    }

    fn clear(&self, fault: Option<&PiperFault>) -> Result<(), String> {
        let faults: Vec<PiperFault> = {
            let mut active = self.active.lock().unwrap_or_else(PoisonError::into_inner);
            match fault {
                Some(f) => {
                    active.retain(|a| !a.same_site(f));
                    vec![*f]
                }
                None => std::mem::take(&mut *active),
            }
        };
        self.with(|h| {
            for fault in faults {
                h.clear(fault).map_err(|e| e.to_string())?;
            }
            Ok(())
        })
    }

    fn health(&self) -> Result<(), String> {
        self.with(|h| piper_health(&h.snapshot()))
    }

    async fn shutdown(&self) {
        let handle = self
            .handle
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take();
        if let Some(h) = handle {
            h.shutdown().await;
        }
    }
}

/// Whether a Piper emulator's physical state is finite: joint positions, velocities and
/// torques, and the gripper.
pub(crate) fn piper_health(s: &PiperSimState) -> Result<(), String> {
    let joints = (0..6).flat_map(|j| {
        [
            (
                format!("joint {} position", j + 1),
                s.joint_positions_rad[j],
            ),
            (
                format!("joint {} velocity", j + 1),
                s.joint_velocities_rad_s[j],
            ),
            (format!("joint {} torque", j + 1), s.joint_torques_nm[j]),
        ]
    });
    crate::devices::finite_state(joints.chain([
        ("the gripper stroke".to_owned(), s.gripper_stroke_m),
        ("the gripper force".to_owned(), s.gripper_force_n),
    ]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn a_nan_physical_state_is_an_emulator_error() {
        let bus = bus::virtual_bus::VirtualBus::new(bus::virtual_bus::VirtualBusConfig::default());
        let node: Arc<dyn CanBus> = Arc::new(bus.attach("piper"));
        let handle = PiperEmulator::spawn(node, PiperConfig::default()).unwrap();
        let mut fw_state = handle.snapshot();
        handle.shutdown().await;
        assert_eq!(piper_health(&fw_state), Ok(()));
        fw_state.joint_velocities_rad_s[1] = f64::NAN;
        let err = piper_health(&fw_state).unwrap_err();
        assert!(err.contains("joint 2 velocity is NaN"), "{err}");
        assert!(err.contains("physics diverged"), "{err}");
    }
}
