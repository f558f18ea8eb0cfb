//! Requests for the IO ports (docs/protocols/realman.md §19): the controller's four digital
//! ports and four analog outputs, the tool's two digital ports, both supplies, and the
//! 2nd-generation software version query (§7).

use super::{query, ranged, EncodeError, Obj, Request, Tag};

/// Controller digital ports (`IO_Num` 1..=4).
pub const DIGITAL_PORTS: u8 = 4;
/// Controller analog channels (`IO_Num` 1..=4).
pub const ANALOG_CHANNELS: u8 = 4;
/// Tool digital ports (`IO_Num` 1..=2).
pub const TOOL_PORTS: u8 = 2;
/// Highest `IO_mode` (14: realtime speed scaling).
pub const MAX_IO_MODE: u8 = 14;
/// Analog full scale, V.
pub const ANALOG_FULL_SCALE_V: f64 = 10.0;

fn port(field: &'static str, n: u8, count: u8) -> Result<i64, EncodeError> {
    ranged(field, i64::from(n), 1, i64::from(count))
}

/// `set_IO_mode`: controller port `io_num` (1–4) to `mode` (0 input, 1 output, 2–14 functions).
pub fn set_io_mode(io_num: u8, mode: u8) -> Result<Request, EncodeError> {
    let n = port("IO_Num", io_num, DIGITAL_PORTS)?;
    let mode = ranged("IO_mode", i64::from(mode), 0, i64::from(MAX_IO_MODE))?;
    Ok(Obj::new("set_IO_mode")
        .field("IO_Num", &n)
        .field("IO_mode", &mode)
        .echo("set_state"))
}

/// `set_DO_state`: drive controller port `io_num` high or low (the port must be an output).
pub fn set_do_state(io_num: u8, high: bool) -> Result<Request, EncodeError> {
    let n = port("IO_Num", io_num, DIGITAL_PORTS)?;
    Ok(Obj::new("set_DO_state")
        .field("IO_Num", &n)
        .field("state", &u8::from(high))
        .echo("set_state"))
}

/// `get_IO_state`: one controller port's mode and level.
pub fn get_io_state(io_num: u8) -> Result<Request, EncodeError> {
    let n = port("IO_Num", io_num, DIGITAL_PORTS)?;
    Ok(Obj::new("get_IO_state")
        .field("IO_Num", &n)
        .done(super::Expect::Data {
            tag: Tag::State("IO_state"),
        }))
}

/// `get_IO_input`: every digital input level and analog input voltage.
pub fn get_io_input() -> Request {
    query("get_IO_input", Tag::State("IO_input_state"))
}

/// `get_IO_output`: every digital output level and analog output voltage.
pub fn get_io_output() -> Request {
    query("get_IO_output", Tag::State("IO_output_state"))
}

/// `set_AO_state`: analog output `io_num` (1–4) to `volts` (0–10 V, 1 mV resolution).
pub fn set_ao_state(io_num: u8, volts: f64) -> Result<Request, EncodeError> {
    let n = port("IO_Num", io_num, ANALOG_CHANNELS)?;
    if !volts.is_finite() {
        return Err(EncodeError::NotEncodable {
            field: "voltage",
            value: volts,
        });
    }
    let mv = ranged(
        "voltage",
        (volts * 1000.0).round() as i64,
        0,
        (ANALOG_FULL_SCALE_V * 1000.0) as i64,
    )?;
    Ok(Obj::new("set_AO_state")
        .field("IO_Num", &n)
        .field("voltage", &mv)
        .echo("state"))
}

/// `set_voltage`: the controller's IO supply (0 → 0 V, 2 → 12 V, 3 → 24 V).
pub fn set_voltage(voltage_type: u8) -> Result<Request, EncodeError> {
    if voltage_type == 1 {
        return Err(EncodeError::OutOfRange {
            field: "voltage_type",
            value: 1,
            min: 2,
            max: 3,
        });
    }
    let t = ranged("voltage_type", i64::from(voltage_type), 0, 3)?;
    Ok(Obj::new("set_voltage")
        .field("voltage_type", &t)
        .echo("state"))
}

/// `get_voltage`: the controller's IO supply setting.
pub fn get_voltage() -> Request {
    query("get_voltage", Tag::Command("voltage_state"))
}

/// `set_tool_IO_mode`: tool port `io_num` (1–2) as input (false) or output (true).
pub fn set_tool_io_mode(io_num: u8, output: bool) -> Result<Request, EncodeError> {
    let n = port("IO_Num", io_num, TOOL_PORTS)?;
    Ok(Obj::new("set_tool_IO_mode")
        .field("IO_Num", &n)
        .field("state", &u8::from(output))
        .echo("set_state"))
}

/// `set_tool_DO_state`: drive tool port `io_num` high or low (the port must be an output).
pub fn set_tool_do_state(io_num: u8, high: bool) -> Result<Request, EncodeError> {
    let n = port("IO_Num", io_num, TOOL_PORTS)?;
    Ok(Obj::new("set_tool_DO_state")
        .field("IO_Num", &n)
        .field("state", &u8::from(high))
        .echo("set_state"))
}

/// `get_tool_IO_state`: both tool ports' modes and levels.
pub fn get_tool_io_state() -> Request {
    query("get_tool_IO_state", Tag::State("tool_IO_state"))
}

/// `set_tool_voltage`: the tool supply (0 → 0 V, 1 → 5 V, 2 → 12 V, 3 → 24 V).
pub fn set_tool_voltage(voltage_type: u8) -> Result<Request, EncodeError> {
    let t = ranged("voltage_type", i64::from(voltage_type), 0, 3)?;
    Ok(Obj::new("set_tool_voltage")
        .field("voltage_type", &t)
        .echo("state"))
}

/// `get_tool_voltage`: the tool supply setting.
pub fn get_tool_voltage() -> Request {
    query("get_tool_voltage", Tag::State("tool_voltage_state"))
}

/// `get_arm_software_version`: the 2nd-generation version codes.
pub fn get_arm_software_version() -> Request {
    query(
        "get_arm_software_version",
        Tag::State("arm_software_version"),
    )
}

/// `get_rm_plus_base_info`: the end-effector's identity over the end-effector protocol.
pub fn get_rm_plus_base_info() -> Request {
    query(
        "get_rm_plus_base_info",
        Tag::Command("get_rm_plus_base_info"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn io_requests_check_ports_and_ranges() {
        assert_eq!(
            set_ao_state(2, 5.0).unwrap().wire,
            "{\"command\":\"set_AO_state\",\"IO_Num\":2,\"voltage\":5000}\r\n"
        );
        assert!(set_ao_state(2, 10.5).is_err());
        assert!(set_ao_state(2, f64::NAN).is_err());
        assert!(set_io_mode(5, 1).is_err());
        assert!(set_io_mode(1, 15).is_err());
        assert!(set_do_state(0, true).is_err());
        assert!(set_tool_do_state(3, true).is_err());
        assert!(set_voltage(1).is_err(), "1 is no controller supply setting");
        assert!(set_voltage(2).is_ok());
        assert!(set_tool_voltage(4).is_err());
    }
}
