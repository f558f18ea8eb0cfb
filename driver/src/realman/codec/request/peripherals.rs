//! Requests for the peripherals (docs/protocols/realman.md §18): Modbus RTU on the controller's
//! and the tool's RS485 ports, the end-effector protocol mode and dexterous-hand following.

use super::{query, ranged, EncodeError, Obj, Request, Tag};

/// Modbus RTU ports: 0 controller RS485 master, 1 tool RS485 master, 2 controller slave.
const RTU_PORTS: (i64, i64) = (0, 2);
/// Baud rates the controller accepts for Modbus RTU.
pub const MODBUS_BAUD_RATES: [u32; 3] = [9600, 115_200, 460_800];
/// Baud rates of the end-effector protocol (0 switches it off).
pub const PLUS_MODES: [u32; 5] = [0, 9600, 115_200, 256_000, 460_800];
/// Most registers one `write_registers` writes.
pub const MAX_REGISTERS_PER_WRITE: usize = 10;

fn baud(field: &'static str, value: u32, allowed: &[u32]) -> Result<u32, EncodeError> {
    if allowed.contains(&value) {
        Ok(value)
    } else {
        Err(EncodeError::OutOfRange {
            field,
            value: i64::from(value),
            min: i64::from(*allowed.iter().min().unwrap_or(&0)),
            max: i64::from(*allowed.iter().max().unwrap_or(&0)),
        })
    }
}

/// `set_modbus_mode`: `port` in Modbus RTU at `baudrate`, replies within `timeout_100ms`.
pub fn set_modbus_mode(
    port: u8,
    baudrate: u32,
    timeout_100ms: u16,
) -> Result<Request, EncodeError> {
    let port = ranged("port", i64::from(port), RTU_PORTS.0, RTU_PORTS.1)?;
    let baudrate = baud("baudrate", baudrate, &MODBUS_BAUD_RATES)?;
    Ok(Obj::new("set_modbus_mode")
        .field("port", &port)
        .field("baudrate", &baudrate)
        .field("timeout", &timeout_100ms)
        .echo("set_state"))
}

/// `close_modbus_mode` on `port`.
pub fn close_modbus_mode(port: u8) -> Result<Request, EncodeError> {
    let port = ranged("port", i64::from(port), RTU_PORTS.0, RTU_PORTS.1)?;
    Ok(Obj::new("close_modbus_mode")
        .field("port", &port)
        .echo("set_state"))
}

/// `write_registers`: `values` (at most 10) from `address` of slave `device` on `port`, each
/// register as two bytes, high byte first.
pub fn write_registers(
    port: u8,
    device: u8,
    address: u16,
    values: &[u16],
) -> Result<Request, EncodeError> {
    let port = ranged("port", i64::from(port), RTU_PORTS.0, RTU_PORTS.1)?;
    let num = ranged(
        "num",
        values.len() as i64,
        1,
        MAX_REGISTERS_PER_WRITE as i64,
    )?;
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    Ok(Obj::new("write_registers")
        .field("port", &port)
        .field("address", &address)
        .field("num", &num)
        .field("data", &bytes)
        .field("device", &device)
        .echo("write_state"))
}

/// `read_holding_registers`: one register at `address` of slave `device` on `port`.
pub fn read_holding_registers(port: u8, device: u8, address: u16) -> Result<Request, EncodeError> {
    let port = ranged("port", i64::from(port), RTU_PORTS.0, RTU_PORTS.1)?;
    Ok(Obj::new("read_holding_registers")
        .field("port", &port)
        .field("address", &address)
        .field("device", &device)
        .done(super::Expect::Data {
            tag: Tag::Command("read_holding_registers"),
        }))
}

/// `set_rm_plus_mode`: the end-effector protocol at `mode` baud (0 off).
pub fn set_rm_plus_mode(mode: u32) -> Result<Request, EncodeError> {
    let mode = baud("mode", mode, &PLUS_MODES)?;
    Ok(Obj::new("set_rm_plus_mode")
        .field("mode", &mode)
        .echo("set_state"))
}

/// `get_rm_plus_mode`.
pub fn get_rm_plus_mode() -> Request {
    query("get_rm_plus_mode", Tag::Command("get_rm_plus_mode"))
}

/// Hand following's acknowledgement: awaited only when the caller blocks (the controller
/// answers every frame; a streaming caller does not wait for it, as the vendor SDK does not).
fn follow(obj: Obj, block: bool) -> Request {
    if block {
        obj.echo("set_state")
    } else {
        obj.done(super::Expect::Nothing)
    }
}

/// `hand_follow_angle` (the vendor SDK's `rm_set_hand_follow_angle`): six finger angles in the
/// hand maker's units (−32768..=32767).
pub fn set_hand_follow_angle(angles: [i16; 6], block: bool) -> Request {
    follow(
        Obj::new("hand_follow_angle").field("hand_angle", &angles),
        block,
    )
}

/// `hand_follow_pos` (the vendor SDK's `rm_set_hand_follow_pos`): six finger positions in the
/// hand maker's units (0..=65535).
pub fn set_hand_follow_pos(positions: [u16; 6], block: bool) -> Request {
    follow(
        Obj::new("hand_follow_pos").field("hand_pos", &positions),
        block,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modbus_requests_have_the_controller_field_names() {
        let r = set_modbus_mode(1, 115_200, 2).expect("valid");
        assert_eq!(
            r.wire,
            "{\"command\":\"set_modbus_mode\",\"port\":1,\"baudrate\":115200,\"timeout\":2}\r\n"
        );
        let r = write_registers(0, 3, 10, &[0x1234, 0xFFFE]).expect("valid");
        assert_eq!(
            r.wire,
            "{\"command\":\"write_registers\",\"port\":0,\"address\":10,\"num\":2,\"data\":[18,52,255,254],\"device\":3}\r\n"
        );
        assert!(
            set_modbus_mode(3, 115_200, 2).is_err(),
            "port 3 is Modbus TCP"
        );
        assert!(set_modbus_mode(0, 19_200, 2).is_err());
        assert!(write_registers(0, 1, 0, &[0; 11]).is_err());
        assert!(write_registers(0, 1, 0, &[]).is_err());
        assert!(set_rm_plus_mode(256_000).is_ok());
        assert!(set_rm_plus_mode(1).is_err());
    }
}
