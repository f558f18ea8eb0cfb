//! State queries, power and enable, errors, identity, frames and install pose
//! (docs/protocols/realman.md §6, §7).

use super::super::faults::codes;
use super::super::params::{rules, Frame};
use super::super::wire::{self, ack, Obj, Req};
use super::{Answer, Controller};

/// Answer a state / power / frame command, or `None` if `name` is not one.
pub(super) fn handle(c: &mut Controller, name: &str, req: Req) -> Option<Answer> {
    let reply = match name {
        "get_arm_software_info" => software_info(c),
        "get_current_arm_state" => c.arm_state_reply(),
        "get_joint_degree" => Obj::state("joint_degree")
            .ints("joint", &c.joints_mdeg())
            .finish(),
        "get_arm_all_state" => all_state(c),
        "get_joint_err_flag" => {
            let brakes: Vec<i64> = c.enabled.iter().map(|e| i64::from(!*e)).collect();
            Obj::state("joint_err_flag")
                .ints("err_flag", &c.err_flags())
                .ints("brake_state", &brakes)
                .finish()
        }
        "get_controller_state" => Obj::state("controller_state")
            .int("voltage", 24_000)
            .int("current", if c.power_on { 1_500 } else { 300 })
            .int("temperature", 42_000)
            .int("err_flag", 0)
            .finish(),
        "get_current_joint_temperature" => Obj::state("current_joint_temperature")
            .ints("joint_temperature", &c.temperatures_milli())
            .finish(),
        "get_current_joint_current" => Obj::state("current_joint_current")
            .ints("joint_current", &c.currents_milli())
            .finish(),
        "get_current_joint_voltage" => Obj::state("current_joint_voltage")
            .ints("joint_voltage", &c.voltages_milli())
            .finish(),
        "get_arm_power_state" => Obj::state("arm_power_state")
            .int("power_state", i64::from(c.power_on))
            .finish(),
        "set_arm_power" => match req.int("arm_power") {
            Some(p @ (0 | 1)) if !c.estop || p == 0 => {
                c.set_power(p == 1);
                ack(name, "arm_power", true)
            }
            _ => ack(name, "arm_power", false),
        },
        "get_joint_en_state" => Obj::state("joint_en_state")
            .ints("en_state", &c.en_flags())
            .finish(),
        "set_joint_en_state" => ack(name, "joint_en_state", set_enable(c, req)),
        "clear_system_err" => {
            clear_system_err(c);
            ack(name, "clear_state", true)
        }
        "set_joint_clear_err" => {
            let ok = match req
                .int("joint_clear_err")
                .and_then(|j| usize::try_from(j).ok())
            {
                Some(j) if (1..=c.facts.dof).contains(&j) => {
                    c.joint_err[j - 1] = 0;
                    true
                }
                _ => false,
            };
            ack(name, "joint_clear_err", ok)
        }
        "get_arm_plan_num" => Obj::state("arm_plan_num")
            .int("plan_num", c.motion.plan_count() as i64)
            .ints("loop_num", &[])
            .ints("loop_cont", &[])
            .finish(),
        "get_current_tool_frame" => tool_frame(c.params.tool_frames.get(c.params.current_tool)),
        "get_current_work_frame" => work_frame(c.params.work_frames.get(c.params.current_work)),
        "get_total_tool_frame" => {
            let names: Vec<&str> = c
                .params
                .tool_frames
                .iter()
                .map(|f| f.name.as_str())
                .collect();
            Obj::state("total_tool_frame")
                .strs("tool_names", &names)
                .finish()
        }
        "get_total_work_frame" => {
            let names: Vec<&str> = c
                .params
                .work_frames
                .iter()
                .map(|f| f.name.as_str())
                .collect();
            Obj::state("total_work_frame")
                .strs("work_names", &names)
                .finish()
        }
        "set_change_tool_frame" => ack(name, "change_tool_frame", change_frame(c, req, true)),
        "set_change_work_frame" => ack(name, "change_work_frame", change_frame(c, req, false)),
        "set_manual_tool_frame" => ack(name, "manual_tool_frame", manual_tool_frame(c, req)),
        "set_delete_tool_frame" => ack(name, "delete_tool_frame", delete_tool_frame(c, req)),
        "get_install_pose" => {
            let p = c.params.install_pose_deg.map(|d| d.round() as i64);
            Obj::state("install_pose").ints("pose", &p).finish()
        }
        "set_install_pose" => {
            let ok = match req.ints("pose") {
                Some(p) if p.len() == 3 => {
                    c.params.install_pose_deg = [p[0] as f64, p[1] as f64, p[2] as f64];
                    true
                }
                _ => false,
            };
            ack(name, "set_state", ok)
        }
        _ => return None,
    };
    Some(Answer::Reply(reply))
}

fn software_info(c: &Controller) -> String {
    let fw = c.profile;
    Obj::command("arm_software_info")
        .str("Product_version", &c.facts.product)
        .obj("algorithm_info", Obj::new().str("version", "1.4.3"))
        .obj(
            "ctrl_info",
            Obj::new()
                .str("build_time", "2024-10-15 10:00:00")
                .str("version", fw.ctrl_version()),
        )
        .obj("dynamic_info", Obj::new().str("model_version", "1.0"))
        .obj(
            "plan_info",
            Obj::new()
                .str("build_time", "2024-10-15 10:00:00")
                .str("version", fw.plan_version()),
        )
        .finish()
}

fn all_state(c: &Controller) -> String {
    let inner = Obj::new()
        .ints("temperature", &c.temperatures_milli())
        .ints("current", &c.currents_milli())
        .ints("voltage", &c.voltages_milli())
        .ints("err_flag", &c.err_flags())
        .ints("en_flag", &c.en_flags());
    let inner = if c.profile.err_array() {
        c.with_errors(inner)
    } else {
        let sys = c.errors.codes().first().copied().unwrap_or(0);
        inner.int("sys_err", i64::from(sys))
    };
    Obj::state("arm_all_state").obj("all_state", inner).finish()
}

fn set_enable(c: &mut Controller, req: Req) -> bool {
    let Some(v) = req.ints("joint_en_state").filter(|v| v.len() == 2) else {
        return false;
    };
    let Some(j) = usize::try_from(v[0])
        .ok()
        .filter(|j| (1..=c.facts.dof).contains(j))
    else {
        return false;
    };
    let on = v[1] != 0;
    if on && (!c.power_on || c.joint_err[j - 1] != 0 || c.estop) {
        return false;
    }
    if !on && c.motion.busy() {
        c.abort_motion();
    }
    c.enabled[j - 1] = on;
    c.plant.set_enabled(j - 1, on);
    true
}

/// Clear every error whose cause is gone.
fn clear_system_err(c: &mut Controller) {
    c.errors.planning = None;
    let joint_ok = c.joint_err.iter().all(|e| *e == 0);
    let estop = c.estop;
    let gripper_ok = c.gripper.as_ref().is_none_or(|g| g.error_bits == 0);
    c.errors.latched.retain(|code| match *code {
        codes::JOINT_COMM => !joint_ok,
        codes::JOINT_DISABLED => estop,
        codes::GRIPPER => !gripper_ok,
        _ => false,
    });
}

fn tool_frame(frame: Option<&Frame>) -> String {
    let Some(f) = frame else {
        return Obj::state("current_tool_frame").finish();
    };
    Obj::state("current_tool_frame")
        .str("tool_name", &f.name)
        .ints("pose", &frame_pose(f))
        .int("payload", wire::milli(f.payload_kg))
        .ints("position", &f.com_m.map(wire::m_to_um))
        .finish()
}

fn work_frame(frame: Option<&Frame>) -> String {
    let Some(f) = frame else {
        return Obj::state("current_work_frame").finish();
    };
    Obj::state("current_work_frame")
        .str("frame_name", &f.name)
        .ints("pose", &frame_pose(f))
        .finish()
}

fn frame_pose(f: &Frame) -> [i64; 6] {
    [
        wire::m_to_um(f.position_m[0]),
        wire::m_to_um(f.position_m[1]),
        wire::m_to_um(f.position_m[2]),
        wire::milli(f.euler_rad[0]),
        wire::milli(f.euler_rad[1]),
        wire::milli(f.euler_rad[2]),
    ]
}

fn change_frame(c: &mut Controller, req: Req, tool: bool) -> bool {
    let key = if tool { "tool_name" } else { "frame_name" };
    let Some(wanted) = req.str(key) else {
        return false;
    };
    if c.motion.busy() {
        return false;
    }
    let frames = if tool {
        &c.params.tool_frames
    } else {
        &c.params.work_frames
    };
    match frames.iter().position(|f| f.name == wanted) {
        Some(i) if tool => c.params.current_tool = i,
        Some(i) => c.params.current_work = i,
        None => {
            c.errors.planning = Some(if tool {
                codes::NO_TOOL_FRAME
            } else {
                codes::NO_WORK_FRAME
            });
            return false;
        }
    }
    true
}

fn manual_tool_frame(c: &mut Controller, req: Req) -> bool {
    let (Some(name), Some(pose)) = (req.str("tool_name"), req.ints("tool_pose")) else {
        return false;
    };
    let Some(pose) = wire::pose_from_wire(&pose) else {
        return false;
    };
    let com = req
        .ints("position")
        .filter(|p| p.len() == 3)
        .unwrap_or(vec![0, 0, 0]);
    let frame = Frame {
        name: name.into(),
        position_m: pose.position_m,
        euler_rad: pose.euler_rad,
        payload_kg: req.int("payload").unwrap_or(0) as f64 / 1000.0,
        com_m: [
            com[0] as f64 * 1e-6,
            com[1] as f64 * 1e-6,
            com[2] as f64 * 1e-6,
        ],
    };
    let bad_name = !rules::frame_name(name);
    let exists = c.params.tool_frames.iter().any(|f| f.name == name);
    if bad_name || exists || c.params.tool_frames.len() >= rules::MAX_TOOL_FRAMES {
        return false;
    }
    c.params.tool_frames.push(frame);
    true
}

fn delete_tool_frame(c: &mut Controller, req: Req) -> bool {
    let Some(name) = req.str("tool_name") else {
        return false;
    };
    // The default frame and the frame in use cannot be deleted.
    match c.params.tool_frames.iter().position(|f| f.name == name) {
        Some(i) if i != 0 && i != c.params.current_tool => {
            c.params.tool_frames.remove(i);
            if c.params.current_tool > i {
                c.params.current_tool -= 1;
            }
            true
        }
        _ => false,
    }
}
