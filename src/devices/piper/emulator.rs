//! The in-process Piper emulator behind the harness's [`EmulatorControl`] seam.

use std::sync::{Arc, Mutex, PoisonError};

use async_trait::async_trait;
use bus::CanBus;
use sim::physics::ObstacleShape as SimShape;
use sim::piper::{
    FirmwareProfile, Flash, PiperConfig, PiperEmulator, PiperFault, PiperFaultKind, PiperHandle,
};

use super::device::EmulatorControl;
use super::model::{EmulatorFault, NtcBoard, ObstacleShape, PiperSettings};

/// A running in-process Piper emulator.
pub(crate) struct PiperSim {
    handle: Mutex<Option<PiperHandle>>,
    /// Faults injected and not yet cleared, so `clear_faults` can undo all of them.
    active: Mutex<Vec<PiperFaultKind>>,
}

fn to_sim(fault: &EmulatorFault) -> PiperFault {
    match *fault {
        EmulatorFault::CommLoss { joint } => PiperFault::JointCommLoss { joint },
        EmulatorFault::MotorOverTemp { joint, temp_c } => {
            PiperFault::MotorOverTemp { joint, temp_c }
        }
        EmulatorFault::DriverOverTemp { joint, temp_c } => {
            PiperFault::DriverOverTemp { joint, temp_c }
        }
        EmulatorFault::OverCurrent { joint } => PiperFault::OverCurrent { joint },
        EmulatorFault::UnderVoltage { voltage_v } => PiperFault::UnderVoltage { voltage_v },
        EmulatorFault::DriverError { joint } => PiperFault::DriverError { joint },
        EmulatorFault::Stall { joint } => PiperFault::Stall { joint },
        EmulatorFault::ExternalTorque { joint, torque_nm } => {
            PiperFault::ExternalTorque { joint, torque_nm }
        }
        EmulatorFault::Collision { joint } => PiperFault::Collision { joint },
        EmulatorFault::Estop => PiperFault::EStop,
        EmulatorFault::NtcOverTemp {
            board: NtcBoard::Main,
        } => PiperFault::MainControlOverTemp,
        EmulatorFault::NtcOverTemp {
            board: NtcBoard::BrakeResistor,
        } => PiperFault::ResistorOverTemp,
        EmulatorFault::GripperSensor => PiperFault::GripperSensorFault,
        EmulatorFault::TeachButton => PiperFault::TeachButton,
    }
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
    fn inject(&self, fault: &EmulatorFault) -> Result<(), String> {
        let sim_fault = to_sim(fault);
        self.with(|h| h.inject(sim_fault).map_err(|e| e.to_string()))?;
        self.active
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(sim_fault.kind());
        Ok(())
    }

    fn clear(&self, fault: Option<&EmulatorFault>) -> Result<(), String> {
        let kinds: Vec<PiperFaultKind> = {
            let mut active = self.active.lock().unwrap_or_else(PoisonError::into_inner);
            match fault {
                Some(f) => {
                    let kind = to_sim(f).kind();
                    active.retain(|k| *k != kind);
                    vec![kind]
                }
                None => std::mem::take(&mut *active),
            }
        };
        self.with(|h| {
            for kind in kinds {
                h.clear(kind).map_err(|e| e.to_string())?;
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
