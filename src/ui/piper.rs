//! The Piper's live source: state from the emulator's snapshot, bus figures from a tap, faults
//! from the emulator's own table ([`sim::piper::FaultKind`]), named as in scenario files.

use driver::piper::{ArmStatusCode, CtrlMode, DriverStatus, MotionStatus};
use serde_json::{json, Value};
use sim::fault_desk::{FaultDesk, Faults};
use sim::piper::PiperMonitor;

use super::bus_tap::BusTap;
use super::{round3, LiveSource};
use crate::harness::report::html::arm_model;

/// A running Piper emulator as the web view sees it.
#[derive(Debug)]
pub struct PiperLive {
    faults: FaultDesk<PiperMonitor>,
    tap: Option<BusTap>,
    hello: Value,
}

impl PiperLive {
    /// A source for `monitor`; `urdf` is the model the emulator loaded, `title` names the run.
    pub fn new(monitor: PiperMonitor, tap: Option<BusTap>, urdf: &str, title: &str) -> Self {
        let model = arm_model(urdf)
            .ok()
            .and_then(|m| serde_json::to_value(m).ok());
        let hello = json!({"type": "hello", "device": "piper", "title": title, "model": model});
        Self {
            faults: FaultDesk::new(monitor),
            tap,
            hello,
        }
    }
}

fn deg(values: &[f64; 6]) -> Vec<f64> {
    values.iter().map(|v| round3(v.to_degrees())).collect()
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
        let s = self.faults.target().snapshot();
        let st = &s.status;
        let bus = match &self.tap {
            Some(tap) => tap.to_json(),
            None => json!({"load_percent": null, "ids": []}),
        };
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
        })
    }

    fn faults(&self) -> &dyn Faults {
        &self.faults
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
    use serde_json::Map;
    use sim::piper::{FaultKind, PiperConfig, PiperEmulator, PiperFault};

    use super::*;
    use crate::ui::{answer, hello_message, page_fault_args, state_message};

    fn args(v: Value) -> Map<String, Value> {
        v.as_object().cloned().unwrap_or_default()
    }

    /// What the page's arguments build (the desk's inject path without the emulator).
    fn piper_fault(name: &str, page: &Map<String, Value>) -> Result<PiperFault, String> {
        sim::piper::build_fault(name, &page_fault_args(page)).map_err(|e| e.message)
    }

    /// What the page's arguments build to clear.
    fn piper_fault_to_clear(name: &str, page: &Map<String, Value>) -> Result<PiperFault, String> {
        FaultKind::named(name)
            .and_then(|kind| kind.build_to_clear(&page_fault_args(page)))
            .map_err(|e| e.message)
    }

    fn command(action: &str, fault: &str, args: Value) -> String {
        json!({"type": action, "fault": fault, "args": args}).to_string()
    }

    #[tokio::test(start_paused = true)]
    async fn page_commands_fault_the_running_firmware_and_show_while_active() {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let emulator =
            PiperEmulator::spawn(Arc::new(bus.attach("piper")), PiperConfig::default()).unwrap();
        let live = PiperLive::new(emulator.monitor(), None, sim::piper::BUNDLED_URDF, "arm");
        let hello = hello_message(&live);
        let torque = hello["faults"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["name"] == "external_torque")
            .unwrap();
        assert_eq!(torque["params"][1]["name"], "torque_nm");
        assert_eq!(
            (&torque["params"][1]["min"], &torque["params"][1]["max"]),
            (&json!(-320.0), &json!(320.0))
        );

        let ack = answer(
            &live,
            &command("inject", "motor_over_temp", json!({"joint": 2})),
        )
        .await;
        assert_eq!(
            ack["message"], "injected motor_over_temp joint 2 90 C",
            "{ack}"
        );
        let hot = answer(
            &live,
            &command(
                "inject",
                "motor_over_temp",
                json!({"joint": 2, "temp_c": 120}),
            ),
        )
        .await;
        assert_eq!(hot["ok"], true);
        // The same site again replaces the earlier entry.
        assert_eq!(
            state_message(&live).await["faults"],
            json!(["motor_over_temp joint 2 120 C"])
        );
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
        assert_eq!(
            emulator.monitor().snapshot().motor_temps_c[1],
            120.0,
            "the firmware's winding is forced"
        );
        let refused = answer(
            &live,
            &command("inject", "under_voltage", json!({"voltage_v": -5})),
        )
        .await;
        assert_eq!(
            (&refused["ok"], &refused["message"]),
            (
                &json!(false),
                &json!("`voltage_v` must be between 0 and 60, got -5")
            )
        );
        let cleared = answer(
            &live,
            &command("clear", "motor_over_temp", json!({"joint": 2})),
        )
        .await;
        assert_eq!(cleared["ok"], true, "{cleared}");
        assert_eq!(state_message(&live).await["faults"], json!([]));
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
        // Refused when the fault is built (the emulator's builder), with the table's message.
        let err = piper_fault(
            "external_torque",
            &args(json!({"joint": 1, "torque_nm": 1e308})),
        )
        .unwrap_err();
        assert_eq!(err, "`torque_nm` must be between -320 and 320, got 1e308");
        let sag = piper_fault("under_voltage", &args(json!({"voltage_v": -5}))).unwrap_err();
        assert_eq!(
            sag, "`voltage_v` must be between 0 and 60, got -5",
            "a negative voltage is refused, not clamped"
        );
    }

    #[test]
    fn clearing_from_the_page_needs_the_site_not_the_values() {
        assert_eq!(
            piper_fault_to_clear("external_torque", &args(json!({"joint": 2}))),
            Ok(PiperFault::ExternalTorque {
                joint: 2,
                torque_nm: 0.0
            })
        );
        assert!(piper_fault_to_clear("external_torque", &Map::new()).is_err());
        assert!(piper_fault_to_clear("nope", &Map::new()).is_err());
    }

    #[test]
    fn an_argument_the_fault_does_not_take_is_refused() {
        let err = piper_fault("estop", &args(json!({"joint": 1}))).unwrap_err();
        assert_eq!(err, "`estop` takes no `joint` (it takes: no arguments)");
    }

    #[test]
    fn every_fault_of_the_table_can_be_built_from_the_page() {
        // What the page sends: each of the fault's parameters, as the page fills them in.
        let full = args(json!({"joint": 1, "torque_nm": 1.0, "temp_c": 95,
                               "voltage_v": "12.5", "board": "brake_resistor"}));
        for kind in FaultKind::ALL {
            let mine: Map<String, Value> = full
                .iter()
                .filter(|(name, _)| kind.param(name).is_some())
                .map(|(name, value)| (name.clone(), value.clone()))
                .collect();
            let fault = piper_fault(kind.name(), &mine).unwrap();
            assert_eq!(fault.kind(), kind);
        }
    }
}
