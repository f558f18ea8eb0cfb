//! Modbus RTU, the end-effector protocol mode and dexterous-hand following
//! (docs/protocols/realman.md §18).

use super::super::wire::{ack, Obj, Req};
use super::{Answer, Controller};

/// Hand-following values the hand accepts (the SDK's range for its angle and position arrays).
const HAND_FOLLOW_ANGLE: std::ops::RangeInclusive<i64> = -32_768..=32_767;
const HAND_FOLLOW_POS: std::ops::RangeInclusive<i64> = 0..=65_535;
/// The emulated hand's full scale (its `set_hand_angle` range).
const HAND_FULL_SCALE: i64 = 1000;
/// `type` of a five-finger hand in the end-effector protocol's identity.
const PLUS_TYPE_HAND: i64 = 2;
/// `hand` of a right hand.
const PLUS_RIGHT_HAND: i64 = 2;

/// Answer a peripheral command, or `None` if `name` is not one.
pub(super) fn handle(c: &mut Controller, name: &str, req: Req) -> Option<Answer> {
    let p = &mut c.peripherals;
    let reply = match name {
        "set_modbus_mode" => {
            let ok = match (req.int("port"), req.int("baudrate"), req.int("timeout")) {
                (Some(port), Some(baud), Some(timeout)) => p.open(port, baud, timeout),
                _ => false,
            };
            ack(name, "set_state", ok)
        }
        "close_modbus_mode" => ack(
            name,
            "set_state",
            req.int("port").is_some_and(|port| p.close(port)),
        ),
        "write_single_register" => {
            let ok = match (
                req.int("port"),
                req.int("device"),
                req.int("address"),
                req.int("data"),
            ) {
                (Some(port), Some(device), Some(address), Some(v))
                    if (-32_768..=65_535).contains(&v) =>
                {
                    let v = v as u16;
                    p.write(
                        port,
                        device,
                        address,
                        &[i64::from(v >> 8), i64::from(v & 0xFF)],
                    )
                }
                _ => false,
            };
            ack(name, "write_state", ok)
        }
        "write_registers" => {
            let ok = match (
                req.int("port"),
                req.int("device"),
                req.int("address"),
                req.int("num"),
                req.ints("data"),
            ) {
                (Some(port), Some(device), Some(address), Some(num), Some(bytes))
                    if bytes.len() as i64 == num * 2 =>
                {
                    p.write(port, device, address, &bytes)
                }
                _ => false,
            };
            ack(name, "write_state", ok)
        }
        "read_holding_registers" => {
            match (req.int("port"), req.int("device"), req.int("address")) {
                (Some(port), Some(device), Some(address)) => match p.read(port, device, address) {
                    Some(v) => Obj::command(name).int("data", i64::from(v)).finish(),
                    None => ack(name, "read_state", false),
                },
                _ => ack(name, "read_state", false),
            }
        }
        "set_rm_plus_mode" => ack(
            name,
            "set_state",
            req.int("mode").is_some_and(|m| p.set_plus_mode(m)),
        ),
        "get_rm_plus_mode" => Obj::command(name).int("mode", p.plus_mode).finish(),
        "get_rm_plus_base_info" => plus_base_info(p.plus_mode),
        // The wire names are `hand_follow_*` (what the vendor SDK sends); the `set_` forms
        // are kept for clients of armhil ≤ this change, which sent those.
        "hand_follow_angle"
        | "hand_follow_pos"
        | "set_hand_follow_angle"
        | "set_hand_follow_pos" => ack(name, "set_state", hand_follow(c, name, req)),
        _ => return None,
    };
    Some(Answer::Reply(reply))
}

/// The end-effector's identity over the end-effector protocol (docs/protocols/realman.md §18):
/// the emulated hand (a right five-finger hand, 6 DoF, positions 0–1000, no force or touch
/// sensing), or `get_state: false` while the protocol is off (nothing on the tool port
/// answers).
fn plus_base_info(plus_mode: i64) -> String {
    if plus_mode == 0 {
        return ack("get_rm_plus_base_info", "get_state", false);
    }
    let six = |v: i64| [v; 6];
    let info = Obj::new()
        .str("manu", "ARMHIL")
        .int("type", PLUS_TYPE_HAND)
        // Versions as strings and the two capabilities as 0/1: what Robotic_Arm 1.1.6 parses
        // (the document's integer versions crash it; its booleans read back as true).
        .str("hv", "1.0.0")
        .str("sv", "1.0.0")
        .str("bv", "1.0.0")
        .int("id", 1)
        .int("dof", 6)
        .int("check", 0)
        .int("bee", 0)
        .int("force", 0)
        .int("touch", 0)
        .int("touch_num", 0)
        .int("touch_sw", 0)
        .int("hand", PLUS_RIGHT_HAND)
        .ints("pos_up", &six(HAND_FULL_SCALE))
        .ints("pos_low", &six(0))
        .ints("angle_up", &six(HAND_FULL_SCALE))
        .ints("angle_low", &six(0))
        .ints("speed_up", &six(HAND_FULL_SCALE))
        .ints("speed_low", &six(0))
        .ints("force_up", &six(0))
        .ints("force_low", &six(0));
    Obj::command("get_rm_plus_base_info")
        .obj("base_info", info)
        .finish()
}

/// Following: the hand chases the latest target at its set speed; values are scaled from the
/// SDK's ranges to the emulated hand's 0–1000.
fn hand_follow(c: &mut Controller, name: &str, req: Req) -> bool {
    let (key, range) = if name.ends_with("hand_follow_angle") {
        ("hand_angle", HAND_FOLLOW_ANGLE)
    } else {
        ("hand_pos", HAND_FOLLOW_POS)
    };
    let Some(values) = req.ints(key) else {
        return false;
    };
    if values.len() != 6 || values.iter().any(|v| !range.contains(v)) {
        return false;
    }
    let targets: Vec<i64> = values
        .iter()
        .map(|v| (*v).clamp(0, HAND_FULL_SCALE))
        .collect();
    c.hand.command(&targets, None);
    true
}
