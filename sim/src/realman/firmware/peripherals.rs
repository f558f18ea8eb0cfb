//! Peripherals on the controller's and the tool's RS485 ports (docs/protocols/realman.md §18):
//! Modbus RTU mode per port and, behind each port in Modbus mode, an emulated generic Modbus
//! slave at every device address (holding registers only, all zero at boot), and the
//! end-effector ecosystem protocol mode (`rm_plus`), which shares the tool port.

use std::collections::BTreeMap;

/// Modbus RTU ports: 0 controller RS485 master, 1 tool RS485 master, 2 controller slave.
pub const MODBUS_PORTS: std::ops::RangeInclusive<i64> = 0..=2;
/// The tool-side port (its Modbus mode excludes the gripper protocol).
pub const TOOL_PORT: i64 = 1;
/// Baud rates the controller accepts for Modbus RTU.
pub const MODBUS_BAUD_RATES: [i64; 3] = [9600, 115_200, 460_800];
/// Baud rates of the end-effector protocol (0 switches it off).
pub const PLUS_MODES: [i64; 5] = [0, 9600, 115_200, 256_000, 460_800];
/// Most registers one `write_registers` writes.
pub const MAX_REGISTERS_PER_WRITE: i64 = 10;

/// One port's Modbus settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModbusPort {
    /// Baud rate.
    pub baudrate: i64,
    /// Reply timeout, 100 ms units (0 is taken as 1).
    pub timeout_100ms: i64,
}

/// The peripherals' state.
#[derive(Debug, Default)]
pub struct Peripherals {
    /// Ports in Modbus RTU mode.
    pub ports: BTreeMap<i64, ModbusPort>,
    /// Holding registers by (port, device, address); absent = 0.
    registers: BTreeMap<(i64, i64, u16), u16>,
    /// End-effector protocol mode (0 off, else its baud rate).
    pub plus_mode: i64,
}

impl Peripherals {
    /// Switch `port` to Modbus RTU; `false` for an unknown port or baud rate.
    pub fn open(&mut self, port: i64, baudrate: i64, timeout_100ms: i64) -> bool {
        if !MODBUS_PORTS.contains(&port)
            || !MODBUS_BAUD_RATES.contains(&baudrate)
            || timeout_100ms < 0
        {
            return false;
        }
        self.ports.insert(
            port,
            ModbusPort {
                baudrate,
                timeout_100ms: timeout_100ms.max(1),
            },
        );
        true
    }

    /// Leave Modbus RTU mode on `port`.
    pub fn close(&mut self, port: i64) -> bool {
        if !MODBUS_PORTS.contains(&port) {
            return false;
        }
        self.ports.remove(&port);
        true
    }

    /// Whether the tool port is taken by Modbus (the gripper protocol then has no port).
    pub fn tool_port_in_modbus(&self) -> bool {
        self.ports.contains_key(&TOOL_PORT)
    }

    fn slave(&self, port: i64, device: i64) -> bool {
        self.ports.contains_key(&port) && (1..=247).contains(&device)
    }

    /// Write registers from `address` with the big-endian byte pairs of `bytes`.
    pub fn write(&mut self, port: i64, device: i64, address: i64, bytes: &[i64]) -> bool {
        let num = bytes.len() as i64 / 2;
        let fits = u16::try_from(address)
            .ok()
            .zip(u16::try_from(address + num - 1).ok())
            .is_some();
        if !self.slave(port, device)
            || !bytes.len().is_multiple_of(2)
            || !(1..=MAX_REGISTERS_PER_WRITE).contains(&num)
            || !fits
            || bytes.iter().any(|b| !(0..=255).contains(b))
        {
            return false;
        }
        for (i, pair) in bytes.chunks(2).enumerate() {
            let value = ((pair[0] as u16) << 8) | pair[1] as u16;
            self.registers
                .insert((port, device, (address + i as i64) as u16), value);
        }
        true
    }

    /// One holding register, as the wire's signed 16-bit value; `None` when nobody answers.
    pub fn read(&self, port: i64, device: i64, address: i64) -> Option<i16> {
        let address = u16::try_from(address).ok()?;
        if !self.slave(port, device) {
            return None;
        }
        let raw = self
            .registers
            .get(&(port, device, address))
            .copied()
            .unwrap_or(0);
        Some(raw as i16)
    }

    /// Set the end-effector protocol mode; `false` for a mode the controller does not know.
    pub fn set_plus_mode(&mut self, mode: i64) -> bool {
        if PLUS_MODES.contains(&mode) {
            self.plus_mode = mode;
            true
        } else {
            false
        }
    }
}
