//! Controller and tool IO ports, their supplies, and the 2nd-generation software version query
//! (docs/protocols/realman.md §7, §19). Reply shapes are the JSON protocol's, as both SDK
//! generations parse them.

use super::super::ioports::{port_index, ANALOG_CHANNELS, DIGITAL_PORTS, TOOL_PORTS};
use super::super::wire::{ack, Obj, Req};
use super::{Answer, Controller};

/// Answer an IO command, or `None` if `name` is not one.
pub(super) fn handle(c: &mut Controller, name: &str, req: Req) -> Option<Answer> {
    if name == "get_arm_software_version" {
        return Some(Answer::Reply(software_version(c)));
    }
    let int = |key: &str| req.int(key);
    let io = &mut c.params.io;
    let reply = match name {
        "set_IO_mode" => {
            let ok =
                matches!((int("IO_Num"), int("IO_mode")), (Some(n), Some(m)) if io.set_mode(n, m));
            ack(name, "set_state", ok)
        }
        "set_DO_state" => {
            let ok =
                matches!((int("IO_Num"), int("state")), (Some(n), Some(s)) if io.set_output(n, s));
            ack(name, "set_state", ok)
        }
        "get_IO_state" => match int("IO_Num").and_then(|n| port_index(n, DIGITAL_PORTS)) {
            Some(i) => Obj::state("IO_state")
                .int("IO_Num", i as i64 + 1)
                .int("IO_Mode", i64::from(io.modes[i]))
                .int("IO_state", i64::from(io.level(i)))
                .finish(),
            None => ack(name, "get_state", false),
        },
        // 2nd-generation single-port queries: outputs and inputs are separate there.
        "get_DO_state" | "get_DI_state" => {
            match int("IO_Num").and_then(|n| port_index(n, DIGITAL_PORTS)) {
                Some(i) => {
                    let (tag, level) = if name == "get_DO_state" {
                        ("DO_state", io.outputs[i])
                    } else {
                        ("DI_state", io.inputs[i])
                    };
                    Obj::state(tag)
                        .int("IO_Num", i as i64 + 1)
                        .int("IO_state", i64::from(level))
                        .finish()
                }
                None => ack(name, "get_state", false),
            }
        }
        "get_AO_state" | "get_AI_state" => {
            match int("IO_Num").and_then(|n| port_index(n, ANALOG_CHANNELS)) {
                Some(i) => {
                    let (tag, mv) = if name == "get_AO_state" {
                        ("AO_state", io.analog_out_mv[i])
                    } else {
                        ("AI_state", io.analog_in_mv[i])
                    };
                    Obj::state(tag)
                        .int("IO_Num", i as i64 + 1)
                        .int("voltage", i64::from(mv))
                        .finish()
                }
                None => ack(name, "get_state", false),
            }
        }
        "get_IO_input" => {
            let di: Vec<i64> = io.inputs.iter().map(|v| i64::from(*v)).collect();
            let ai: Vec<i64> = io.analog_in_mv.iter().map(|v| i64::from(*v)).collect();
            Obj::state("IO_input_state")
                .ints("DI", &di)
                .ints("AI", &ai)
                .finish()
        }
        "get_IO_output" => {
            let d: Vec<i64> = io.outputs.iter().map(|v| i64::from(*v)).collect();
            let a: Vec<i64> = io.analog_out_mv.iter().map(|v| i64::from(*v)).collect();
            Obj::state("IO_output_state")
                .ints("DO", &d)
                .ints("AO", &a)
                .finish()
        }
        "set_AO_state" => {
            let ok = matches!((int("IO_Num"), int("voltage")), (Some(n), Some(v)) if io.set_analog_out(n, v));
            ack(name, "state", ok)
        }
        "set_voltage" => ack(
            name,
            "state",
            int("voltage_type").is_some_and(|t| io.set_supply(t)),
        ),
        "get_voltage" => Obj::command("voltage_state")
            .int("voltage_type", i64::from(io.supply_type))
            .finish(),
        "set_tool_DO_state" => {
            let ok = matches!((int("IO_Num"), int("state")), (Some(n), Some(s)) if io.set_tool_output(n, s));
            ack(name, "set_state", ok)
        }
        "set_tool_IO_mode" => {
            let ok = matches!((int("IO_Num"), int("state")), (Some(n), Some(m)) if io.set_tool_mode(n, m));
            ack(name, "set_state", ok)
        }
        "get_tool_IO_state" => {
            let modes: Vec<i64> = io.tool_modes.iter().map(|v| i64::from(*v)).collect();
            let levels: Vec<i64> = (0..TOOL_PORTS)
                .map(|i| i64::from(io.tool_level(i)))
                .collect();
            Obj::state("tool_IO_state")
                .ints("IO_Mode", &modes)
                .ints("IO_State", &levels)
                .finish()
        }
        "set_tool_voltage" => ack(
            name,
            "state",
            int("voltage_type").is_some_and(|t| io.set_tool_supply(t)),
        ),
        "get_tool_voltage" => Obj::state("tool_voltage_state")
            .int("voltage_type", i64::from(io.tool_supply_type))
            .finish(),
        _ => return None,
    };
    Some(Answer::Reply(reply))
}

/// A version string `V1.7.0` as the 2nd-generation code: one hex digit per number (0x0170).
pub(super) fn version_code(version: &str) -> u32 {
    version
        .trim_start_matches(['V', 'v'])
        .split('.')
        .filter_map(|d| d.parse::<u32>().ok())
        .fold(0, |acc, d| (acc << 4) | (d & 0xF))
}

/// The model byte of the 2nd-generation codes: 0x6B for RM65-B (the documented one); the
/// other models get 0xNB from their series number (an armhil choice, no source lists them).
pub(super) fn model_byte(product: &str) -> u32 {
    match product {
        p if p.starts_with("RM65") => 0x6B,
        p if p.starts_with("RM75") => 0x7B,
        _ => 0x6B,
    }
}

/// Kernel versions reported as uint16 (0x0203 = 2.3, the documented example).
const KERNEL_VERSION: i64 = 0x0203;

fn software_version(c: &Controller) -> String {
    let fw = c.profile;
    let model = model_byte(&c.facts.product) << 16;
    Obj::state("arm_software_version")
        .int(
            "Plan_version",
            i64::from(model | version_code(fw.plan_version())),
        )
        .int(
            "Ctrl_version",
            i64::from(model | version_code(fw.ctrl_version())),
        )
        .int("Real-time_Kernal1", KERNEL_VERSION)
        .int("Real-time_Kernal2", KERNEL_VERSION)
        .str("Plan_build_info", "202410151000")
        .str("ctrlM4_build_info", "202410151000")
        .str("ctrlM7_build_info", "202410151000")
        .str("Product_version", &c.facts.product)
        .finish()
}
