//! Motion commands (docs/protocols/realman.md §3–§5): planned moves, steps, teach jogs,
//! passthrough streams, and the stop family.

use super::super::kinematics::{self, Pose};
use super::super::wire::{self, ack, Obj, Req};
use super::motion::{Goal, Jog, MoveCommand, TrajectoryType};
use super::stream::Tracking;
use super::{Answer, ClientId, Controller};

/// Answer a motion command, or `None` if `name` is not one.
pub(super) fn handle(c: &mut Controller, client: ClientId, name: &str, req: Req) -> Option<Answer> {
    let reply = match name {
        "movej" | "movel" | "movej_p" | "movec" | "moves" => {
            let accepted = planned_move(c, client, name, req);
            ack(name, "receive_state", accepted)
        }
        "set_joint_step" | "set_pos_step" | "set_ort_step" => {
            let accepted = step(c, client, name, req);
            ack(name, "receive_state", accepted)
        }
        "set_joint_teach" | "set_pos_teach" | "set_ort_teach" => {
            let key = &name["set_".len()..];
            ack(name, key, teach(c, name, req))
        }
        "set_stop_teach" => {
            c.motion.set_jog(None);
            ack(name, "stop_teach", true)
        }
        "movej_canfd" | "movej_follow" | "movep_canfd" | "movep_follow" => {
            passthrough(c, name, req);
            return Some(Answer::Silent);
        }
        "set_arm_stop" => {
            c.stop(false);
            ack(name, "arm_stop", true)
        }
        "set_arm_slow_stop" => {
            c.stop(true);
            ack(name, "arm_slow_stop", true)
        }
        "set_arm_pause" => {
            c.pause();
            ack(name, "arm_pause", true)
        }
        "set_arm_continue" => ack(name, "arm_continue", c.resume()),
        "set_delete_current_trajectory" => {
            ack(name, "delete_current_trajectory", c.delete_current())
        }
        "set_arm_delete_trajectory" => ack(name, "arm_delete_trajectory", c.delete_all()),
        "get_arm_current_trajectory" => current_trajectory(c),
        _ => return None,
    };
    Some(Answer::Reply(reply))
}

/// Speed percent `v` in 1–100 (0 is taken as the slowest speed).
fn speed(req: Req) -> Option<f64> {
    let v = req.int("v")?;
    (0..=100).contains(&v).then_some(v.max(1) as f64)
}

fn pose_field(req: Req, key: &str) -> Option<Pose> {
    wire::pose_from_wire(&req.ints(key)?)
}

fn planned_move(c: &mut Controller, client: ClientId, name: &str, req: Req) -> bool {
    let Some(v) = speed(req) else {
        return false;
    };
    let connect = req.int("trajectory_connect").unwrap_or(0) != 0;
    let blend_r = req.int("r").unwrap_or(0).clamp(0, 100) as f64;
    let goal = match name {
        "movej" => match req.ints("joint") {
            Some(j) if j.len() == c.facts.dof => Some((
                Goal::Joint(j.into_iter().map(wire::mdeg_to_rad).collect()),
                TrajectoryType::MoveJ,
            )),
            _ => None,
        },
        "movel" => pose_field(req, "pose")
            .map(|p| (Goal::Linear(c.flange_target(&p)), TrajectoryType::MoveL)),
        "movej_p" => pose_field(req, "pose").and_then(|p| {
            let target = c.flange_target(&p);
            match c.solve(&target, &c.tail_rad()) {
                Ok(q) => Some((Goal::Joint(q), TrajectoryType::MoveJ)),
                Err(code) => {
                    c.errors.planning = Some(code);
                    None
                }
            }
        }),
        "movec" => req.sub("pose").and_then(|p| {
            let via = pose_field(p, "pose_via")?;
            let to = pose_field(p, "pose_to")?;
            let loops = u32::try_from(req.int("loop").unwrap_or(0)).ok()?;
            Some((
                Goal::Circle {
                    via: c.flange_target(&via),
                    to: c.flange_target(&to),
                    loops,
                },
                TrajectoryType::MoveC,
            ))
        }),
        "moves" => pose_field(req, "pose").map(|p| {
            (
                Goal::Spline(vec![c.flange_target(&p)]),
                TrajectoryType::MoveS,
            )
        }),
        _ => None,
    };
    let Some((goal, kind)) = goal else {
        return false;
    };
    let cmd = MoveCommand {
        goal,
        kind,
        speed_percent: v,
        blend_r,
        connect,
    };
    submit_or_refuse(c, client, cmd)
}

/// A single move that stops at its end (steps).
fn single(goal: Goal, kind: TrajectoryType, speed_percent: f64) -> MoveCommand {
    MoveCommand {
        goal,
        kind,
        speed_percent,
        blend_r: 0.0,
        connect: false,
    }
}

fn submit_or_refuse(c: &mut Controller, client: ClientId, cmd: MoveCommand) -> bool {
    match c.submit(client, cmd) {
        Ok(()) => true,
        Err(code) => {
            if code != 0 {
                c.errors.planning = Some(code);
            }
            tracing::debug!(code, "Realman move refused");
            false
        }
    }
}

fn step(c: &mut Controller, client: ClientId, name: &str, req: Req) -> bool {
    let Some(v) = speed(req) else {
        return false;
    };
    let tail = c.tail_rad();
    if name == "set_joint_step" {
        let Some(js) = req.ints("joint_step").filter(|s| s.len() == 2) else {
            return false;
        };
        let Some(j) = joint_index(c, js[0]) else {
            return false;
        };
        let mut to = tail;
        to[j] += wire::mdeg_to_rad(js[1]);
        let cmd = single(Goal::Joint(to), TrajectoryType::MoveJ, v);
        return submit_or_refuse(c, client, cmd);
    }
    let (Some(kind), Some(step)) = (req.str("step_type"), req.int("step")) else {
        return false;
    };
    let mut pose = c.reported_pose(&tail);
    let axis = match kind {
        "x_step" | "rx_step" => 0,
        "y_step" | "ry_step" => 1,
        "z_step" | "rz_step" => 2,
        _ => return false,
    };
    if name == "set_pos_step" && !kind.starts_with('r') {
        pose.position_m[axis] += step as f64 * 1e-6;
    } else if name == "set_ort_step" && kind.starts_with('r') {
        pose.euler_rad[axis] += step as f64 * 1e-3;
    } else {
        return false;
    }
    let goal = Goal::Linear(c.flange_target(&pose));
    submit_or_refuse(c, client, single(goal, TrajectoryType::MoveL, v))
}

fn joint_index(c: &Controller, joint: i64) -> Option<usize> {
    let j = usize::try_from(joint).ok()?;
    (1..=c.facts.dof).contains(&j).then(|| j - 1)
}

fn teach(c: &mut Controller, name: &str, req: Req) -> bool {
    let (Some(v), Some(dir)) = (speed(req), req.str("direction")) else {
        return false;
    };
    let sign = match dir {
        "pos" => 1.0,
        "neg" => -1.0,
        _ => return false,
    };
    if !c.can_move() || c.motion.busy() {
        return false;
    }
    let fraction = sign * v / 100.0;
    let jog = match name {
        "set_joint_teach" => {
            let Some(j) = req.int("teach_joint").and_then(|j| joint_index(c, j)) else {
                return false;
            };
            Jog::Joint {
                joint: j,
                speed_rad_s: fraction * c.params.max_speed_deg_s[j].to_radians(),
            }
        }
        _ => {
            let axis = match req.str("teach_type") {
                Some("x" | "rx") => 0,
                Some("y" | "ry") => 1,
                Some("z" | "rz") => 2,
                _ => return false,
            };
            if name == "set_pos_teach" {
                Jog::Position {
                    axis,
                    speed_m_s: fraction * c.params.line_speed_m_s,
                }
            } else {
                Jog::Orientation {
                    axis,
                    speed_rad_s: fraction * c.params.angular_speed_rad_s,
                }
            }
        }
    };
    c.motion.set_jog(Some(jog));
    true
}

/// Passthrough frames get no reply on a 3rd-gen controller; an unusable frame is ignored.
fn passthrough(c: &mut Controller, name: &str, req: Req) {
    if !c.can_move() || c.motion.busy() {
        tracing::debug!(
            command = name,
            "Realman passthrough frame ignored: arm not ready"
        );
        return;
    }
    let seed = c.setpoint_rad.clone();
    let target = if name.starts_with("movej") {
        req.ints("joint")
            .filter(|j| j.len() == c.facts.dof)
            .map(|j| j.into_iter().map(wire::mdeg_to_rad).collect::<Vec<f64>>())
    } else {
        let pose = req
            .ints("pose")
            .and_then(|p| wire::pose_from_wire(&p))
            .or_else(|| {
                req.ints("pose_quat")
                    .and_then(|p| wire::pose_from_quat_wire(&p))
            });
        pose.and_then(|p| kinematics::inverse(&c.model, &c.flange_target(&p), &seed).ok())
    };
    match target {
        Some(t) => {
            let status = if name.starts_with("movej") {
                "move_through_joint"
            } else {
                "move_through_pose"
            };
            // High follow (`follow: true` on a passthrough frame) bypasses the online planner.
            let tracking = if name.ends_with("_canfd") && req.bool("follow") == Some(true) {
                Tracking::Direct
            } else {
                Tracking::Planned
            };
            c.motion.set_stream(t, status, tracking);
        }
        None => tracing::debug!(
            command = name,
            "Realman passthrough frame ignored: bad target"
        ),
    }
}

fn current_trajectory(c: &Controller) -> String {
    let kind = c.motion.current_type();
    let data: Vec<i64> = if kind.reports_pose() {
        c.pose_wire().to_vec()
    } else {
        c.joints_mdeg()
    };
    Obj::state("arm_current_trajectory")
        .str("type", kind.wire())
        .ints("data", &data)
        .finish()
}
