//! A whole robot's live source: the robot drawn from its URDF, a strip per actuator, each
//! actuator's state, and faults per actuator (RobStride's fault table, addressed by URDF
//! joint name), a push on a joint, and a bus cut off.

use serde_json::{json, Value};
use sim::fault_desk::{FaultDesk, Faults};
use sim::robot::{RobotMonitor, RobotSnapshot};

use super::bus_tap::BusTap;
use super::{round3, LiveSource};
use crate::harness::report::html::arm_model;

/// A robot as the web view sees it.
#[derive(Debug)]
pub struct RobotLive {
    faults: FaultDesk<RobotMonitor>,
    /// Per bus: its name and its tap.
    taps: Vec<(String, BusTap)>,
    /// The joints the 3D view sets, in the model's order (revolute, not mimic).
    drawn: Vec<String>,
    hello: Value,
}

impl RobotLive {
    /// A source for `monitor` (a strip per actuated joint, in configuration order): `urdf`
    /// is the robot's and `paths` where its meshes are (its config's `urdf_paths`), `taps`
    /// a tap per bus by name.
    pub fn new(
        monitor: RobotMonitor,
        (urdf, paths): (&str, &sim::description::PackagePaths),
        taps: Vec<(String, BusTap)>,
        title: &str,
    ) -> Self {
        let model = arm_model((urdf, paths))
            .inspect_err(|e| tracing::warn!("the web view cannot draw the robot: {e}"))
            .ok();
        let drawn = model.as_ref().map_or_else(Vec::new, |m| {
            m.joints
                .iter()
                .filter(|j| matches!(j.kind, "revolute" | "continuous") && j.mimic.is_none())
                .map(|j| j.name.clone())
                .collect()
        });
        let joints: Vec<&str> = monitor
            .layout()
            .joints
            .iter()
            .map(|(j, _)| j.as_str())
            .collect();
        let hello = json!({"type": "hello", "device": "robot", "title": title, "model": model,
                           "strip_names": joints});
        Self {
            faults: FaultDesk::new(monitor),
            taps,
            drawn,
            hello,
        }
    }

    fn bus_json(&self) -> Value {
        let mut load: Option<f64> = None;
        let mut ids = Vec::new();
        for (name, tap) in &self.taps {
            let figures = tap.to_json();
            if let Some(l) = figures["load_percent"].as_f64() {
                load = Some(load.map_or(l, |m: f64| m.max(l)));
            }
            for row in figures["ids"].as_array().into_iter().flatten() {
                let mut row = row.clone();
                row[0] = json!(format!("{name} {}", row[0].as_str().unwrap_or("")));
                ids.push(row);
            }
        }
        json!({"load_percent": load, "ids": ids})
    }

    fn panel(&self, s: &RobotSnapshot) -> Vec<Value> {
        let mut panel = vec![json!([
            "base",
            format!(
                "x {:.3} y {:.3} z {:.3} m",
                s.base_position_m[0], s.base_position_m[1], s.base_position_m[2]
            )
        ])];
        for (name, tap) in &self.taps {
            let load = tap.to_json()["load_percent"].as_f64();
            let lost = s.lost_buses.contains(name);
            panel.push(json!([
                format!("bus {name}"),
                format!(
                    "{}{}",
                    load.map_or("load –".to_owned(), |l| format!("load {l:.1} %")),
                    if lost { ", LOST" } else { "" }
                )
            ]));
        }
        for j in &s.joints {
            let m = &j.actuator;
            panel.push(json!([
                format!(
                    "{} ({} {} id {} on {})",
                    j.joint, m.kind, m.model, m.can_id, j.bus
                ),
                format!(
                    "{}, {}, {:.1} °C, faults: {}",
                    if m.enabled { "enabled" } else { "disabled" },
                    m.mode,
                    m.temperature_c,
                    match m.faults.as_slice() {
                        [] => "none".to_owned(),
                        names => names.join(","),
                    }
                )
            ]));
        }
        panel
    }
}

/// The root link's pose as the 3D view takes it: a 4×4 transform by rows.
fn base_pose(s: &RobotSnapshot) -> Vec<f64> {
    let (r, t) = (&s.base_rotation, &s.base_position_m);
    let mut pose = Vec::with_capacity(16);
    for row in 0..3 {
        pose.extend(r[row].map(round4));
        pose.push(round4(t[row]));
    }
    pose.extend([0.0, 0.0, 0.0, 1.0]);
    pose
}

fn round4(v: f64) -> f64 {
    (v * 10_000.0).round() / 10_000.0
}

#[async_trait::async_trait]
impl LiveSource for RobotLive {
    fn hello(&self) -> Value {
        self.hello.clone()
    }

    async fn state(&self) -> Value {
        let Ok(s) = self.faults.target().snapshot().await else {
            return json!({"type": "state", "t": 0.0, "faults": ["the robot has stopped"]});
        };
        let per = |f: &dyn Fn(&sim::robot::JointSnapshot) -> f64| -> Vec<f64> {
            s.joints.iter().map(|j| round3(f(j))).collect()
        };
        // The 3D view's angles in the model's joint order; a passive joint is drawn at 0.
        let physical: Vec<Option<f64>> = self
            .drawn
            .iter()
            .map(|name| s.joint(name).map(|j| round3(j.position_rad.to_degrees())))
            .collect();
        json!({
            "type": "state",
            "t": round3(s.time_s),
            "physical_deg": physical,
            "base_position_m": s.base_position_m.map(round3),
            "base_pose": base_pose(&s),
            "joints_deg": per(&|j| j.position_rad.to_degrees()),
            "velocity_deg_s": per(&|j| j.velocity_rad_s.to_degrees()),
            "torque_nm": per(&|j| j.actuator.torque_nm),
            "temperature_c": per(&|j| j.actuator.temperature_c),
            "panel": self.panel(&s),
            "bus": self.bus_json(),
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
    use bus::CanBus;
    use sim::robot::RobotEmulator;

    use super::*;
    use crate::ui::{apply_command, hello_message, state_message, Command};

    fn command(action: &str, fault: &str, args: Value) -> Command {
        serde_json::from_value(json!({"type": action, "fault": fault, "args": args})).unwrap()
    }

    #[tokio::test(start_paused = true)]
    async fn the_page_faults_an_actuator_pushes_a_joint_and_cuts_a_bus() {
        let file =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/robstride_arm6.yaml");
        let config = crate::robots::load_robot_file(&file).unwrap().config;
        let buses: Vec<VirtualBus> = config
            .buses
            .iter()
            .map(|_| VirtualBus::new(VirtualBusConfig::default()))
            .collect();
        let nodes = buses
            .iter()
            .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
            .collect();
        let taps = config
            .buses
            .iter()
            .zip(&buses)
            .map(|(c, b)| {
                (
                    c.name.clone(),
                    BusTap::spawn(Arc::new(b.attach("ui")), c.bitrate_bps),
                )
            })
            .collect();
        let (urdf, paths) = (config.urdf.clone(), config.urdf_paths.clone());
        let robot = RobotEmulator::spawn(config, nodes).unwrap();
        let live = RobotLive::new(robot.monitor(), (&urdf, &paths), taps, "arm6");

        let hello = hello_message(&live);
        assert_eq!(hello["strip_names"][3], "wrist_roll");
        assert!(hello["model"]["joints"]
            .as_array()
            .is_some_and(|j| j.len() >= 6));
        let bus_lost = hello["faults"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["name"] == "bus_lost");
        assert_eq!(bus_lost.unwrap()["params"][0]["default"], "can0");

        let ack = apply_command(
            live.faults(),
            &command(
                "inject",
                "over_temperature",
                json!({"joint": "elbow_pitch"}),
            ),
        )
        .await
        .unwrap();
        assert_eq!(ack, "injected over_temperature on elbow_pitch");
        let faults = live.faults();
        apply_command(
            faults,
            &command("inject", "bus_lost", json!({"bus": "can1"})),
        )
        .await
        .unwrap();
        apply_command(
            faults,
            &command(
                "inject",
                "external_torque",
                json!({"joint": "shoulder_yaw", "torque_nm": "8"}),
            ),
        )
        .await
        .unwrap();
        tokio::time::sleep(std::time::Duration::from_millis(300)).await;
        let state = state_message(&live).await;
        assert_eq!(
            state["faults"],
            json!([
                "over_temperature on elbow_pitch",
                "bus_lost can1",
                "external_torque on shoulder_yaw"
            ])
        );
        let panel = state["panel"].to_string();
        assert!(
            panel.contains("LOST") && panel.contains("over_temperature"),
            "{panel}"
        );
        // The push turned the shoulder, and the 3D view sees it in the model's joint order.
        assert!(state["joints_deg"][0].as_f64().unwrap() > 1.0, "{state}");
        assert_eq!(state["physical_deg"][0], state["joints_deg"][0]);
        assert_eq!(state["base_pose"].as_array().unwrap().len(), 16);

        let cleared = apply_command(
            faults,
            &command("clear", "bus_lost", json!({"bus": "can1"})),
        )
        .await
        .unwrap();
        assert_eq!(cleared, "cleared bus_lost can1");
        // A push is cleared by its joint alone, and stops.
        let stop = command("clear", "external_torque", json!({"joint": "shoulder_yaw"}));
        assert_eq!(
            apply_command(faults, &stop).await,
            Ok("cleared external_torque on shoulder_yaw".into())
        );
        let unknown = command("inject", "over_temperature", json!({"joint": "elbo"}));
        let unknown = apply_command(faults, &unknown).await.unwrap_err();
        assert!(
            unknown.starts_with("no actuator drives joint `elbo`"),
            "{unknown}"
        );
        let melt = command("inject", "melt", json!({"joint": "elbow_pitch"}));
        let melt = apply_command(faults, &melt).await.unwrap_err();
        assert!(melt.starts_with("no robot fault `melt`"), "{melt}");
        // A push beyond ten times the actuator's peak torque is refused before it reaches
        // the physics.
        let shove = command(
            "inject",
            "external_torque",
            json!({"joint": "shoulder_yaw", "torque_nm": 1e6}),
        );
        let shove = apply_command(faults, &shove).await.unwrap_err();
        assert!(shove.starts_with("`torque_nm` must be between"), "{shove}");
        assert_eq!(
            state_message(&live).await["faults"],
            json!(["over_temperature on elbow_pitch"])
        );
        robot.shutdown().await;
    }
}
