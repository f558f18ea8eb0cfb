//! RobStride's live source: every motor's state from the emulator's snapshot, faults from the
//! emulator's table ([`sim::robstride::Fault`]) addressed by motor CAN ID, as in scenario files.

use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use serde_json::{json, Value};
use sim::robstride::{Fault, ModeState, MotorFault, MotorSnapshot, RobstrideMonitor};

use super::bus_tap::BusTap;
use super::fault_args::fault_args;
use super::{round3, Command, LiveSource};

/// RobStride actuators on one bus as the web view sees them.
#[derive(Debug)]
pub struct RobstrideLive {
    monitor: RobstrideMonitor,
    tap: Option<BusTap>,
    hello: Value,
    started: Instant,
    /// Faults injected from the page and not cleared: (motor, fault).
    active: Mutex<Vec<(u8, Fault)>>,
}

impl RobstrideLive {
    /// A source for `monitor`; `motors` are the configured CAN IDs, `title` names the run.
    pub fn new(monitor: RobstrideMonitor, tap: Option<BusTap>, motors: &[u8], title: &str) -> Self {
        let first = motors.first().copied().map(f64::from);
        let faults: Vec<Value> = Fault::ALL
            .iter()
            .map(|f| {
                json!({"name": f.name(),
                       "description": format!("sets fault word bit 0x{:08X}; clear removes the cause, the latch stays until stop + clear", f.word_bit()),
                       "params": f.params().iter().map(|p| json!({
                           "name": p.name, "description": format!("{} of the motor", p.what),
                           "required": true, "default": first})).collect::<Vec<_>>()})
            })
            .collect();
        let hello = json!({"type": "hello", "device": "robstride", "title": title,
                           "model": null, "motors": motors, "faults": faults});
        Self {
            monitor,
            tap,
            hello,
            started: Instant::now(),
            active: Mutex::new(Vec::new()),
        }
    }
}

/// The mode's name on the page (also a robot's actuators').
pub(super) fn mode_name(mode: ModeState) -> &'static str {
    match mode {
        ModeState::Reset => "reset",
        ModeState::Calibration => "calibration",
        ModeState::Run => "run",
    }
}

/// Names of the injectable faults whose bit is set in `word` (also a robot's actuators').
pub(super) fn fault_names(word: u32) -> Vec<&'static str> {
    Fault::ALL
        .iter()
        .filter(|f| word & f.word_bit() != 0)
        .map(|f| f.name())
        .collect()
}

fn motor_json(m: &MotorSnapshot) -> Value {
    json!({
        "id": m.can_id,
        "model": m.model.name(),
        "mode": mode_name(m.mode),
        "run_mode": m.run_mode,
        "angle_deg": round3(m.angle_rad.to_degrees()),
        "bus_voltage_v": round3(m.bus_voltage_v),
        "faults": fault_names(m.fault_word),
        "fault_word": format!("0x{:08X}", m.fault_word),
        "warning_word": format!("0x{:08X}", m.warning_word),
        "listening": m.listening,
    })
}

/// The motor ID and fault of a page command, made by the emulator's one fault builder
/// ([`sim::robstride::build_fault`]): the names, CAN ID range and messages of scenario files.
pub fn robstride_fault(command: &Command) -> Result<(u8, Fault), String> {
    sim::robstride::build_fault(&command.fault, &fault_args(&command.args))
        .map(|MotorFault { motor, fault }| (motor, fault))
        .map_err(|e| e.message)
}

#[async_trait::async_trait]
impl LiveSource for RobstrideLive {
    fn hello(&self) -> Value {
        self.hello.clone()
    }

    async fn state(&self) -> Value {
        let motors = self.monitor.snapshot().await.unwrap_or_default();
        let per = |f: &dyn Fn(&MotorSnapshot) -> f64| -> Vec<f64> {
            motors.iter().map(|m| round3(f(m))).collect()
        };
        let active: Vec<String> = self
            .active
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .iter()
            .map(|(id, f)| format!("{} motor {id}", f.name()))
            .collect();
        json!({
            "type": "state",
            "t": round3(self.started.elapsed().as_secs_f64()),
            "motors": motors.iter().map(motor_json).collect::<Vec<_>>(),
            "joints_deg": per(&|m| m.angle_rad.to_degrees()),
            "velocity_deg_s": per(&|m| m.speed_rad_s.to_degrees()),
            "torque_nm": per(&|m| m.torque_nm),
            "temperature_c": per(&|m| m.temperature_c),
            "bus": self.tap.as_ref().map_or(json!({"load_percent": null, "ids": []}), BusTap::to_json),
            "faults": active,
        })
    }

    async fn command(&self, command: &Command) -> Result<String, String> {
        let (motor, fault) = robstride_fault(command)?;
        if command.action == "inject" {
            self.monitor
                .inject(motor, fault)
                .await
                .map_err(|e| e.to_string())?;
            let mut active = self.active.lock().unwrap_or_else(PoisonError::into_inner);
            active.retain(|x| *x != (motor, fault));
            active.push((motor, fault));
            Ok(format!("injected {} on motor {motor}", fault.name()))
        } else {
            self.monitor
                .clear(motor, fault)
                .await
                .map_err(|e| e.to_string())?;
            self.active
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .retain(|x| *x != (motor, fault));
            Ok(format!("cleared {} on motor {motor}", fault.name()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn command(fault: &str, args: Value) -> Command {
        Command {
            action: "inject".into(),
            fault: fault.into(),
            args: args.as_object().cloned().unwrap_or_default(),
        }
    }

    #[test]
    fn page_commands_name_a_motor_and_a_fault_of_the_table() {
        assert_eq!(
            robstride_fault(&command("over_temperature", json!({"motor": 127}))),
            Ok((127, Fault::OverTemperature))
        );
        assert_eq!(
            robstride_fault(&command("gate_driver", json!({"motor": "5"}))),
            Ok((5, Fault::GateDriver))
        );
        assert!(robstride_fault(&command("gate_driver", json!({}))).is_err());
        assert!(robstride_fault(&command("gate_driver", json!({"motor": 200}))).is_err());
        assert!(robstride_fault(&command("melted", json!({"motor": 1}))).is_err());
        // An argument the fault does not take is refused, as in scenario files (it used to be
        // ignored here).
        assert_eq!(
            robstride_fault(&command("gate_driver", json!({"motor": 1, "joint": 2}))),
            Err("fault `gate_driver` has no argument `joint`; it takes: motor".to_owned())
        );
        assert_eq!(
            robstride_fault(&command("gate_driver", json!({"motor": ""}))),
            Err("`gate_driver` needs `motor`".to_owned())
        );
        for f in Fault::ALL {
            assert_eq!(
                robstride_fault(&command(f.name(), json!({"motor": 1}))),
                Ok((1, f))
            );
        }
    }

    #[test]
    fn fault_words_name_their_faults() {
        let word = Fault::UnderVoltage.word_bit() | Fault::GateDriver.word_bit();
        let mut names = fault_names(word);
        names.sort_unstable();
        assert_eq!(names, ["gate_driver", "under_voltage"]);
    }
}
