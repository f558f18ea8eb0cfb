//! Gripper, dexterous hand and realtime-push configuration (docs/protocols/realman.md §10, §11).

use super::super::params::{rules, PushCustom};
use super::super::wire::{ack, Obj, Req};
use super::{Answer, ClientId, Controller};

/// Gripper speed when a command gives none.
const DEFAULT_GRIPPER_SPEED: i64 = 500;

/// Answer a gripper / hand / push command, or `None` if `name` is not one.
pub(super) fn handle(c: &mut Controller, client: ClientId, name: &str, req: Req) -> Option<Answer> {
    let reply = match name {
        "set_gripper_route" => {
            let ok = match (req.int("min"), req.int("max"), c.gripper.as_mut()) {
                (Some(lo), Some(hi), Some(g)) if (0..hi).contains(&lo) && hi <= 1000 => {
                    g.route = (lo, hi);
                    true
                }
                _ => false,
            };
            Obj::command(name).bool("state", ok).finish()
        }
        "set_gripper_release"
        | "set_gripper_pick"
        | "set_gripper_pick_on"
        | "set_gripper_position" => {
            // Every gripper motion is acknowledged under the one name `set_gripper`.
            Obj::command("set_gripper")
                .bool("state", gripper_move(c, client, name, req))
                .finish()
        }
        "get_gripper_state" => gripper_state(c),
        "set_hand_posture" | "set_hand_seq" | "set_hand_angle" => {
            ack(name, "set_state", hand_move(c, client, name, req))
        }
        "set_hand_speed" | "set_hand_force" => {
            let key = &name["set_".len()..];
            let ok = match req.int(key) {
                Some(v @ 1..=1000) => {
                    if key == "hand_speed" {
                        c.hand.speed = v;
                    } else {
                        c.hand.force = v;
                    }
                    true
                }
                _ => false,
            };
            ack(name, "set_state", ok)
        }
        "set_realtime_push" => Obj::command(name).bool("state", set_push(c, req)).finish(),
        "get_realtime_push" => push_reply(c),
        _ => return None,
    };
    Some(Answer::Reply(reply))
}

fn gripper_move(c: &mut Controller, client: ClientId, name: &str, req: Req) -> bool {
    let Some(g) = c.gripper.as_mut() else {
        return false;
    };
    // The gripper speaks over the tool's RS485 port: not while that port is in Modbus mode.
    if g.error_bits != 0 || !c.power_on || c.peripherals.tool_port_in_modbus() {
        return false;
    }
    let speed = req.int("speed").unwrap_or(DEFAULT_GRIPPER_SPEED);
    if !(1..=1000).contains(&speed) {
        return false;
    }
    let target = match name {
        "set_gripper_release" => g.route.1 as f64,
        "set_gripper_position" => match req.int("position") {
            Some(p @ 1..=1000) => p as f64,
            _ => return false,
        },
        _ => match req.int("force") {
            Some(f @ 50..=1000) => {
                g.force = f;
                g.route.0 as f64
            }
            _ => return false,
        },
    };
    let block = req.bool("block").unwrap_or(false).then_some(client);
    g.command(target, speed, block);
    true
}

fn gripper_state(c: &Controller) -> String {
    let obj = Obj::command("get_gripper_state");
    match &c.gripper {
        Some(g) => obj
            .int("enable", 1)
            .int("status", 1)
            .int("error", i64::from(g.error_bits))
            .int("mode", i64::from(g.mode))
            .int("current_force", if g.mode == 2 { g.force } else { 0 })
            .int("temperature", 30)
            .int("actpos", g.position.round() as i64)
            .finish(),
        None => obj
            .int("enable", 0)
            .int("status", 0)
            .int("error", 0)
            .int("mode", 0)
            .int("current_force", 0)
            .int("temperature", 0)
            .int("actpos", 0)
            .finish(),
    }
}

/// Finger targets of a stored posture or sequence: a fixed synthetic table (the real hand's
/// table is user-taught), so that every number gives a distinct, repeatable hand shape.
fn preset(number: i64) -> [i64; 6] {
    let mut out = [0; 6];
    for (i, slot) in out.iter_mut().enumerate() {
        *slot = (number * 137 + i as i64 * 211).rem_euclid(1001);
    }
    out
}

fn hand_move(c: &mut Controller, client: ClientId, name: &str, req: Req) -> bool {
    let targets = match name {
        "set_hand_angle" => match req.ints("hand_angle") {
            Some(a) if a.len() == 6 && a.iter().all(|v| (-1..=1000).contains(v)) => a,
            _ => return false,
        },
        _ => {
            let key = if name == "set_hand_posture" {
                "posture_num"
            } else {
                "seq_num"
            };
            match req.int(key) {
                Some(n @ 1..=40) => preset(n).to_vec(),
                _ => return false,
            }
        }
    };
    let block = req.bool("block").unwrap_or(false).then_some(client);
    c.hand.command(&targets, block);
    true
}

fn set_push(c: &mut Controller, req: Req) -> bool {
    let mut push = c.params.push.clone();
    if let Some(cycle) = req.int("cycle") {
        match u32::try_from(cycle) {
            Ok(v) if rules::PUSH_CYCLES.contains(&v) => push.cycle = v,
            _ => return false,
        }
    }
    if let Some(enable) = req.bool("enable") {
        push.enable = enable;
    }
    if let Some(port) = req.int("port") {
        match u16::try_from(port) {
            Ok(p) if rules::push_port(p) => push.port = p,
            _ => return false,
        }
    }
    if let Some(fc) = req.int("force_coordinate") {
        push.force_coordinate = fc;
    }
    if let Some(ip) = req.str("ip") {
        if !rules::push_ip(ip) {
            return false;
        }
        push.ip = ip.to_owned();
    }
    if let Some(custom) = req.sub("custom") {
        if let Some(map) = custom.0.as_object() {
            for key in map.keys() {
                if let Some(on) = custom.bool(key) {
                    push.custom.set(key, on);
                }
            }
        }
    }
    c.params.push = push;
    true
}

fn push_reply(c: &Controller) -> String {
    let p = &c.params.push;
    let mut custom = Obj::new();
    // The SDK's extra keys (hand, rm_plus_*) are reported only once switched on.
    for (i, (key, on)) in p.custom.entries().into_iter().enumerate() {
        if i < PushCustom::DOCUMENTED || on {
            custom = custom.bool(key, on);
        }
    }
    Obj::command("get_realtime_push")
        .int("cycle", i64::from(p.cycle))
        .bool("enable", p.enable)
        .int("port", i64::from(p.port))
        .int("force_coordinate", p.force_coordinate)
        .str("ip", &p.ip)
        .obj("custom", custom)
        .finish()
}
