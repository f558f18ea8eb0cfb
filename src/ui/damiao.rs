//! Damiao's live source: every motor's state from the emulator's snapshot (ids, model, enable,
//! control mode, position, velocity, torque, temperatures, and the state nibble its feedback
//! frames carry, by name), and faults from the emulator's table ([`sim::damiao::Fault`])
//! addressed by the motor's ESC_ID (`motor`).

use std::time::Instant;

use serde_json::{json, Value};
use sim::actuator::{ActuatorSnapshot, Detail};
use sim::damiao::{DamiaoMonitor, Fault};
use sim::fault_desk::{FaultDesk, Faults};

use super::bus_tap::BusTap;
use super::{round3, LiveSource};

/// Damiao motors on one bus as the web view sees them.
#[derive(Debug)]
pub struct DamiaoLive {
    faults: FaultDesk<DamiaoMonitor>,
    tap: Option<BusTap>,
    hello: Value,
    started: Instant,
}

impl DamiaoLive {
    /// A source for `monitor` (a dial and strip per motor, named by the ESC_ID it powered on
    /// with); `title` names the run.
    pub fn new(monitor: DamiaoMonitor, tap: Option<BusTap>, title: &str) -> Self {
        let motors = monitor.power_on_ids().to_vec();
        let hello = json!({"type": "hello", "device": "damiao", "title": title,
                           "model": null, "motors": motors});
        Self {
            faults: FaultDesk::new(monitor),
            tap,
            hello,
            started: Instant::now(),
        }
    }
}

/// The name of a feedback frame's state nibble (docs/protocols/damiao.md §5): `disabled`,
/// `enabled`, or the error by the emulator's fault table (`over_voltage`, `comm_lost`, …).
pub fn state_name(nibble: i64) -> &'static str {
    match nibble {
        0 => "disabled",
        1 => "enabled",
        code => u8::try_from(code)
            .ok()
            .and_then(Fault::from_code)
            .map_or("unknown", Fault::name),
    }
}

/// A kind-specific value of the snapshot (`mst_id`, `state`, `mos_temperature_c`, …).
fn detail(m: &ActuatorSnapshot, name: &str) -> Option<Detail> {
    m.details.iter().find(|(n, _)| *n == name).map(|(_, d)| *d)
}

fn int(m: &ActuatorSnapshot, name: &str) -> Option<i64> {
    match detail(m, name)? {
        Detail::Int(v) => Some(v),
        _ => None,
    }
}

fn real(m: &ActuatorSnapshot, name: &str) -> Option<f64> {
    match detail(m, name)? {
        Detail::Real(v) => Some(v),
        Detail::Int(v) => Some(v as f64),
        Detail::Word(_) => None,
    }
}

fn motor_json(m: &ActuatorSnapshot) -> Value {
    let state = int(m, "state").unwrap_or(0);
    json!({
        "id": m.can_id,
        "mst_id": int(m, "mst_id"),
        "model": m.model,
        "enabled": m.enabled,
        "mode": m.mode,
        "ctrl_mode": int(m, "ctrl_mode"),
        "state": state,
        "state_name": state_name(state),
        "position_rad": round3(m.angle_rad),
        "velocity_rad_s": round3(m.speed_rad_s),
        "torque_nm": round3(m.torque_nm),
        "mos_temperature_c": real(m, "mos_temperature_c").map(round3),
        "rotor_temperature_c": round3(m.temperature_c),
        "bus_voltage_v": real(m, "bus_voltage_v").map(round3),
        "faults": m.faults,
    })
}

/// One line of the page's panel per motor.
fn panel_row(m: &ActuatorSnapshot) -> Value {
    let feedback = int(m, "mst_id").map_or(String::new(), |id| format!(", feedback 0x{id:03X}"));
    let mos = real(m, "mos_temperature_c").map_or("–".to_owned(), |t| format!("{t:.1}"));
    json!([
        format!("motor {} ({}{feedback})", m.can_id, m.model),
        format!(
            "{}, {}, state {}, MOS {mos} °C, rotor {:.1} °C, faults: {}",
            if m.enabled { "enabled" } else { "disabled" },
            m.mode,
            state_name(int(m, "state").unwrap_or(0)),
            m.temperature_c,
            match m.faults.as_slice() {
                [] => "none".to_owned(),
                names => names.join(","),
            }
        )
    ])
}

#[async_trait::async_trait]
impl LiveSource for DamiaoLive {
    fn hello(&self) -> Value {
        self.hello.clone()
    }

    async fn state(&self) -> Value {
        let motors = self.faults.target().snapshot().await.unwrap_or_default();
        let per = |f: &dyn Fn(&ActuatorSnapshot) -> f64| -> Vec<f64> {
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
            "panel": motors.iter().map(panel_row).collect::<Vec<_>>(),
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
    use std::time::Duration;

    use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
    use bus::{CanBus, CanFrame};
    use sim::damiao::{DamiaoBus, DamiaoConfig, Model, MotorConfig};

    use super::*;
    use crate::ui::{answer, hello_message, state_message};

    fn command(action: &str, fault: &str, args: Value) -> String {
        json!({"type": action, "fault": fault, "args": args}).to_string()
    }

    /// The host's `FF … FF code` special command to `esc`.
    fn special(esc: u16, code: u8) -> CanFrame {
        let mut data = [0xFF; 8];
        data[7] = code;
        CanFrame::standard(esc, &data).unwrap()
    }

    #[tokio::test(start_paused = true)]
    async fn the_state_names_each_motor_s_mode_and_state_and_faults_reach_it_through_the_desk() {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let config = DamiaoConfig::new(vec![
            MotorConfig::new(1, Model::DM8009),
            MotorConfig::new(2, Model::DM4310).with_mst_id(0x21),
        ]);
        let emulator = DamiaoBus::spawn(config, Arc::new(bus.attach("motors"))).unwrap();
        let host = bus.attach("host");
        let live = DamiaoLive::new(emulator.monitor(), None, "two motors");

        // The menu: the emulator's table, `motor` first, suggesting the first ESC_ID.
        let hello = hello_message(&live);
        assert_eq!(
            (&hello["device"], &hello["motors"]),
            (&json!("damiao"), &json!([1, 2]))
        );
        let faults = hello["faults"].as_array().unwrap();
        assert_eq!(faults.len(), Fault::ALL.len());
        assert_eq!(faults[0]["name"], "over_voltage");
        let motor = &faults[0]["params"][0];
        assert_eq!(
            (&motor["name"], &motor["default"], &motor["max"]),
            (&json!("motor"), &json!(1.0), &json!(2047.0))
        );

        // Motor 1 enabled by the host; motor 2 stays disabled.
        host.send(special(1, 0xFC)).await.unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
        let state = state_message(&live).await;
        let motors = state["motors"].as_array().unwrap();
        assert_eq!(motors.len(), 2);
        let one = &motors[0];
        assert_eq!(
            (&one["id"], &one["mst_id"], &one["model"], &one["enabled"]),
            (&json!(1), &json!(0x11), &json!("DM8009"), &json!(true))
        );
        assert_eq!(
            (
                &one["mode"],
                &one["ctrl_mode"],
                &one["state"],
                &one["state_name"]
            ),
            (&json!("mit"), &json!(1), &json!(1), &json!("enabled"))
        );
        for key in [
            "position_rad",
            "velocity_rad_s",
            "torque_nm",
            "mos_temperature_c",
            "rotor_temperature_c",
            "bus_voltage_v",
        ] {
            assert!(one[key].is_number(), "{key}: {one}");
        }
        assert_eq!(one["rotor_temperature_c"], 25.0);
        assert_eq!(
            (&motors[1]["mst_id"], &motors[1]["state_name"]),
            (&json!(0x21), &json!("disabled"))
        );
        assert_eq!(state["joints_deg"].as_array().unwrap().len(), 2);
        assert_eq!(
            state["panel"][1][0],
            json!("motor 2 (DM4310, feedback 0x021)")
        );

        // A number typed into the box is a number; the fault latches the motor's state.
        let ack = answer(
            &live,
            &command(
                "inject",
                "mos_over_temperature",
                json!({"motor": "1", "temperature_c": "130"}),
            ),
        )
        .await;
        assert_eq!(
            (&ack["ok"], &ack["message"]),
            (
                &json!(true),
                &json!("injected mos_over_temperature temperature_c=130 on motor 1")
            ),
            "{ack}"
        );
        tokio::time::sleep(Duration::from_millis(5)).await;
        let state = state_message(&live).await;
        assert_eq!(
            state["faults"],
            json!(["mos_over_temperature temperature_c=130 on motor 1"])
        );
        let one = &state["motors"][0];
        assert_eq!(one["faults"], json!(["mos_over_temperature"]), "{one}");
        assert_eq!(
            (&one["state"], &one["state_name"], &one["enabled"]),
            (&json!(0xB), &json!("mos_over_temperature"), &json!(false))
        );
        assert_eq!(one["mos_temperature_c"], 130.0);

        // Refused with the builder's messages.
        for (args, message) in [
            (json!({}), "`overload` needs `motor`"),
            (
                json!({"motor": 4000}),
                "`motor`: ESC_ID 4000 out of range, expected 0..=2047",
            ),
            (
                json!({"motor": 1, "joint": 2}),
                "fault `overload` has no argument `joint`; it takes: motor",
            ),
        ] {
            let ack = answer(&live, &command("inject", "overload", args)).await;
            assert_eq!(
                (&ack["ok"], &ack["message"]),
                (&json!(false), &json!(message))
            );
        }
        let melted = answer(&live, &command("inject", "melted", json!({"motor": 1}))).await;
        assert!(melted["message"]
            .as_str()
            .unwrap()
            .starts_with("no Damiao fault `melted`; known:"));

        // Clearing removes the cause; the host's FB then clears the latch.
        let ack = answer(
            &live,
            &command("clear", "mos_over_temperature", json!({"motor": 1})),
        )
        .await;
        assert_eq!(ack["message"], "cleared mos_over_temperature on motor 1");
        host.send(special(1, 0xFB)).await.unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
        let state = state_message(&live).await;
        assert_eq!(state["faults"], json!([]));
        assert_eq!(state["motors"][0]["state_name"], "disabled");
        emulator.shutdown().await;
    }

    #[test]
    fn state_nibbles_are_named() {
        assert_eq!(state_name(0), "disabled");
        assert_eq!(state_name(1), "enabled");
        assert_eq!(state_name(0xD), "comm_lost");
        assert_eq!(state_name(0x5), "unknown");
        assert_eq!(state_name(-1), "unknown");
    }
}
