//! The Piper's live source: state from the emulator's snapshot, bus figures from a tap, faults
//! from the emulator's own table ([`sim::piper::FaultKind`]), named as in scenario files.

use std::sync::{Mutex, PoisonError};

use driver::piper::{ArmStatusCode, CtrlMode, DriverStatus, MotionStatus};
use serde_json::{json, Map, Value};
use sim::piper::{FaultKind, NtcBoard, PiperFault, PiperMonitor};

use super::bus_tap::BusTap;
use super::{Command, LiveSource};
use crate::harness::elide_long_tokens;
use crate::harness::report::html::arm_model;

/// A running Piper emulator as the web view sees it.
#[derive(Debug)]
pub struct PiperLive {
    monitor: PiperMonitor,
    tap: Option<BusTap>,
    hello: Value,
    /// Faults injected from the page and not cleared, with their text.
    active: Mutex<Vec<(String, PiperFault)>>,
}

impl PiperLive {
    /// A source for `monitor`; `urdf` is the model the emulator loaded, `title` names the run.
    pub fn new(monitor: PiperMonitor, tap: Option<BusTap>, urdf: &str, title: &str) -> Self {
        let model = arm_model(urdf)
            .ok()
            .and_then(|m| serde_json::to_value(m).ok());
        let faults: Vec<Value> = FaultKind::ALL
            .iter()
            .map(|k| {
                let params: Vec<Value> = k
                    .params()
                    .iter()
                    .map(|p| {
                        json!({"name": p.name, "description": p.description,
                               "required": p.required, "default": p.default,
                               "min": p.range.map(|r| r.0), "max": p.range.map(|r| r.1)})
                    })
                    .collect();
                json!({"name": k.name(), "description": k.description(), "params": params})
            })
            .collect();
        let hello = json!({"type": "hello", "device": "piper", "title": title,
                           "model": model, "faults": faults});
        Self {
            monitor,
            tap,
            hello,
            active: Mutex::new(Vec::new()),
        }
    }
}

fn number(args: &Map<String, Value>, key: &str, kind: FaultKind) -> Result<f64, String> {
    match args.get(key) {
        Some(v) => v
            .as_f64()
            .or_else(|| v.as_str().and_then(|s| s.trim().parse().ok()))
            .filter(|x| x.is_finite())
            .ok_or_else(|| elide_long_tokens(&format!("`{key}` must be a number, got {v}"))),
        None => kind
            .params()
            .iter()
            .find(|p| p.name == key)
            .and_then(|p| p.default)
            .ok_or_else(|| format!("`{}` needs `{key}`", kind.name())),
    }
}

fn joint(args: &Map<String, Value>, kind: FaultKind) -> Result<u8, String> {
    let j = number(args, "joint", kind)?;
    if (1.0..=6.0).contains(&j) && j.fract() == 0.0 {
        Ok(j as u8)
    } else {
        Err(elide_long_tokens(&format!("`joint` must be 1..6, got {j}")))
    }
}

/// The fault a page command names, with the table's defaults for omitted parameters. Values
/// are not range-checked here: injecting checks them against the fault table (the emulator's
/// `inject`, the one check every caller goes through), and clearing ignores them.
pub fn piper_fault(name: &str, args: &Map<String, Value>) -> Result<PiperFault, String> {
    let kind = FaultKind::from_name(name).ok_or_else(|| format!("no Piper fault `{name}`"))?;
    let n = |key: &str| number(args, key, kind);
    Ok(match kind {
        FaultKind::CommLoss => PiperFault::CommLoss {
            joint: joint(args, kind)?,
        },
        FaultKind::MotorOverTemp => PiperFault::MotorOverTemp {
            joint: joint(args, kind)?,
            temp_c: n("temp_c")?,
        },
        FaultKind::DriverOverTemp => PiperFault::DriverOverTemp {
            joint: joint(args, kind)?,
            temp_c: n("temp_c")?,
        },
        FaultKind::OverCurrent => PiperFault::OverCurrent {
            joint: joint(args, kind)?,
        },
        FaultKind::UnderVoltage => PiperFault::UnderVoltage {
            voltage_v: n("voltage_v")?,
        },
        FaultKind::DriverError => PiperFault::DriverError {
            joint: joint(args, kind)?,
        },
        FaultKind::Stall => PiperFault::Stall {
            joint: joint(args, kind)?,
        },
        FaultKind::ExternalTorque => PiperFault::ExternalTorque {
            joint: joint(args, kind)?,
            torque_nm: n("torque_nm")?,
        },
        FaultKind::Collision => PiperFault::Collision {
            joint: joint(args, kind)?,
        },
        FaultKind::Estop => PiperFault::Estop,
        FaultKind::NtcOverTemp => {
            let board = match args.get("board").and_then(Value::as_str) {
                None | Some("") => NtcBoard::Main,
                Some(b) => NtcBoard::ALL
                    .into_iter()
                    .find(|x| x.name() == b)
                    .ok_or_else(|| format!("`board` must be main or brake_resistor, got {b}"))?,
            };
            PiperFault::NtcOverTemp { board }
        }
        FaultKind::GripperSensorFault => PiperFault::GripperSensorFault,
        FaultKind::TeachButton => PiperFault::TeachButton,
    })
}

fn deg(values: &[f64; 6]) -> Vec<f64> {
    values.iter().map(|v| round3(v.to_degrees())).collect()
}

fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

fn name_or_code(name: Option<&'static str>, code: u8) -> String {
    name.map_or_else(|| format!("0x{code:02X}"), str::to_owned)
}

#[async_trait::async_trait]
impl LiveSource for PiperLive {
    fn hello(&self) -> Value {
        self.hello.clone()
    }

    async fn state(&self) -> Value {
        let s = self.monitor.snapshot();
        let st = &s.status;
        let bus = match &self.tap {
            Some(tap) => tap.to_json(),
            None => json!({"load_percent": null, "ids": []}),
        };
        let active: Vec<String> = self
            .active
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .iter()
            .map(|(text, _)| text.clone())
            .collect();
        json!({
            "type": "state",
            "t": round3(s.time_s),
            "joints_deg": deg(&s.reported_joints_rad),
            "physical_deg": deg(&s.joint_positions_rad),
            "velocity_deg_s": deg(&s.joint_velocities_rad_s),
            "torque_nm": s.joint_torques_nm.map(round3),
            "current_a": s.motor_currents_a.map(round3),
            "temperature_c": s.motor_temps_c.map(round3),
            "gripper_mm": round3(s.gripper_stroke_m * 1000.0),
            "gripper_force_n": round3(s.gripper_force_n),
            "contacts": s.contacts,
            "status": {
                "ctrl_mode": name_or_code(CtrlMode::from(st.ctrl_mode).name(), st.ctrl_mode),
                "arm_status": name_or_code(ArmStatusCode::from(st.arm_status).name(), st.arm_status),
                "motion": name_or_code(MotionStatus::from(st.motion_status).name(), st.motion_status),
                "mode_feed": st.mode_feed,
                "enabled": st.enabled,
                "gripper_enabled": st.gripper_enabled,
                "driver_faults": st.driver_status.iter()
                    .map(|b| DriverStatus(*b).names().into_iter()
                        .filter(|n| DriverStatus::BITS.iter().any(|(_, m, fault)| m == n && *fault))
                        .collect::<Vec<_>>())
                    .collect::<Vec<_>>(),
                "limit_bits": st.limit_bits,
                "comm_bits": st.comm_bits,
            },
            "bus": bus,
            "faults": active,
        })
    }

    async fn command(&self, command: &Command) -> Result<String, String> {
        let fault = piper_fault(&command.fault, &command.args)?;
        let text = fault.to_string();
        let mut active = self.active.lock().unwrap_or_else(PoisonError::into_inner);
        if command.action == "inject" {
            self.monitor.inject(fault).map_err(|e| e.to_string())?;
            active.retain(|(_, f)| !f.same_site(&fault));
            active.push((text.clone(), fault));
            Ok(format!("injected {text}"))
        } else {
            self.monitor.clear(fault).map_err(|e| e.to_string())?;
            active.retain(|(_, f)| !f.same_site(&fault));
            Ok(format!("cleared {text}"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(v: Value) -> Map<String, Value> {
        v.as_object().cloned().unwrap_or_default()
    }

    #[test]
    fn page_commands_become_emulator_faults_with_table_defaults() {
        assert_eq!(
            piper_fault("motor_over_temp", &args(json!({"joint": 2}))),
            Ok(PiperFault::MotorOverTemp {
                joint: 2,
                temp_c: 90.0
            })
        );
        assert_eq!(
            piper_fault(
                "external_torque",
                &args(json!({"joint": "3", "torque_nm": "1.5"}))
            ),
            Ok(PiperFault::ExternalTorque {
                joint: 3,
                torque_nm: 1.5
            })
        );
        assert_eq!(piper_fault("estop", &Map::new()), Ok(PiperFault::Estop));
        assert!(piper_fault("stall", &args(json!({"joint": 7}))).is_err());
        assert!(piper_fault("stall", &Map::new()).is_err());
        assert!(piper_fault("external_torque", &args(json!({"joint": 1}))).is_err());
        assert!(piper_fault("nope", &Map::new()).is_err());
    }

    #[test]
    fn page_errors_do_not_echo_huge_values() {
        let torque = FaultKind::ExternalTorque.param("torque_nm").unwrap();
        assert_eq!(torque.range, Some((-320.0, 320.0)));
        let bad = piper_fault(
            "stall",
            &args(json!({"joint": format!("1{}", "0".repeat(300))})),
        )
        .unwrap_err();
        assert!(bad.len() < 100, "{bad}");
        let bad = piper_fault(
            "external_torque",
            &args(json!({"joint": 1, "torque_nm": "x".repeat(300)})),
        )
        .unwrap_err();
        assert!(bad.len() < 100, "{bad}");
    }

    #[test]
    fn an_absurd_value_from_the_page_is_refused_by_the_emulator_table() {
        let fault = piper_fault(
            "external_torque",
            &args(json!({"joint": 1, "torque_nm": 1e308})),
        )
        .unwrap();
        let err = fault.check().unwrap_err().to_string();
        assert_eq!(err, "`torque_nm` must be between -320 and 320, got 1e308");
        let sag = piper_fault("under_voltage", &args(json!({"voltage_v": -5}))).unwrap();
        assert!(
            sag.check().is_err(),
            "a negative voltage is refused, not clamped"
        );
    }

    #[test]
    fn every_fault_of_the_table_can_be_built_from_the_page() {
        let full = args(json!({"joint": 1, "torque_nm": 1.0}));
        for kind in FaultKind::ALL {
            let fault = piper_fault(kind.name(), &full).unwrap();
            assert_eq!(fault.kind(), kind);
        }
    }
}
