//! Layer 2 of the Realman grammar: the `realman` device kind, the `realman:` step, the arm
//! conditions and the emulator faults.

use sim::realman::{RealmanFault, RealmanFaultKind};

use super::model::{
    Motion, PoseDeg, RealmanAction, RealmanSettings, RmCommand, RmCond, RmFault, ARM_STATES,
    ERRORS, MODELS,
};
use super::raw::{RawConds, RawFault, RawRmStep, RawSettings, RawStep};
use crate::devices::Action;
use crate::harness::error::Pos;
use crate::harness::model::{ErrorClass, Near, StepKind};
use crate::harness::raw::S;
use crate::harness::validate::{pos, Ctx, Res};

/// Default tolerances of the conditions.
const DEFAULT_TOLERANCE_DEG: f64 = 0.05;
const DEFAULT_TOLERANCE_M: f64 = 0.001;
const DEFAULT_TOLERANCE_HZ: f64 = 2.0;
/// Most driver connections a scenario may open.
const MAX_CLIENTS: i64 = 4;

/// The settings of a `kind: realman` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, _at: Pos) -> Res<RealmanSettings> {
    let model = match &d.model {
        Some(m) => ctx.choice(m, "model", &MODELS)?,
        None => "RM65-B",
    };
    let dof = if model == "RM75-B" { 7 } else { 6 };
    let initial_joints_deg = match &d.initial_joints_deg {
        Some(j) => Some(joints(ctx, j, "initial_joints_deg", dof)?),
        None => None,
    };
    let clients = match &d.clients {
        Some(c) if (1..=MAX_CLIENTS).contains(&c.value) => c.value as usize,
        Some(c) => {
            return Err(ctx.err(
                pos(c),
                format!(
                    "`clients`: {} out of range, expected 1..={MAX_CLIENTS}",
                    c.value
                ),
            ))
        }
        None => 1,
    };
    Ok(RealmanSettings {
        model,
        initial_joints_deg,
        gripper: d.gripper.as_ref().is_none_or(|g| g.value),
        clients,
    })
}

fn joints(ctx: &Ctx<'_>, v: &S<Vec<f64>>, key: &str, dof: usize) -> Res<Vec<f64>> {
    if v.value.len() != dof || v.value.iter().any(|x| !x.is_finite()) {
        return Err(ctx.err(
            pos(v),
            format!(
                "`{key}` needs {dof} finite angles (degrees), got {:?}",
                v.value
            ),
        ));
    }
    Ok(v.value.clone())
}

fn int_in(ctx: &Ctx<'_>, v: &S<i64>, key: &str, lo: i64, hi: i64) -> Res<i64> {
    if (lo..=hi).contains(&v.value) {
        Ok(v.value)
    } else {
        Err(ctx.err(
            pos(v),
            format!("`{key}`: {} out of range, expected {lo}..={hi}", v.value),
        ))
    }
}

/// Which argument keys each command takes (`client` aside).
const COMMAND_KEYS: [(&str, &[&str]); 21] = [
    ("handshake", &[]),
    ("movej", &["joints_deg", "speed", "blend", "queue", "block"]),
    (
        "movel",
        &[
            "position_m",
            "euler_deg",
            "speed",
            "blend",
            "queue",
            "block",
        ],
    ),
    ("movej_p", &["position_m", "euler_deg", "speed", "block"]),
    (
        "movec",
        &[
            "via_position_m",
            "via_euler_deg",
            "position_m",
            "euler_deg",
            "loops",
            "speed",
            "block",
        ],
    ),
    ("stop", &[]),
    ("slow_stop", &[]),
    ("pause", &[]),
    ("continue", &[]),
    ("delete_trajectories", &[]),
    ("clear_errors", &[]),
    ("power", &["on"]),
    ("push", &["period_ms", "enable"]),
    ("gripper_position", &["position", "block"]),
    ("gripper_pick", &["speed", "force", "block"]),
    ("gripper_release", &["speed", "block"]),
    ("read_gripper", &["expect", "tolerance"]),
    ("hand_posture", &["posture", "block"]),
    ("hand_angles", &["angles", "block"]),
    ("read_joints", &[]),
    ("reconnect", &[]),
];

fn present_keys(a: &RawRmStep) -> Vec<(&'static str, Pos)> {
    let mut out = Vec::new();
    macro_rules! keys {
        ($($field:ident),* $(,)?) => {
            $(if let Some(v) = &a.$field { out.push((stringify!($field), pos(v))); })*
        };
    }
    keys!(
        joints_deg,
        position_m,
        euler_deg,
        via_position_m,
        via_euler_deg,
        loops,
        speed,
        blend,
        queue,
        block,
        position,
        force,
        posture,
        angles,
        period_ms,
        enable,
        on,
        expect,
        tolerance,
    );
    out
}

/// A Realman step.
pub(crate) fn step(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<(&'static str, StepKind)> {
    match raw {
        RawStep::Realman(a) => realman_step(ctx, a, at),
    }
}

fn pose(
    ctx: &Ctx<'_>,
    position: &Option<S<Vec<f64>>>,
    euler: &Option<S<Vec<f64>>>,
    names: (&str, &str),
    command: &str,
    at: Pos,
) -> Res<PoseDeg> {
    let p = ctx.required(position, names.0, command, at)?;
    let e = ctx.required(euler, names.1, command, at)?;
    Ok(PoseDeg {
        position_m: ctx.array::<3>(p, names.0)?,
        euler_deg: ctx.array::<3>(e, names.1)?,
    })
}

fn motion(ctx: &Ctx<'_>, a: &RawRmStep) -> Res<Motion> {
    let speed = match &a.speed {
        Some(s) => int_in(ctx, s, "speed", 1, 100)? as u8,
        None => 20,
    };
    let blend = match &a.blend {
        Some(b) => int_in(ctx, b, "blend", 0, 100)? as u8,
        None => 0,
    };
    Ok(Motion {
        speed,
        blend,
        queue: a.queue.as_ref().is_some_and(|q| q.value),
        block: a.block.as_ref().is_none_or(|b| b.value),
    })
}

fn command(ctx: &Ctx<'_>, a: &RawRmStep, name: &str, at: Pos) -> Res<RmCommand> {
    let block = a.block.as_ref().is_none_or(|b| b.value);
    let unit = |v: &Option<S<i64>>, key: &str, lo: i64, default: i64| -> Res<u16> {
        v.as_ref()
            .map_or(Ok(default), |v| int_in(ctx, v, key, lo, 1000))
            .map(|x| x as u16)
    };
    Ok(match name {
        "handshake" => RmCommand::Handshake,
        "movej" => {
            let j = ctx.required(&a.joints_deg, "joints_deg", name, at)?;
            let dof = j.value.len().clamp(6, 7);
            RmCommand::MoveJ(joints(ctx, j, "joints_deg", dof)?, motion(ctx, a)?)
        }
        "movel" => RmCommand::MoveL(
            pose(
                ctx,
                &a.position_m,
                &a.euler_deg,
                ("position_m", "euler_deg"),
                name,
                at,
            )?,
            motion(ctx, a)?,
        ),
        "movej_p" => RmCommand::MoveJP(
            pose(
                ctx,
                &a.position_m,
                &a.euler_deg,
                ("position_m", "euler_deg"),
                name,
                at,
            )?,
            motion(ctx, a)?,
        ),
        "movec" => RmCommand::MoveC {
            via: pose(
                ctx,
                &a.via_position_m,
                &a.via_euler_deg,
                ("via_position_m", "via_euler_deg"),
                name,
                at,
            )?,
            to: pose(
                ctx,
                &a.position_m,
                &a.euler_deg,
                ("position_m", "euler_deg"),
                name,
                at,
            )?,
            loops: a
                .loops
                .as_ref()
                .map_or(Ok(0), |l| int_in(ctx, l, "loops", 0, 100))? as u32,
            motion: motion(ctx, a)?,
        },
        "stop" => RmCommand::Stop,
        "slow_stop" => RmCommand::SlowStop,
        "pause" => RmCommand::Pause,
        "continue" => RmCommand::Continue,
        "delete_trajectories" => RmCommand::DeleteTrajectories,
        "clear_errors" => RmCommand::ClearErrors,
        "power" => RmCommand::Power(ctx.required(&a.on, "on", name, at)?.value),
        "push" => {
            let p = ctx.required(&a.period_ms, "period_ms", name, at)?;
            let period_ms = int_in(ctx, p, "period_ms", 5, 500)?;
            if period_ms % 5 != 0 {
                return Err(ctx.err(pos(p), "`period_ms` must be a multiple of 5"));
            }
            RmCommand::Push {
                period_ms: period_ms as u32,
                enable: a.enable.as_ref().is_none_or(|e| e.value),
            }
        }
        "gripper_position" => RmCommand::GripperPosition {
            position: int_in(
                ctx,
                ctx.required(&a.position, "position", name, at)?,
                "position",
                1,
                1000,
            )? as u16,
            block,
        },
        "gripper_pick" => RmCommand::GripperPick {
            speed: unit(&a.speed, "speed", 1, 500)?,
            force: unit(&a.force, "force", 50, 200)?,
            block,
        },
        "gripper_release" => RmCommand::GripperRelease {
            speed: unit(&a.speed, "speed", 1, 500)?,
            block,
        },
        "read_gripper" => RmCommand::ReadGripper {
            expect: match &a.expect {
                Some(e) => Some(Near {
                    value: ctx.finite(e, "expect")?,
                    tolerance: a
                        .tolerance
                        .as_ref()
                        .map_or(Ok(5.0), |t| ctx.non_negative(t, "tolerance"))?,
                }),
                None => None,
            },
        },
        "hand_posture" => RmCommand::HandPosture {
            posture: int_in(
                ctx,
                ctx.required(&a.posture, "posture", name, at)?,
                "posture",
                1,
                40,
            )? as u8,
            block,
        },
        "hand_angles" => {
            let v = ctx.required(&a.angles, "angles", name, at)?;
            if v.value.len() != 6 || v.value.iter().any(|x| !(-1..=1000).contains(x)) {
                return Err(ctx.err(
                    pos(v),
                    "`angles` needs 6 values in 0..=1000 (-1 keeps a finger)",
                ));
            }
            let mut angles = [None; 6];
            for (slot, x) in angles.iter_mut().zip(&v.value) {
                *slot = u16::try_from(*x).ok();
            }
            RmCommand::HandAngles { angles, block }
        }
        "read_joints" => RmCommand::ReadJoints,
        _ => RmCommand::Reconnect,
    })
}

/// A `realman:` step.
fn realman_step(ctx: &Ctx<'_>, a: &RawRmStep, at: Pos) -> Res<(&'static str, StepKind)> {
    let names: Vec<&str> = COMMAND_KEYS.iter().map(|(n, _)| *n).collect();
    let Some(cmd) = &a.command else {
        return Err(ctx.err(
            at,
            format!("`realman` needs `do:` with one of: {}", names.join(", ")),
        ));
    };
    let table: Vec<(&str, &str)> = names.iter().map(|n| (*n, *n)).collect();
    let name = ctx.choice(cmd, "do", &table)?;
    let allowed = COMMAND_KEYS
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(&[][..], |(_, k)| *k);
    for (key, key_at) in present_keys(a) {
        if !allowed.contains(&key) {
            let takes = if allowed.is_empty() {
                "no arguments besides `client`".to_owned()
            } else {
                allowed.join(", ")
            };
            return Err(ctx.err(
                key_at,
                format!("`{key}` does not apply to `do: {name}`; it takes: {takes}"),
            ));
        }
    }
    let command = command(ctx, a, name, at)?;
    let client = match &a.client {
        Some(c) => int_in(ctx, c, "client", 1, MAX_CLIENTS)? as usize - 1,
        None => 0,
    };
    let device = ctx.device_of_kind(&a.device, at, "realman", "this step")?;
    let timeout = a
        .timeout_ms
        .as_ref()
        .map(|t| ctx.positive_millis(t, "timeout_ms"))
        .transpose()?;
    let expect_error = a
        .expect_error
        .as_ref()
        .map(|e| ctx.choice(e, "expect_error", &ErrorClass::NAMES))
        .transpose()?;
    let label = LABELS
        .iter()
        .find(|(n, _)| *n == name)
        .map_or("realman", |(_, l)| l);
    Ok((
        label,
        StepKind::Action {
            device,
            action: Action::Realman(RealmanAction { client, command }),
            timeout,
            expect_error,
        },
    ))
}

/// Step labels for reports.
const LABELS: [(&str, &str); 21] = [
    ("handshake", "realman handshake"),
    ("movej", "realman movej"),
    ("movel", "realman movel"),
    ("movej_p", "realman movej_p"),
    ("movec", "realman movec"),
    ("stop", "realman stop"),
    ("slow_stop", "realman slow_stop"),
    ("pause", "realman pause"),
    ("continue", "realman continue"),
    ("delete_trajectories", "realman delete_trajectories"),
    ("clear_errors", "realman clear_errors"),
    ("power", "realman power"),
    ("push", "realman push"),
    ("gripper_position", "realman gripper_position"),
    ("gripper_pick", "realman gripper_pick"),
    ("gripper_release", "realman gripper_release"),
    ("read_gripper", "realman read_gripper"),
    ("hand_posture", "realman hand_posture"),
    ("hand_angles", "realman hand_angles"),
    ("read_joints", "realman read_joints"),
    ("reconnect", "realman reconnect"),
];

/// A Realman emulator fault with its arguments.
pub(crate) fn fault(ctx: &Ctx<'_>, raw: &RawFault, at: Pos) -> Res<RmFault> {
    let a = &raw.args;
    let name = raw.kind.name();
    let int = |v: &Option<S<i64>>, key: &str, lo: i64, hi: i64| -> Res<i64> {
        int_in(ctx, ctx.required(v, key, name, at)?, key, lo, hi)
    };
    let f = match raw.kind {
        RealmanFaultKind::ConnectionDrop => RealmanFault::ConnectionDrop { peer_ip: None },
        RealmanFaultKind::ReplyDelay => RealmanFault::ReplyDelay {
            delay_ms: int(&a.delay_ms, "delay_ms", 1, 60_000)? as u64,
        },
        RealmanFaultKind::MalformedReply => RealmanFault::MalformedReply {
            count: int(&a.count, "count", 1, 1000)? as u32,
        },
        RealmanFaultKind::UdpLoss => RealmanFault::UdpLoss {
            permille: int(&a.permille, "permille", 0, 1000)? as u16,
        },
        RealmanFaultKind::UdpReorder => RealmanFault::UdpReorder,
        RealmanFaultKind::JointError => RealmanFault::JointError {
            joint: int(&a.joint, "joint", 1, 7)? as u8,
            code: int(&a.code, "code", 1, 0xFFFF)? as u16,
        },
        RealmanFaultKind::PowerLoss => RealmanFault::PowerLoss,
        RealmanFaultKind::Collision => RealmanFault::Collision,
        RealmanFaultKind::EStop => RealmanFault::EStop,
        RealmanFaultKind::GripperFault => RealmanFault::GripperFault {
            bits: int(&a.bits, "bits", 1, 0xFF)? as u8,
        },
    };
    Ok(RmFault(f))
}

/// The arm conditions of `expect` / `wait_until`.
pub(crate) fn checks(ctx: &Ctx<'_>, c: &RawConds, step: &str, at: Pos) -> Res<Vec<RmCond>> {
    let mut out = Vec::new();
    let tol = |t: &Option<S<f64>>, key: &str, default: f64| {
        t.as_ref().map_or(Ok(default), |t| ctx.non_negative(t, key))
    };
    if let Some(j) = &c.joints_deg {
        let dof = j.value.len().clamp(6, 7);
        out.push(RmCond::Joints(
            joints(ctx, j, "joints_deg", dof)?,
            tol(&c.tolerance_deg, "tolerance_deg", DEFAULT_TOLERANCE_DEG)?,
        ));
    }
    if let Some(p) = &c.position_m {
        out.push(RmCond::Position(
            ctx.array::<3>(p, "position_m")?,
            tol(&c.tolerance_m, "tolerance_m", DEFAULT_TOLERANCE_M)?,
        ));
    }
    if let Some(s) = &c.arm_state {
        let table: Vec<(&'static str, &str)> = ARM_STATES.iter().map(|n| (*n, *n)).collect();
        out.push(RmCond::ArmState(ctx.choice(s, "arm_state", &table)?));
    }
    if let Some(list) = &c.errors {
        let mut names = Vec::new();
        for e in &list.value {
            let table: Vec<(&'static str, &str)> = ERRORS.iter().map(|(n, _)| (*n, *n)).collect();
            names.push(ctx.choice(e, "errors", &table)?);
        }
        // In table order, as the observation lists them.
        let ordered = ERRORS
            .iter()
            .map(|(n, _)| *n)
            .filter(|n| names.contains(n))
            .collect();
        out.push(RmCond::Errors(ordered));
    }
    if let Some(e) = &c.joints_enabled {
        out.push(RmCond::Enabled(e.value.clone()));
    }
    if let Some(h) = &c.push_hz {
        out.push(RmCond::PushHz(Near {
            value: ctx.non_negative(h, "push_hz")?,
            tolerance: tol(&c.tolerance_hz, "tolerance_hz", DEFAULT_TOLERANCE_HZ)?,
        }));
    }
    if let Some(k) = &c.connected {
        out.push(RmCond::Connected(k.value));
    }
    if out.is_empty() {
        return Err(ctx.err(at, format!("`{step}` has no condition")));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use sim::realman::RealmanFault;

    use crate::devices::realman::model::{RmCommand, RmCond};
    use crate::devices::{Action, Check, DeviceKind};
    use crate::harness::model::StepKind;
    use crate::harness::parse_scenario;
    use crate::harness::test_support::error_of;

    const BENCH: &str = "bench:\n  devices:\n    arm: {kind: realman, clients: 2}\n";

    #[test]
    fn a_valid_bench_step_condition_and_fault_are_typed() {
        let text = format!(
            "{BENCH}faults:\n  - {{at_ms: 100, for_ms: 50, fault: {{reply_delay: {{delay_ms: 600}}}}}}\nsteps:\n  - realman: {{do: movej, joints_deg: [10, 20, 30, 40, 50, 60], speed: 30, blend: 20, queue: true, client: 2}}\n  - wait_until: {{joints_deg: [10, 20, 30, 40, 50, 60], arm_state: idle, errors: [collision, beyond_joint_limit], timeout_ms: 100}}\n"
        );
        let s = parse_scenario(Path::new("ok.yaml"), &text).expect("valid");
        let DeviceKind::Realman(settings) = &s.bench.devices[0].kind else {
            panic!("not a realman device");
        };
        assert_eq!((settings.model, settings.clients), ("RM65-B", 2));
        let StepKind::Action {
            action: Action::Realman(a),
            ..
        } = &s.steps[0].kind
        else {
            panic!("not a realman action");
        };
        assert_eq!(a.client, 1);
        let RmCommand::MoveJ(j, m) = &a.command else {
            panic!("not movej: {:?}", a.command);
        };
        assert_eq!(j[5], 60.0);
        assert!(m.queue && m.block && m.speed == 30 && m.blend == 20);
        let StepKind::WaitUntil { checks, .. } = &s.steps[1].kind else {
            panic!("not wait_until");
        };
        // Error names come back in table (code) order.
        assert!(checks.contains(&Check::Realman(RmCond::Errors(vec![
            "beyond_joint_limit",
            "collision"
        ]))));
        assert!(s.faults[0]
            .fault
            .describe()
            .starts_with("reply_delay 600 ms ("));
        let crate::harness::model::FaultSpec::Emulator {
            fault: crate::devices::DeviceFault::Realman(f),
            ..
        } = &s.faults[0].fault
        else {
            panic!("not a realman fault");
        };
        assert_eq!(f.0, RealmanFault::ReplyDelay { delay_ms: 600 });
    }

    #[test]
    fn bad_arguments_are_errors_at_their_position() {
        let e = error_of(&format!(
            "{BENCH}steps:\n  - realman: {{do: movej, joints_deg: [1, 2, 3], speed: 30}}\n"
        ));
        assert!(
            e.starts_with("broken.yaml:5:") && e.contains("`joints_deg` needs 6"),
            "{e}"
        );
        let e = error_of(&format!(
            "{BENCH}steps:\n  - realman: {{do: movej, joints_deg: [0, 0, 0, 0, 0, 0], speed: 101}}\n"
        ));
        assert!(
            e.contains("`speed`: 101 out of range, expected 1..=100"),
            "{e}"
        );
        let e = error_of(&format!(
            "{BENCH}steps:\n  - realman: {{do: pause, speed: 3}}\n"
        ));
        assert!(e.contains("`speed` does not apply to `do: pause`"), "{e}");
        let e = error_of(&format!(
            "{BENCH}steps:\n  - realman: {{do: push, period_ms: 7}}\n"
        ));
        assert!(e.contains("multiple of 5"), "{e}");
        let e = error_of(&format!(
            "{BENCH}steps:\n  - realman: {{do: read_joints, client: 5}}\n"
        ));
        assert!(e.contains("`client`: 5 out of range"), "{e}");
        let e = error_of(&format!(
            "{BENCH}faults:\n  - {{at_ms: 5, fault: {{joint_error: {{joint: 3}}}}}}\nsteps:\n  - wait_ms: 1\n"
        ));
        assert!(e.contains("`joint_error` needs `code`"), "{e}");
        let e = error_of(&format!(
            "{BENCH}steps:\n  - expect: {{arm_state: dancing}}\n"
        ));
        assert!(e.contains("`arm_state`: unknown value `dancing`"), "{e}");
    }
}
