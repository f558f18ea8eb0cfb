//! RobStride's live source: every motor's state from the emulator's snapshot, faults from the
//! emulator's table ([`sim::robstride::Fault`]) addressed by motor CAN ID, as in scenario files.

use std::time::Instant;

use serde_json::{json, Value};
use sim::fault_desk::{FaultDesk, Faults};
use sim::robstride::{Fault, MotorSnapshot, RobstrideMonitor};

use super::bus_tap::BusTap;
use super::{round3, LiveSource};

/// RobStride actuators on one bus as the web view sees them.
#[derive(Debug)]
pub struct RobstrideLive {
    faults: FaultDesk<RobstrideMonitor>,
    tap: Option<BusTap>,
    hello: Value,
    started: Instant,
}

impl RobstrideLive {
    /// A source for `monitor`; `motors` are the configured CAN IDs, `title` names the run.
    pub fn new(monitor: RobstrideMonitor, tap: Option<BusTap>, motors: &[u8], title: &str) -> Self {
        let hello = json!({"type": "hello", "device": "robstride", "title": title,
                           "model": null, "motors": motors});
        Self {
            faults: FaultDesk::new(monitor),
            tap,
            hello,
            started: Instant::now(),
        }
    }
}

/// Names of the injectable faults whose bit is set in `word` (also a robot's actuators').
pub(super) fn fault_names(word: u32) -> Vec<&'static str> {
    Fault::set_in(word).into_iter().map(Fault::name).collect()
}

fn motor_json(m: &MotorSnapshot) -> Value {
    json!({
        "id": m.can_id,
        "model": m.model.name(),
        "mode": m.mode.name(),
        "run_mode": m.run_mode,
        "angle_deg": round3(m.angle_rad.to_degrees()),
        "bus_voltage_v": round3(m.bus_voltage_v),
        "faults": fault_names(m.fault_word),
        "fault_word": format!("0x{:08X}", m.fault_word),
        "warning_word": format!("0x{:08X}", m.warning_word),
        "listening": m.listening,
    })
}

#[async_trait::async_trait]
impl LiveSource for RobstrideLive {
    fn hello(&self) -> Value {
        self.hello.clone()
    }

    async fn state(&self) -> Value {
        let motors = self.faults.target().snapshot().await.unwrap_or_default();
        let per = |f: &dyn Fn(&MotorSnapshot) -> f64| -> Vec<f64> {
            motors.iter().map(|m| round3(f(m))).collect()
        };
        json!({
            "type": "state",
            "t": round3(self.started.elapsed().as_secs_f64()),
            "motors": motors.iter().map(motor_json).collect::<Vec<_>>(),
            "joints_deg": per(&|m| m.angle_rad.to_degrees()),
            "velocity_deg_s": per(&|m| m.speed_rad_s.to_degrees()),
            "torque_nm": per(&|m| m.torque_nm),
            "temperature_c": per(&|m| m.temperature_c),
            "bus": self.tap.as_ref().map_or(json!({"load_percent": null, "ids": []}), BusTap::to_json),
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
    use sim::robstride::{Model, MotorConfig, RobstrideBus, RobstrideConfig};

    use super::*;
    use crate::ui::{answer, hello_message, state_message};

    fn command(action: &str, fault: &str, args: Value) -> String {
        json!({"type": action, "fault": fault, "args": args}).to_string()
    }

    #[tokio::test(start_paused = true)]
    async fn page_commands_reach_a_motor_through_the_emulators_fault_builder() {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let config = RobstrideConfig::new(vec![MotorConfig::new(5, Model::RS03)]);
        let emulator = RobstrideBus::spawn(Arc::new(bus.attach("motors")), config).unwrap();
        let live = RobstrideLive::new(emulator.monitor(), None, &[5], "one motor");

        // The menu: the emulator's table, the motor field starting at the configured ID.
        let hello = hello_message(&live);
        let faults = hello["faults"].as_array().unwrap();
        assert_eq!(faults.len(), Fault::ALL.len());
        assert_eq!(faults[0]["name"], "over_temperature");
        let motor = &faults[0]["params"][0];
        assert_eq!(
            (
                &motor["name"],
                &motor["default"],
                &motor["min"],
                &motor["max"]
            ),
            (&json!("motor"), &json!(5.0), &json!(1.0), &json!(127.0))
        );

        // A number typed into the box is a number; the fault reaches the motor's fault word.
        let ack = answer(
            &live,
            &command("inject", "gate_driver", json!({"motor": "5"})),
        )
        .await;
        assert_eq!(ack["message"], "injected gate_driver on motor 5", "{ack}");
        assert_eq!(ack["ok"], true);
        tokio::time::sleep(std::time::Duration::from_millis(5)).await;
        let state = state_message(&live).await;
        assert_eq!(state["faults"], json!(["gate_driver on motor 5"]));
        assert_eq!(
            state["motors"][0]["faults"],
            json!(["gate_driver"]),
            "{state}"
        );

        // Refused with the builder's messages (the scenario files' too).
        for (fault, args, message) in [
            (
                "gate_driver",
                json!({"motor": 200}),
                "`motor`: CAN ID 200 out of range, expected 1..=127",
            ),
            ("gate_driver", json!({}), "`gate_driver` needs `motor`"),
            (
                "gate_driver",
                json!({"motor": ""}),
                "`gate_driver` needs `motor`",
            ),
            (
                "gate_driver",
                json!({"motor": 5, "joint": 2}),
                "fault `gate_driver` has no argument `joint`; it takes: motor",
            ),
        ] {
            let ack = answer(&live, &command("inject", fault, args)).await;
            assert_eq!(
                (&ack["ok"], &ack["message"]),
                (&json!(false), &json!(message))
            );
        }
        let melted = answer(&live, &command("inject", "melted", json!({"motor": 5}))).await;
        assert!(melted["message"]
            .as_str()
            .unwrap()
            .starts_with("no RobStride fault `melted`; known:"));

        let ack = answer(&live, &command("clear", "gate_driver", json!({"motor": 5}))).await;
        assert_eq!(ack["message"], "cleared gate_driver on motor 5");
        assert_eq!(state_message(&live).await["faults"], json!([]));
    }

    #[test]
    fn fault_words_name_their_faults() {
        let word = Fault::UnderVoltage.word_bit() | Fault::GateDriver.word_bit();
        let mut names = fault_names(word);
        names.sort_unstable();
        assert_eq!(names, ["gate_driver", "under_voltage"]);
    }
}
