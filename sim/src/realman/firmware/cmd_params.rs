//! Motion parameters (end-effector limits, collision stage, DH, zero offsets), joint limits,
//! speeds and accelerations, and parameter saving (docs/protocols/realman.md §8, §9).

use super::super::facts::DhRow;
use super::super::params::{self, rules};
use super::super::wire::{self, ack, Obj, Req};
use super::{Answer, Controller};

/// 1 RPM of a joint's output = 6 °/s.
const DEG_S_PER_RPM: f64 = 6.0;

/// Answer a parameter command, or `None` if `name` is not one.
pub(super) fn handle(c: &mut Controller, name: &str, req: Req) -> Option<Answer> {
    let reply = match name {
        "set_arm_max_line_speed" => {
            set_milli(name, req, "arm_line_speed", &mut c.params.line_speed_m_s)
        }
        "set_arm_max_line_acc" => set_milli(name, req, "arm_line_acc", &mut c.params.line_acc_m_s2),
        "set_arm_max_angular_speed" => set_milli(
            name,
            req,
            "arm_angular_speed",
            &mut c.params.angular_speed_rad_s,
        ),
        "set_arm_max_angular_acc" => set_milli(
            name,
            req,
            "arm_angular_acc",
            &mut c.params.angular_acc_rad_s2,
        ),
        "get_arm_max_line_speed" => get_milli(
            "arm_max_line_speed",
            "arm_line_speed",
            c.params.line_speed_m_s,
        ),
        "get_arm_max_line_acc" => {
            get_milli("arm_max_line_acc", "arm_line_acc", c.params.line_acc_m_s2)
        }
        "get_arm_max_angular_speed" => get_milli(
            "arm_max_angular_speed",
            "arm_angular_speed",
            c.params.angular_speed_rad_s,
        ),
        "get_arm_max_angular_acc" => get_milli(
            "arm_max_angular_acc",
            "arm_angular_acc",
            c.params.angular_acc_rad_s2,
        ),
        "set_arm_init" => {
            c.params.line_speed_m_s = params::INIT_LINE_SPEED_M_S;
            c.params.line_acc_m_s2 = params::INIT_LINE_ACC_M_S2;
            c.params.angular_speed_rad_s = params::INIT_ANGULAR_SPEED_RAD_S;
            c.params.angular_acc_rad_s2 = params::INIT_ANGULAR_ACC_RAD_S2;
            return Some(Answer::Reply(ack(name, "arm_init", true)));
        }
        _ => return handle_more(c, name, req),
    };
    Some(Answer::Reply(reply))
}

/// `{"command":<name>,key:ok}` with the value (a positive 0.001-unit integer) stored in SI.
fn set_milli(name: &str, req: Req, key: &str, slot: &mut f64) -> String {
    let ok = match req.int(key).map(|v| v as f64 / 1000.0) {
        Some(v) if params::rules::positive_limit(v) => {
            *slot = v;
            true
        }
        _ => false,
    };
    ack(name, key, ok)
}

fn get_milli(tag: &str, key: &str, value: f64) -> String {
    Obj::state(tag).int(key, wire::milli(value)).finish()
}

fn handle_more(c: &mut Controller, name: &str, req: Req) -> Option<Answer> {
    let reply = match name {
        "set_collision_stage" => {
            let stage = req
                .int("collision_stage")
                .and_then(|s| u8::try_from(s).ok());
            let ok = match stage {
                Some(s) if params::rules::COLLISION_STAGES.contains(&s) => {
                    c.params.collision_stage = s;
                    true
                }
                _ => false,
            };
            // The SDK only accepts this command name with the key `collision_state`.
            ack("set_collision_stage", "collision_state", ok)
        }
        "get_collision_stage" => Obj::state("get_collision_stage")
            .int("collision_stage", i64::from(c.params.collision_stage))
            .finish(),
        "set_self_collision_enable" => match req.bool("set_enable") {
            Some(on) => {
                c.params.self_collision_enable = on;
                ack(name, "set_state", true)
            }
            None => ack(name, "set_state", false),
        },
        "get_self_collision_enable" => Obj::command(name)
            .bool("enable_state", c.params.self_collision_enable)
            .finish(),
        "get_DH_data" => dh_reply(c),
        "set_DH_data" => ack(name, "set_state", set_dh(c, req)),
        "set_DH_data_default" => {
            c.params.dh.clone_from(&c.facts.dh);
            ack(name, "set_state", true)
        }
        "set_joint_zero_offset" => {
            let ok = match req.ints("offset") {
                Some(o) if o.len() == c.facts.dof => {
                    c.params.zero_offset_deg = o.iter().map(|v| *v as f64 / 1000.0).collect();
                    true
                }
                _ => false,
            };
            ack(name, "set_state", ok)
        }
        "save_device_info_all" => {
            let ok = match c.save_state() {
                Ok(()) => true,
                Err(e) => {
                    tracing::warn!(error = %e, "Realman emulator cannot save its state file");
                    false
                }
            };
            ack(name, "model", ok)
        }
        _ => return joint_config(c, name, req).map(Answer::Reply),
    };
    Some(Answer::Reply(reply))
}

fn dh_reply(c: &Controller) -> String {
    let mut obj = Obj::command("get_DH_data");
    for (i, row) in c.params.dh.iter().enumerate() {
        obj = obj.ints(
            &format!("joint_{}", i + 1),
            &[
                wire::milli(row.alpha_deg),
                wire::m_to_um(row.a_m),
                wire::m_to_um(row.d_m),
                wire::milli(row.offset_deg),
            ],
        );
    }
    obj.finish()
}

fn set_dh(c: &mut Controller, req: Req) -> bool {
    let mut rows = Vec::with_capacity(c.facts.dof);
    for i in 1..=c.facts.dof {
        match req.ints(&format!("joint_{i}")) {
            Some(v) if v.len() == 4 => rows.push(DhRow {
                alpha_deg: v[0] as f64 / 1000.0,
                a_m: v[1] as f64 * 1e-6,
                d_m: v[2] as f64 * 1e-6,
                offset_deg: v[3] as f64 / 1000.0,
            }),
            _ => return false,
        }
    }
    c.params.dh = rows;
    true
}

/// Which joint table a joint-configuration command addresses.
#[derive(Debug, Clone, Copy)]
enum Table {
    MinPos,
    MaxPos,
    Speed,
    Acc,
}

/// Joint limits / speeds / accelerations (arm-level and drive-level names share the tables).
fn joint_config(c: &mut Controller, name: &str, req: Req) -> Option<String> {
    let base = name.replace("_drive", "");
    let drive = base.len() != name.len();
    let (table, key, get_key) = match base.as_str() {
        "set_joint_min_pos" | "get_joint_min_pos" => (Table::MinPos, "joint_min_pos", "min_pos"),
        "set_joint_max_pos" | "get_joint_max_pos" => (Table::MaxPos, "joint_max_pos", "max_pos"),
        "set_joint_max_speed" | "get_joint_max_speed" => {
            (Table::Speed, "joint_max_speed", "joint_speed")
        }
        "set_joint_max_acc" | "get_joint_max_acc" => (Table::Acc, "joint_max_acc", "joint_acc"),
        _ => return None,
    };
    if base.starts_with("get_") {
        let values = read_table(c, table);
        // Drive-level getters answer with `command`, arm-level ones with `state`.
        let obj = if drive {
            Obj::command(name)
        } else {
            Obj::state(key)
        };
        return Some(obj.ints(get_key, &values).finish());
    }
    let ok = req
        .ints(key)
        .filter(|v| v.len() == 2)
        .is_some_and(|v| write_table(c, table, v[0], v[1]));
    Some(ack(name, key, ok))
}

fn read_table(c: &Controller, table: Table) -> Vec<i64> {
    let p = &c.params;
    match table {
        Table::MinPos => p.min_deg.iter().map(|d| wire::milli(*d)).collect(),
        Table::MaxPos => p.max_deg.iter().map(|d| wire::milli(*d)).collect(),
        Table::Speed => p
            .max_speed_deg_s
            .iter()
            .map(|d| wire::milli(d / DEG_S_PER_RPM))
            .collect(),
        Table::Acc => p
            .max_acc_deg_s2
            .iter()
            .map(|d| wire::milli(d / DEG_S_PER_RPM))
            .collect(),
    }
}

/// Store one joint's value (wire units); false for a bad joint or value, or a joint that is
/// still enabled (the controller writes joint parameters only to a disabled joint, §9).
fn write_table(c: &mut Controller, table: Table, joint: i64, value: i64) -> bool {
    let Some(j) = usize::try_from(joint)
        .ok()
        .filter(|j| (1..=c.facts.dof).contains(j))
        .map(|j| j - 1)
    else {
        return false;
    };
    if c.enabled[j] {
        return false;
    }
    let p = &mut c.params;
    let v = value as f64 / 1000.0;
    match table {
        Table::MinPos if rules::joint_limits(v, p.max_deg[j]).is_ok() => p.min_deg[j] = v,
        Table::MaxPos if rules::joint_limits(p.min_deg[j], v).is_ok() => p.max_deg[j] = v,
        Table::Speed if rules::positive_limit(v) => p.max_speed_deg_s[j] = v * DEG_S_PER_RPM,
        Table::Acc if rules::positive_limit(v) => p.max_acc_deg_s2[j] = v * DEG_S_PER_RPM,
        _ => return false,
    }
    true
}
