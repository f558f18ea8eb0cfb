//! Layer 2 of the `actuator_group` grammar, with file:line:col errors.

use sim::actuator::registry::kind_named;
use sim::actuator::ActuatorConfig;
use sim::robstride::{Load, Model, MotorConfig};

use super::model::{
    GroupAction, GroupActuator, GroupCheck, GroupFault, GroupMode, GroupSettings, JointTarget,
};
use super::raw::{RawConds, RawFault, RawGroupStep, RawSettings, RawStep};
use crate::scenario::{pos, Ctx, DeviceStep, Pos, Res, S};

/// The CAN IDs a RobStride motor takes (the firmware's range).
const CAN_IDS: std::ops::RangeInclusive<i64> = 1..=127;

/// The group's actuators: joints named once, CAN IDs distinct and in range, known models.
pub(crate) fn settings(ctx: &Ctx<'_>, raw: &RawSettings, at: Pos) -> Res<GroupSettings> {
    let list = match (&raw.actuators, &raw.robot) {
        (Some(list), None) => list,
        (None, Some(file)) => return robot_settings(ctx, file, raw.gantry.as_ref()),
        (Some(_), Some(file)) => {
            return Err(ctx.err(
                pos(file),
                "give `actuators` (one bus, a rig each) or `robot` (a robot file), not both",
            ))
        }
        (None, None) => return Err(ctx.err(
            at,
            "an actuator group needs `actuators` (one bus, a rig each) or `robot` (a robot file)",
        )),
    };
    if let Some(gantry) = &raw.gantry {
        return Err(ctx.err(
            pos(gantry),
            "`gantry` holds a robot's base: give it with `robot`, not `actuators`",
        ));
    }
    if list.value.is_empty() {
        return Err(ctx.err(
            pos(list),
            "`actuators` is empty; a group needs at least one",
        ));
    }
    let mut actuators: Vec<GroupActuator> = Vec::new();
    for entry in &list.value {
        let a = &entry.value;
        if actuators.iter().any(|b| b.joint == a.joint.value) {
            return Err(ctx.err(
                pos(&a.joint),
                format!("joint `{}` is listed twice", a.joint.value),
            ));
        }
        if !CAN_IDS.contains(&a.can_id.value) {
            return Err(ctx.err(
                pos(&a.can_id),
                format!("`can_id` must be 1..=127, got {}", a.can_id.value),
            ));
        }
        let can_id = a.can_id.value as u8;
        if let Some(other) = actuators
            .iter()
            .find(|b| b.actuator.can_id() == u32::from(can_id))
        {
            return Err(ctx.err(
                pos(&a.can_id),
                format!(
                    "CAN ID {can_id} is already joint `{}`'s on this bus",
                    other.joint
                ),
            ));
        }
        let model = Model::named(&a.model.value).map_err(|e| ctx.err(pos(&a.model), e))?;
        let load = match &a.pendulum {
            None => Load::default(),
            Some(p) => Load::Pendulum {
                mass_kg: positive(ctx, &p.value.mass_kg, "mass_kg")?,
                length_m: positive(ctx, &p.value.length_m, "length_m")?,
            },
        };
        actuators.push(GroupActuator {
            joint: a.joint.value.clone(),
            actuator: ActuatorConfig::new(MotorConfig::new(can_id, model).with_load(load)),
            bus: 0,
        });
    }
    Ok(GroupSettings {
        actuators,
        buses: vec!["bench".to_owned()],
        robot: None,
    })
}

/// `robot: FILE`: the robot file, relative to the scenario, loaded with its own errors (which
/// name the robot file's line and column) reported at the `robot:` key.
fn robot_settings(
    ctx: &Ctx<'_>,
    file: &S<String>,
    gantry: Option<&S<String>>,
) -> Res<GroupSettings> {
    let dir = ctx.file.parent().unwrap_or(std::path::Path::new("."));
    let path = dir.join(&file.value);
    let loaded = crate::robots::load_robot_file(&path).map_err(|e| {
        let shown = match &e {
            crate::robots::RobotFileError::Invalid(inner) => inner.to_string(),
            other => other.to_string(),
        };
        ctx.err(pos(file), format!("robot file `{}`: {shown}", file.value))
    })?;
    let mut config = loaded.config;
    if let Some(word) = gantry {
        config.gantry = sim::robot::Gantry::parse(&word.value)
            .map_err(|e| ctx.err(pos(word), format!("`gantry` {e}")))?;
        if config.base == sim::robot::Base::Fixed && config.gantry != sim::robot::Gantry::Off {
            return Err(ctx.err(
                pos(word),
                format!(
                    "`gantry`: robot `{}` has a fixed base; a gantry holds a floating one",
                    config.name
                ),
            ));
        }
    }
    // Each joint is driven by its kind's driver, one driver per bus: a bus carrying two
    // kinds would need a host node per kind, which a bench does not open (yet).
    let mut actuators: Vec<GroupActuator> = Vec::with_capacity(config.actuators.len());
    for a in &config.actuators {
        let kind = a.actuator.kind().name;
        if let Some(other) = actuators
            .iter()
            .find(|o| o.bus == a.bus && o.actuator.kind().name != kind)
        {
            return Err(ctx.err(
                pos(file),
                format!(
                    "robot file `{}`: bus `{}` carries a {} actuator (joint `{}`) and a {} one (joint `{}`); a scenario's group drives one kind per bus",
                    file.value,
                    config.buses[a.bus].name,
                    other.actuator.kind().name,
                    other.joint,
                    kind,
                    a.joint
                ),
            ));
        }
        actuators.push(GroupActuator {
            joint: a.joint.clone(),
            actuator: a.actuator.clone(),
            bus: a.bus,
        });
    }
    Ok(GroupSettings {
        actuators,
        buses: config.buses.iter().map(|b| b.name.clone()).collect(),
        robot: Some(config),
    })
}

fn positive(ctx: &Ctx<'_>, value: &S<f64>, key: &str) -> Res<f64> {
    let v = ctx.finite(value, key)?;
    if v <= 0.0 {
        return Err(ctx.err(pos(value), format!("`{key}` must be > 0, got {v}")));
    }
    Ok(v)
}

/// Joint names to targets, each joint a part of device `device`.
fn targets(
    ctx: &Ctx<'_>,
    device: usize,
    raw: &S<std::collections::BTreeMap<String, S<f64>>>,
    key: &str,
) -> Res<Vec<(String, JointTarget)>> {
    if raw.value.is_empty() {
        return Err(ctx.err(pos(raw), format!("`{key}` names no joint")));
    }
    raw.value
        .iter()
        .map(|(joint, angle)| {
            // The map's keys carry no span; the value's place is the joint's line.
            let name = S::new(joint.clone(), angle.referenced, angle.defined);
            let actuator = ctx.part(device, &name, "joint")?;
            let angle_rad = ctx.finite(angle, key)?;
            Ok((
                joint.clone(),
                JointTarget {
                    actuator,
                    angle_rad,
                },
            ))
        })
        .collect()
}

/// A `group:` step.
pub(crate) fn step(
    ctx: &Ctx<'_>,
    raw: &RawStep,
    at: Pos,
) -> Res<(&'static str, DeviceStep<GroupAction>)> {
    let RawStep::Group(s) = raw;
    let device = ctx.device(&s.device, at)?;
    let command = ctx.required(&s.command, "do", "group", at)?;
    let present: Vec<(&'static str, Pos)> = [
        ("targets_rad", s.targets_rad.as_ref().map(pos)),
        ("kp", s.kp.as_ref().map(pos)),
        ("kd", s.kd.as_ref().map(pos)),
        ("every_ms", s.every_ms.as_ref().map(pos)),
        ("window_ms", s.window_ms.as_ref().map(pos)),
        ("mode", s.mode.as_ref().map(pos)),
        ("speed_rad_s", s.speed_rad_s.as_ref().map(pos)),
    ]
    .into_iter()
    .filter_map(|(k, p)| p.map(|p| (k, p)))
    .collect();
    let (label, action) = match command.value.as_str() {
        "enable" => {
            ctx.only_arguments(&present, &[], "enable", "no arguments")?;
            ("group enable", GroupAction::Enable)
        }
        "disable" => {
            ctx.only_arguments(&present, &[], "disable", "no arguments")?;
            ("group disable", GroupAction::Disable)
        }
        "hold" => {
            let targets = step_targets(ctx, device, s, "do: hold", at)?;
            let kp = ctx.non_negative(ctx.required(&s.kp, "kp", "do: hold", at)?, "kp")?;
            let kd = ctx.non_negative(ctx.required(&s.kd, "kd", "do: hold", at)?, "kd")?;
            ctx.only_arguments(
                &present,
                &["targets_rad", "kp", "kd", "every_ms"],
                "hold",
                "targets_rad, kp, kd, every_ms",
            )?;
            let every = s
                .every_ms
                .as_ref()
                .map(|ms| ctx.positive_millis(ms, "every_ms"))
                .transpose()?;
            (
                "group hold",
                GroupAction::Hold {
                    targets,
                    kp,
                    kd,
                    every,
                },
            )
        }
        "mode" => {
            ctx.only_arguments(&present, &["mode"], "mode", "mode")?;
            let mode = ctx.choice(
                ctx.required(&s.mode, "mode", "do: mode", at)?,
                "mode",
                &[(GroupMode::Mit, "mit"), (GroupMode::Csp, "csp")],
            )?;
            ("group mode", GroupAction::Mode(mode))
        }
        "move" => {
            ctx.only_arguments(
                &present,
                &["targets_rad", "speed_rad_s"],
                "move",
                "targets_rad, speed_rad_s",
            )?;
            let targets = step_targets(ctx, device, s, "do: move", at)?;
            let speed = ctx.required(&s.speed_rad_s, "speed_rad_s", "do: move", at)?;
            let speed_rad_s = ctx.non_negative(speed, "speed_rad_s")?;
            ("group move", GroupAction::Move {
                targets,
                speed_rad_s,
            })
        }
        "watchdog" => {
            ctx.only_arguments(&present, &["window_ms"], "watchdog", "window_ms")?;
            let window = ctx.positive_millis(
                ctx.required(&s.window_ms, "window_ms", "do: watchdog", at)?,
                "window_ms",
            )?;
            ("group watchdog", GroupAction::Watchdog { window })
        }
        "release_gantry" => {
            ctx.only_arguments(&present, &[], "release_gantry", "no arguments")?;
            ("group release_gantry", GroupAction::ReleaseGantry)
        }
        other => {
            return Err(ctx.err(
                pos(command),
                format!(
                    "`do`: unknown group command `{other}`; expected one of: enable, disable, hold, watchdog, mode, move, release_gantry"
                ),
            ))
        }
    };
    Ok((
        label,
        DeviceStep {
            device,
            action,
            timeout: ctx.timeout(&s.timeout_ms)?,
            expect_error: ctx.expect_error(&s.expect_error)?,
        },
    ))
}

/// A step's required `targets_rad`, each joint resolved to its actuator.
fn step_targets(
    ctx: &Ctx<'_>,
    device: usize,
    s: &RawGroupStep,
    command: &str,
    at: Pos,
) -> Res<Vec<JointTarget>> {
    let raw = ctx.required(&s.targets_rad, "targets_rad", command, at)?;
    Ok(targets(ctx, device, raw, "targets_rad")?
        .into_iter()
        .map(|(_, t)| t)
        .collect())
}

/// The group's conditions.
pub(crate) fn checks(
    ctx: &Ctx<'_>,
    raw: &RawConds,
    device: usize,
    _step: &str,
    _at: Pos,
) -> Res<Vec<GroupCheck>> {
    let mut checks = Vec::new();
    match (&raw.joints_rad, &raw.tolerance_rad) {
        (Some(joints), Some(tolerance)) => checks.push(GroupCheck::Joints {
            targets: targets(ctx, device, joints, "joints_rad")?,
            tolerance_rad: ctx.non_negative(tolerance, "tolerance_rad")?,
        }),
        (Some(joints), None) => {
            return Err(ctx.err(pos(joints), "`joints_rad` needs `tolerance_rad`"))
        }
        (None, Some(tolerance)) => {
            return Err(ctx.err(pos(tolerance), "`tolerance_rad` needs `joints_rad`"))
        }
        (None, None) => {}
    }
    if let Some(joints) = &raw.enabled_joints {
        let mut names: Vec<String> = Vec::new();
        for joint in &joints.value {
            ctx.part(device, joint, "joint")?;
            if names.contains(&joint.value) {
                return Err(ctx.err(
                    pos(joint),
                    format!("joint `{}` is listed twice", joint.value),
                ));
            }
            names.push(joint.value.clone());
        }
        checks.push(GroupCheck::EnabledJoints(names));
    }
    match (&raw.base_height_m, &raw.tolerance_m) {
        (Some(height), Some(tolerance)) => checks.push(GroupCheck::BaseHeight {
            height_m: ctx.finite(height, "base_height_m")?,
            tolerance_m: ctx.non_negative(tolerance, "tolerance_m")?,
        }),
        (Some(height), None) => {
            return Err(ctx.err(pos(height), "`base_height_m` needs `tolerance_m`"))
        }
        (None, Some(tolerance)) => {
            return Err(ctx.err(pos(tolerance), "`tolerance_m` needs `base_height_m`"))
        }
        (None, None) => {}
    }
    Ok(checks)
}

/// `actuator_fault: {joint, fault, …}`, checked by the fault table of the joint's actuator kind
/// (the one builder its emulator uses): its names, its values (`counts`), its ranges and
/// messages, each shown at its argument.
pub(crate) fn fault(
    ctx: &Ctx<'_>,
    raw: &RawFault,
    device: Option<usize>,
    at: Pos,
) -> Res<GroupFault> {
    let RawFault::Actuator(f) = raw;
    let device = device.ok_or_else(|| {
        ctx.err(
            at,
            "the bench has several devices: say which group with `device:`",
        )
    })?;
    let joint = f
        .word("joint")
        .ok_or_else(|| ctx.err(at, "`actuator_fault` needs `joint`"))?;
    let actuator = ctx.part(device, &joint, "joint")?;
    let name = f.word("fault").ok_or_else(|| {
        ctx.err(
            at,
            "`actuator_fault` needs `fault`: one of the joint's actuator's fault names",
        )
    })?;
    let model = ctx.part_actuator(device, actuator).ok_or_else(|| {
        ctx.err(
            at,
            "`actuator_fault` names a device whose parts are not actuators",
        )
    })?;
    let kind = kind_named(model.kind)
        .ok_or_else(|| ctx.err(at, format!("an actuator of no known kind `{}`", model.kind)))?;
    let values = f.args_except(&["joint", "fault"]);
    let label = (kind.fault_label)(model.name, &name.value, &values, false).map_err(|e| {
        if e.arg.is_none() {
            ctx.err(pos(&name), e.message)
        } else {
            f.refusal(ctx, at, e)
        }
    })?;
    Ok(GroupFault {
        joint: joint.value,
        actuator,
        fault: name.value,
        args: values,
        label,
    })
}
