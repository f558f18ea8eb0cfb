//! A robot's faults, the one builder behind the web view and the Python emulator
//! ([`FaultTarget`] on [`RobotMonitor`]): each actuator kind's fault table on the actuator of
//! a joint (addressed by URDF joint name), a push on a joint, and a bus cut off. A scenario's
//! `actuator_fault: {joint, fault}` names the same tables.

use crate::actuator::registry::kind_named;
use crate::actuator::ActuatorModel;
use crate::fault_args::{self, shown_word, FaultArgError, FaultArgValue, FaultArgs};
use crate::fault_desk::{FaultInfo, FaultTarget, ParamInfo};
use crate::piper::faults::Shown;
use crate::robot::RobotMonitor;
use crate::robstride::faults::{within, EXTERNAL_TORQUE_PEAK_MULTIPLE};
use crate::yaml_words::suggestion;

/// The push's name.
pub const EXTERNAL_TORQUE: &str = "external_torque";
/// The bus fault's name.
pub const BUS_LOST: &str = "bus_lost";
/// The name of the gantry's release (an event: the stand does not come back).
pub const GANTRY_RELEASE: &str = "gantry_release";

/// A fault on a running robot.
#[derive(Debug, Clone, PartialEq)]
pub enum RobotFault {
    /// A fault of the actuator kind's table on the actuator of `joint`.
    Actuator {
        /// The URDF joint.
        joint: String,
        /// The fault's name in its kind's table.
        fault: &'static str,
        /// Its values (no `joint`).
        args: FaultArgs,
        /// How it shows applied (`encoder_glitch 100 counts`).
        label: String,
    },
    /// A torque from outside on `joint` (N·m, in the actuator's shaft frame); clearing it
    /// stops the push.
    ExternalTorque {
        /// The URDF joint.
        joint: String,
        /// The torque.
        torque_nm: f64,
    },
    /// `bus` cut off: no frame reaches or leaves its actuators.
    BusLost {
        /// The bus's name.
        bus: String,
    },
    /// The stand holding the base lets go ([`crate::robot::Gantry`]); an event.
    GantryRelease,
}

/// What a robot's faults are addressed by: its actuated joints (with their actuators'
/// models, which bound a push) and its buses, in configuration order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RobotLayout {
    /// Each actuated joint and its actuator's model.
    pub joints: Vec<(String, ActuatorModel)>,
    /// Each bus's name.
    pub buses: Vec<String>,
}

impl RobotLayout {
    /// The fault tables of the actuator kinds the robot carries, each once, in joint order.
    fn actuator_faults(&self) -> Vec<FaultInfo> {
        let mut models: Vec<&str> = Vec::new();
        let mut table: Vec<FaultInfo> = Vec::new();
        for (_, model) in &self.joints {
            if models.contains(&model.name) {
                continue;
            }
            models.push(model.name);
            let Some(kind) = kind_named(model.kind) else {
                continue;
            };
            // Two kinds may name one fault alike (under_voltage): listed once, as the first
            // joint's actuator takes it.
            for fault in (kind.faults)(model.name) {
                if !table.iter().any(|f| f.name == fault.name) {
                    table.push(fault);
                }
            }
        }
        table
    }

    /// Every fault name: the actuators' tables (`actuator_faults`), then the push and the
    /// bus cut.
    fn names(actuator_faults: &[FaultInfo]) -> Vec<&'static str> {
        let mut names: Vec<&str> = actuator_faults.iter().map(|f| f.name).collect();
        names.extend([EXTERNAL_TORQUE, BUS_LOST, GANTRY_RELEASE]);
        names
    }

    /// The fault table, suggesting the first joint and the first bus.
    pub fn fault_table(&self) -> Vec<FaultInfo> {
        let first_joint = self
            .joints
            .first()
            .map(|(name, _)| FaultArgValue::Text(name.clone()));
        let joint = |what: &str| {
            ParamInfo::required("joint", format!("URDF joint {what}"))
                .suggesting(first_joint.clone())
        };
        let mut table: Vec<FaultInfo> = self
            .actuator_faults()
            .into_iter()
            .map(|f| FaultInfo {
                name: f.name,
                description: format!("{} (on the joint's actuator)", f.description),
                params: std::iter::once(joint("whose actuator faults"))
                    .chain(f.params)
                    .collect(),
            })
            .collect();
        table.push(FaultInfo {
            name: EXTERNAL_TORQUE,
            description: "a torque from outside on the joint (N·m); clear stops pushing".into(),
            params: vec![
                joint("pushed"),
                ParamInfo::required("torque_nm", "N·m, in the actuator's shaft frame")
                    .suggesting(Some(FaultArgValue::Number(5.0))),
            ],
        });
        table.push(FaultInfo {
            name: BUS_LOST,
            description: "the bus cut off: no frame reaches or leaves its actuators".into(),
            params: vec![ParamInfo::required("bus", "bus name")
                .suggesting(self.buses.first().cloned().map(FaultArgValue::Text))],
        });
        table.push(FaultInfo {
            name: GANTRY_RELEASE,
            description: "the stand holding a floating base lets go: the robot stands or falls"
                .into(),
            params: Vec::new(),
        });
        table
    }

    /// The fault `name` from `args`; `clearing`: a push's torque may be left out.
    pub fn build(
        &self,
        name: &str,
        args: &FaultArgs,
        clearing: bool,
    ) -> Result<RobotFault, FaultArgError> {
        let actuator_faults = self.actuator_faults();
        match fault_args::named("robot", name, &Self::names(&actuator_faults), |n| n)? {
            EXTERNAL_TORQUE => {
                args.only(name, &["joint", "torque_nm"])?;
                let (joint, model) = self.joint(name, args)?;
                let torque_nm = match args.get("torque_nm") {
                    None if clearing => 0.0,
                    None => return Err(FaultArgError::missing(name, "torque_nm")),
                    Some(FaultArgValue::Number(x)) => {
                        let max = EXTERNAL_TORQUE_PEAK_MULTIPLE * model.peak_torque_nm;
                        within("torque_nm", *x, (-max, max))
                            .map_err(|e| FaultArgError::at("torque_nm", e.to_string()))?
                    }
                    Some(other) => {
                        return Err(FaultArgError::at(
                            "torque_nm",
                            format!("`torque_nm` must be a number (N·m), got {other}"),
                        ))
                    }
                };
                Ok(RobotFault::ExternalTorque { joint, torque_nm })
            }
            GANTRY_RELEASE => {
                args.only(name, &[])?;
                Ok(RobotFault::GantryRelease)
            }
            BUS_LOST => {
                args.only(name, &["bus"])?;
                let bus = word(name, args, "bus")?;
                if !self.buses.contains(&bus) {
                    let known: Vec<&str> = self.buses.iter().map(String::as_str).collect();
                    return Err(FaultArgError::at(
                        "bus",
                        format!(
                            "the robot has no bus {}{}; its buses: {}",
                            shown_word(&bus),
                            suggestion(&bus, &known),
                            known.join(", ")
                        ),
                    ));
                }
                Ok(RobotFault::BusLost { bus })
            }
            fault => {
                // Every other name is an actuator kind's, with its values (which clearing
                // may leave out), checked by the kind of the joint's actuator. An argument no
                // kind's fault of this name takes is refused first, by name.
                let known: Vec<&str> = std::iter::once("joint")
                    .chain(
                        actuator_faults
                            .iter()
                            .filter(|f| f.name == fault)
                            .flat_map(|f| f.params.iter().map(|p| p.name)),
                    )
                    .collect();
                args.only(name, &known)?;
                let (joint, model) = self.joint(name, args)?;
                let kind = kind_named(model.kind).filter(|k| k.has_fault(model.name, fault));
                let Some(kind) = kind else {
                    return Err(FaultArgError::at(
                        "joint",
                        format!(
                            "joint {}'s actuator ({} {}) has no fault `{fault}`",
                            shown_word(&joint),
                            model.kind,
                            model.name
                        ),
                    ));
                };
                let mut values = FaultArgs::new();
                for (arg, value) in args.iter().filter(|(arg, _)| *arg != "joint") {
                    values.push(arg, value.clone());
                }
                let label = (kind.fault_label)(model.name, fault, &values, clearing)?;
                Ok(RobotFault::Actuator {
                    joint,
                    fault,
                    args: values,
                    label,
                })
            }
        }
    }

    /// The `joint` argument: an actuated joint of the robot, and its actuator's model.
    fn joint(
        &self,
        fault: &str,
        args: &FaultArgs,
    ) -> Result<(String, ActuatorModel), FaultArgError> {
        let joint = word(fault, args, "joint")?;
        match self.joints.iter().find(|(name, _)| *name == joint) {
            Some((_, model)) => Ok((joint, *model)),
            None => {
                let known: Vec<&str> = self.joints.iter().map(|(n, _)| n.as_str()).collect();
                Err(FaultArgError::at(
                    "joint",
                    format!(
                        "no actuator drives joint {}{}",
                        shown_word(&joint),
                        suggestion(&joint, &known)
                    ),
                ))
            }
        }
    }
}

/// A name argument: a word, or a whole number written where a name was meant (a form's box
/// reads `1` as a number).
fn word(fault: &str, args: &FaultArgs, arg: &str) -> Result<String, FaultArgError> {
    match args.get(arg) {
        None => Err(FaultArgError::missing(fault, arg)),
        Some(FaultArgValue::Text(text)) => Ok(text.trim().to_owned()),
        Some(FaultArgValue::Number(x)) => Ok(Shown(*x).to_string()),
    }
}

#[async_trait::async_trait]
impl FaultTarget for RobotMonitor {
    type Fault = RobotFault;

    fn fault_table(&self) -> Vec<FaultInfo> {
        self.layout().fault_table()
    }

    fn build(&self, name: &str, args: &FaultArgs) -> Result<RobotFault, FaultArgError> {
        self.layout().build(name, args, false)
    }

    fn build_to_clear(&self, name: &str, args: &FaultArgs) -> Result<RobotFault, FaultArgError> {
        self.layout().build(name, args, true)
    }

    fn label(&self, fault: &RobotFault) -> String {
        match fault {
            RobotFault::Actuator { joint, label, .. } => format!("{label} on {joint}"),
            RobotFault::ExternalTorque { joint, .. } => format!("{EXTERNAL_TORQUE} on {joint}"),
            RobotFault::BusLost { bus } => format!("{BUS_LOST} {bus}"),
            RobotFault::GantryRelease => GANTRY_RELEASE.to_owned(),
        }
    }

    fn lasts(&self, fault: &RobotFault) -> bool {
        !matches!(fault, RobotFault::GantryRelease)
    }

    fn same_site(&self, a: &RobotFault, b: &RobotFault) -> bool {
        match (a, b) {
            // One fault of a kind per actuator, whatever its values.
            (
                RobotFault::Actuator { joint, fault, .. },
                RobotFault::Actuator {
                    joint: other_joint,
                    fault: other,
                    ..
                },
            ) => joint == other_joint && fault == other,
            _ => self.label(a) == self.label(b),
        }
    }

    async fn inject(&self, fault: RobotFault) -> Result<(), String> {
        match fault {
            RobotFault::Actuator {
                joint, fault, args, ..
            } => RobotMonitor::inject(self, &joint, fault, args).await,
            RobotFault::ExternalTorque { joint, torque_nm } => {
                self.set_external_torque(&joint, torque_nm).await
            }
            RobotFault::BusLost { bus } => self.set_bus_lost(&bus, true).await,
            RobotFault::GantryRelease => self.release_gantry().await.map(|_| ()),
        }
        .map_err(|e| e.to_string())
    }

    async fn clear(&self, fault: RobotFault) -> Result<(), String> {
        match fault {
            RobotFault::Actuator {
                joint, fault, args, ..
            } => RobotMonitor::clear(self, &joint, fault, args).await,
            RobotFault::ExternalTorque { joint, .. } => self.set_external_torque(&joint, 0.0).await,
            RobotFault::BusLost { bus } => self.set_bus_lost(&bus, false).await,
            // An event: nothing is left to clear (the stand does not come back).
            RobotFault::GantryRelease => Ok(()),
        }
        .map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robstride::{Fault, Model};

    fn model(model: &str) -> ActuatorModel {
        crate::actuator::configure(model, 1).unwrap().model()
    }

    fn layout() -> RobotLayout {
        RobotLayout {
            joints: vec![
                ("left_knee".into(), model("RS04")),
                ("left_ankle".into(), model("RS02")),
            ],
            buses: vec!["can0".into(), "can1".into()],
        }
    }

    fn args(pairs: &[(&str, FaultArgValue)]) -> FaultArgs {
        let mut args = FaultArgs::new();
        for (name, value) in pairs {
            args.push(*name, value.clone());
        }
        args
    }

    fn text(t: &str) -> FaultArgValue {
        FaultArgValue::Text(t.into())
    }

    #[test]
    fn faults_are_addressed_by_joint_and_bus_name() {
        let l = layout();
        assert_eq!(
            l.build("gate_driver", &args(&[("joint", text("left_knee"))]), false),
            Ok(RobotFault::Actuator {
                joint: "left_knee".into(),
                fault: "gate_driver",
                args: FaultArgs::new(),
                label: "gate_driver".into(),
            })
        );
        assert_eq!(
            l.build("bus_lost", &args(&[("bus", text("can1"))]), false),
            Ok(RobotFault::BusLost { bus: "can1".into() })
        );
        let knee = l.build("gate_driver", &args(&[("joint", text("left_kne"))]), false);
        assert_eq!(
            knee.unwrap_err().message,
            "no actuator drives joint `left_kne`; did you mean `left_knee`?"
        );
        let bus = l.build("bus_lost", &args(&[("bus", text("can7"))]), false);
        assert!(
            bus.unwrap_err().message.ends_with("its buses: can0, can1"),
            "the robot's buses are listed"
        );
        let melt = l.build("melt", &args(&[("joint", text("left_knee"))]), false);
        assert!(melt
            .unwrap_err()
            .message
            .starts_with("no robot fault `melt`; known: over_temperature"));
        let extra = l.build(
            "gate_driver",
            &args(&[("joint", text("left_knee")), ("bus", text("can0"))]),
            false,
        );
        assert_eq!(extra.unwrap_err().arg.as_deref(), Some("bus"));
    }

    #[test]
    fn a_push_is_bounded_by_the_joints_actuator_and_cleared_without_a_torque() {
        let l = layout();
        let push = |joint: &str, torque: f64| {
            l.build(
                EXTERNAL_TORQUE,
                &args(&[
                    ("joint", text(joint)),
                    ("torque_nm", FaultArgValue::Number(torque)),
                ]),
                false,
            )
        };
        assert_eq!(
            push("left_knee", 5.0),
            Ok(RobotFault::ExternalTorque {
                joint: "left_knee".into(),
                torque_nm: 5.0
            })
        );
        // Ten times each model's peak torque: the knee's RS04 (120 N·m) takes what the
        // ankle's RS02 (17 N·m) refuses.
        let big = crate::robstride::faults::max_external_torque_nm(Model::RS02) + 1.0;
        assert!(push("left_knee", big).is_ok());
        let refused = push("left_ankle", big).unwrap_err();
        assert_eq!(refused.arg.as_deref(), Some("torque_nm"));
        assert!(
            refused.message.contains("must be between"),
            "{}",
            refused.message
        );
        let needs = l.build(
            EXTERNAL_TORQUE,
            &args(&[("joint", text("left_knee"))]),
            false,
        );
        assert_eq!(
            needs.unwrap_err().message,
            "`external_torque` needs `torque_nm`"
        );
        let clear = l.build(
            EXTERNAL_TORQUE,
            &args(&[("joint", text("left_knee"))]),
            true,
        );
        assert_eq!(
            clear,
            Ok(RobotFault::ExternalTorque {
                joint: "left_knee".into(),
                torque_nm: 0.0
            })
        );
    }

    #[test]
    fn the_table_suggests_the_first_joint_and_bus() {
        let table = layout().fault_table();
        assert_eq!(table.len(), Fault::ALL.len() + 3);
        let bus = table.iter().find(|f| f.name == BUS_LOST).unwrap();
        assert_eq!(bus.params[0].default, Some(text("can0")));
        assert_eq!(table[0].params[0].default, Some(text("left_knee")));
    }
}
