//! The in-process Piper emulator behind the harness's [`EmulatorControl`] seam.

use std::sync::{Arc, Mutex, PoisonError};

use async_trait::async_trait;
use bus::CanBus;
use sim::physics::ObstacleShape as SimShape;
use sim::piper::{FirmwareProfile, Flash, PiperConfig, PiperEmulator, PiperFault, PiperHandle};

use super::device::EmulatorControl;
use super::model::{ObstacleShape, PiperSettings};

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
