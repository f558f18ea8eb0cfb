//! Realman's live source: the arm from the controller's snapshot, the TCP clients connected
//! and the UDP push targets, faults from the emulator's table ([`sim::realman::RealmanFaultKind`])
//! with the parameters scenario files give them.

use serde_json::{json, Value};
use sim::fault_desk::{FaultDesk, Faults};
use sim::realman::RealmanMonitor;

use super::{round3, LiveSource};
use crate::harness::report::html::arm_model;

/// A running Realman emulator as the web view sees it.
#[derive(Debug)]
pub struct RealmanLive {
    faults: FaultDesk<RealmanMonitor>,
    hello: Value,
}

impl RealmanLive {
    /// A source for `monitor`; `urdf` is the arm's model, `title` names the run.
    pub fn new(monitor: RealmanMonitor, urdf: &str, title: &str) -> Self {
        let model = arm_model(urdf)
            .ok()
            .and_then(|m| serde_json::to_value(m).ok());
        let hello = json!({"type": "hello", "device": "realman", "title": title, "model": model});
        Self {
            faults: FaultDesk::new(monitor),
            hello,
        }
    }
}

#[async_trait::async_trait]
impl LiveSource for RealmanLive {
    fn hello(&self) -> Value {
        self.hello.clone()
    }

    async fn state(&self) -> Value {
        let monitor = self.faults.target();
        let s = monitor.snapshot();
        let (push, io) =
            monitor.with_controller(|c| (c.params().push.clone(), c.params().io.summary()));
        let clients = monitor.clients();
        let stats = monitor.stats();
        // Where the push goes now, as the emulator's push task decides it.
        let targets: Vec<String> = monitor
            .push_targets()
            .iter()
            .map(ToString::to_string)
            .collect();
        let deg = |v: &[f64]| v.iter().map(|x| round3(x.to_degrees())).collect::<Vec<_>>();
        let errors: Vec<String> = s.errors.iter().map(|e| format!("0x{e:04X}")).collect();
        let p = s.pose.position_m;
        let panel = vec![
            json!(["status", s.status]),
            json!(["power", if s.power_on { "on" } else { "off" }]),
            json!([
                "enabled",
                s.enabled
                    .iter()
                    .enumerate()
                    .filter(|(_, e)| **e)
                    .map(|(i, _)| format!("J{}", i + 1))
                    .collect::<Vec<_>>()
                    .join(" ")
            ]),
            json!([
                "errors",
                if errors.is_empty() {
                    "none".to_owned()
                } else {
                    errors.join(" ")
                }
            ]),
            json!(["queued moves", s.queued_moves.to_string()]),
            // Each port's mode (i input, o output) and level, analog outputs, supplies.
            json!(["IO", io]),
            json!([
                "pose (mm)",
                format!("{:.1}, {:.1}, {:.1}", p[0] * 1e3, p[1] * 1e3, p[2] * 1e3)
            ]),
            json!([
                "TCP clients",
                if clients.is_empty() {
                    "none".to_owned()
                } else {
                    clients
                        .iter()
                        .map(ToString::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            ]),
            json!([
                "UDP push",
                if !push.enable {
                    "off".to_owned()
                } else if targets.is_empty() {
                    format!(
                        "on, every {} ms, but no connected client to send it to",
                        push.cycle * 5
                    )
                } else {
                    format!(
                        "{} every {} ms ({} sent)",
                        targets.join(", "),
                        push.cycle * 5,
                        stats.push.sent
                    )
                }
            ]),
        ];
        json!({
            "type": "state",
            "t": round3(s.time_ms as f64 / 1000.0),
            "joints_deg": deg(&s.joints_rad),
            "velocity_deg_s": deg(&s.speeds_rad_s),
            "setpoint_deg": deg(&s.setpoint_rad),
            "clients": clients.iter().map(ToString::to_string).collect::<Vec<_>>(),
            "push_targets": targets,
            "errors": errors,
            "status": {"status": s.status, "power_on": s.power_on, "enabled": s.enabled},
            "panel": panel,
            "bus": null,
        })
    }

    fn faults(&self) -> &dyn Faults {
        &self.faults
    }
}

#[cfg(test)]
mod tests {
    use serde_json::Map;
    use sim::realman::{RealmanFault, RealmanFaultKind};

    use super::*;
    use crate::harness::elide_long_tokens;
    use crate::ui::{answer, page_fault_args, state_message};

    fn args(v: Value) -> Map<String, Value> {
        v.as_object().cloned().unwrap_or_default()
    }

    /// What the page's arguments build, as the page shows a refusal.
    fn realman_fault(name: &str, page: &Map<String, Value>) -> Result<RealmanFault, String> {
        sim::realman::build_fault(name, &page_fault_args(page))
            .map_err(|e| elide_long_tokens(&e.message))
    }

    fn command(action: &str, fault: &str, args: Value) -> String {
        json!({"type": action, "fault": fault, "args": args}).to_string()
    }

    #[tokio::test(start_paused = true)]
    async fn page_faults_reach_the_controller_and_events_are_not_kept() {
        let emu = rm65b_in_memory().await;
        let live = RealmanLive::new(emu.monitor(), "", "test");
        let ack = answer(&live, &command("inject", "estop", json!({}))).await;
        assert_eq!(ack["message"], "injected estop", "{ack}");
        assert!(
            emu.snapshot()
                .errors
                .contains(&sim::realman::faults::codes::JOINT_DISABLED),
            "the controller is in e-stop"
        );
        let drop = answer(&live, &command("inject", "connection_drop", json!({}))).await;
        assert_eq!(drop["ok"], true, "{drop}");
        assert_eq!(state_message(&live).await["faults"], json!(["estop"]));
        // Cleared by name: the page's leftover arguments do not matter.
        let cleared = answer(&live, &command("clear", "estop", json!({"joint": 1}))).await;
        assert_eq!(cleared["message"], "cleared estop");
        assert_eq!(state_message(&live).await["faults"], json!([]));
        let bad = answer(
            &live,
            &command("inject", "udp_loss", json!({"permille": 1001})),
        )
        .await;
        assert_eq!(bad["ok"], false);
        emu.shutdown().await;
    }

    #[test]
    fn page_commands_become_emulator_faults_in_range() {
        assert_eq!(
            realman_fault("joint_error", &args(json!({"joint": 3, "code": 8}))),
            Ok(RealmanFault::JointError { joint: 3, code: 8 })
        );
        assert_eq!(
            realman_fault("reply_delay", &args(json!({"delay_ms": "600"}))),
            Ok(RealmanFault::ReplyDelay { delay_ms: 600 })
        );
        assert!(realman_fault("joint_error", &args(json!({"joint": 8, "code": 8}))).is_err());
        assert!(realman_fault("udp_loss", &args(json!({"permille": 1001}))).is_err());
        assert!(realman_fault("reply_delay", &Map::new()).is_err());
        assert!(realman_fault("nope", &Map::new()).is_err());
        // What the page sends: each of the fault's own parameters (an argument the fault does
        // not take is refused, as in scenario files and Python).
        let full = args(
            json!({"delay_ms": 1, "count": 1, "permille": 1, "joint": 1, "code": 1, "bits": 1}),
        );
        for kind in RealmanFaultKind::ALL {
            let mine: Map<String, Value> = full
                .iter()
                .filter(|(name, _)| kind.param(name).is_some())
                .map(|(name, value)| (name.clone(), value.clone()))
                .collect();
            assert_eq!(
                realman_fault(kind.name(), &mine).map(|f| f.kind()),
                Ok(kind)
            );
        }
        assert!(realman_fault("estop", &args(json!({"joint": 1}))).is_err());
    }

    /// An RM65-B emulator without sockets, for the view's state.
    async fn rm65b_in_memory() -> sim::realman::RealmanHandle {
        use sim::realman::model::ArmModel;
        use sim::realman::{ControllerConfig, EmulatorConfig, RealmanEmulator, Transport};
        RealmanEmulator::spawn(
            EmulatorConfig::new(ControllerConfig::new(ArmModel::rm65b())),
            Transport::InMemory,
        )
        .await
        .expect("emulator")
    }

    /// The value of the panel row called `name` in a state message.
    fn panel_row(state: &Value, name: &str) -> Option<Value> {
        state["panel"]
            .as_array()
            .and_then(|rows| rows.iter().find(|r| r[0] == name))
            .map(|r| r[1].clone())
    }

    #[tokio::test(start_paused = true)]
    async fn the_panel_shows_the_io_ports() {
        let emu = rm65b_in_memory().await;
        let monitor = emu.monitor();
        monitor.with_controller(|c| {
            for r in [
                json!({"command": "set_IO_mode", "IO_Num": 2, "IO_mode": 1}),
                json!({"command": "set_DO_state", "IO_Num": 2, "state": 1}),
                json!({"command": "set_AO_state", "IO_Num": 1, "voltage": 1500}),
            ] {
                c.handle(1, &r);
            }
        });
        let live = RealmanLive::new(monitor, "", "test");
        let state = live.state().await;
        let io = panel_row(&state, "IO");
        assert_eq!(
            io,
            Some(json!(
                "DIO 1:i0 2:o1 3:i0 4:i0 | AO 1.500 0.000 0.000 0.000 V | 24 V · tool 1:i0 2:i0 24 V"
            ))
        );
        emu.shutdown().await;
    }

    #[tokio::test(start_paused = true)]
    async fn the_panel_lists_only_where_the_push_really_goes() {
        let emu = rm65b_in_memory().await;
        let monitor = emu.monitor();
        // A target stored by an earlier client; nobody is connected now, so the emulator
        // pushes nowhere (the view used to list 192.0.2.7:8089 all the same).
        monitor.with_controller(|c| {
            let set = json!({"command": "set_realtime_push", "cycle": 1, "enable": true,
                             "port": 8089, "ip": "192.0.2.7"});
            c.handle(1, &set);
        });
        let live = RealmanLive::new(monitor, "", "test");
        let state = live.state().await;
        assert_eq!(state["push_targets"], json!([]));
        let row = panel_row(&state, "UDP push");
        assert_eq!(
            row,
            Some(json!(
                "on, every 5 ms, but no connected client to send it to"
            ))
        );
        emu.shutdown().await;
    }

    #[test]
    fn page_errors_do_not_echo_huge_values() {
        let digits = format!("1{}", "0".repeat(300));
        let err = realman_fault("reply_delay", &args(json!({"delay_ms": digits}))).unwrap_err();
        assert!(err.len() < 120, "{err}");
        // The name is cut; the known names follow it.
        let err = realman_fault(&"x".repeat(300), &Map::new()).unwrap_err();
        assert!(!err.contains(&"x".repeat(50)), "{err}");
        assert!(err.ends_with("estop, gripper_fault"), "{err}");
    }
}
