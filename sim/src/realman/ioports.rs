//! The controller's and the tool flange's IO ports (docs/protocols/realman.md §19): what each
//! port is set to, what it outputs and what it reads. Kept with the settings, so the state file
//! holds it across a restart.
//!
//! Ports are numbered from 1 on the wire (`IO_Num`); arrays here are indexed from 0.

use serde::{Deserialize, Serialize};

use crate::state_file::InvalidField;

/// Digital ports on the controller (3rd generation: 4 ports, each input or output).
pub const DIGITAL_PORTS: usize = 4;
/// Analog channels on the controller (2nd generation: 4 outputs and 4 inputs, 0–10 V).
pub const ANALOG_CHANNELS: usize = 4;
/// Digital ports on the tool flange.
pub const TOOL_PORTS: usize = 2;
/// Highest `IO_mode` of a controller port (0 input, 1 output, 2–12 input functions,
/// 13 collision output, 14 realtime speed scaling).
pub const MAX_IO_MODE: u8 = 14;
/// Modes in which the controller drives the port (`set_DO_state` needs mode 1; mode 13 is
/// driven by the collision detector).
pub const OUTPUT_MODES: [u8; 2] = [1, 13];
/// Full scale of an analog channel, mV.
pub const ANALOG_FULL_SCALE_MV: u16 = 10_000;
/// Controller IO supply settings (`set_voltage`): 0 → 0 V, 2 → 12 V, 3 → 24 V (1 is not one).
pub const SUPPLY_TYPES: [u8; 3] = [0, 2, 3];
/// Tool supply settings (`set_tool_voltage`): 0 → 0 V, 1 → 5 V, 2 → 12 V, 3 → 24 V.
pub const TOOL_SUPPLY_TYPES: [u8; 4] = [0, 1, 2, 3];

/// Volts of a supply setting, for display.
pub fn supply_volts(voltage_type: u8) -> u8 {
    match voltage_type {
        1 => 5,
        2 => 12,
        3 => 24,
        _ => 0,
    }
}

/// The IO ports' state.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IoState {
    /// `IO_mode` of each controller digital port.
    pub modes: [u8; DIGITAL_PORTS],
    /// Level each controller port drives when in output mode (0/1).
    pub outputs: [u8; DIGITAL_PORTS],
    /// Level each controller port reads (what is wired to it; set from outside the protocol).
    pub inputs: [u8; DIGITAL_PORTS],
    /// Analog outputs, mV.
    pub analog_out_mv: [u16; ANALOG_CHANNELS],
    /// Analog inputs, mV (set from outside the protocol).
    pub analog_in_mv: [u16; ANALOG_CHANNELS],
    /// Controller IO supply setting (see [`SUPPLY_TYPES`]).
    pub supply_type: u8,
    /// Tool ports' mode: 0 input, 1 output.
    pub tool_modes: [u8; TOOL_PORTS],
    /// Level each tool port drives in output mode.
    pub tool_outputs: [u8; TOOL_PORTS],
    /// Level each tool port reads.
    pub tool_inputs: [u8; TOOL_PORTS],
    /// Tool supply setting (see [`TOOL_SUPPLY_TYPES`]).
    pub tool_supply_type: u8,
}

impl Default for IoState {
    /// Power-on: every port an input reading low, outputs low, both supplies at 24 V (the
    /// gripper, online at power-on, runs on the tool's 24 V).
    fn default() -> Self {
        Self {
            modes: [0; DIGITAL_PORTS],
            outputs: [0; DIGITAL_PORTS],
            inputs: [0; DIGITAL_PORTS],
            analog_out_mv: [0; ANALOG_CHANNELS],
            analog_in_mv: [0; ANALOG_CHANNELS],
            supply_type: 3,
            tool_modes: [0; TOOL_PORTS],
            tool_outputs: [0; TOOL_PORTS],
            tool_inputs: [0; TOOL_PORTS],
            tool_supply_type: 3,
        }
    }
}

/// A wire port number (1-based) as an index below `count`.
pub fn port_index(io_num: i64, count: usize) -> Option<usize> {
    usize::try_from(io_num)
        .ok()
        .filter(|n| (1..=count).contains(n))
        .map(|n| n - 1)
}

fn level(value: i64) -> Option<u8> {
    match value {
        0 | 1 => Some(value as u8),
        _ => None,
    }
}

impl IoState {
    /// `set_IO_mode`: false for an unknown port or mode.
    pub fn set_mode(&mut self, io_num: i64, mode: i64) -> bool {
        match (
            port_index(io_num, DIGITAL_PORTS),
            u8::try_from(mode).ok().filter(|m| *m <= MAX_IO_MODE),
        ) {
            (Some(i), Some(m)) => {
                self.modes[i] = m;
                true
            }
            _ => false,
        }
    }

    /// `set_DO_state`: only a port in general output mode (1) takes a level.
    pub fn set_output(&mut self, io_num: i64, state: i64) -> bool {
        match (port_index(io_num, DIGITAL_PORTS), level(state)) {
            (Some(i), Some(l)) if self.modes[i] == 1 => {
                self.outputs[i] = l;
                true
            }
            _ => false,
        }
    }

    /// The level a controller port shows: what it drives in an output mode, else what it reads.
    pub fn level(&self, i: usize) -> u8 {
        if OUTPUT_MODES.contains(&self.modes[i]) {
            self.outputs[i]
        } else {
            self.inputs[i]
        }
    }

    /// `set_AO_state`: voltage in mV, 0..=10000.
    pub fn set_analog_out(&mut self, io_num: i64, mv: i64) -> bool {
        match (
            port_index(io_num, ANALOG_CHANNELS),
            u16::try_from(mv)
                .ok()
                .filter(|v| *v <= ANALOG_FULL_SCALE_MV),
        ) {
            (Some(i), Some(v)) => {
                self.analog_out_mv[i] = v;
                true
            }
            _ => false,
        }
    }

    /// `set_voltage`.
    pub fn set_supply(&mut self, voltage_type: i64) -> bool {
        match u8::try_from(voltage_type)
            .ok()
            .filter(|t| SUPPLY_TYPES.contains(t))
        {
            Some(t) => {
                self.supply_type = t;
                true
            }
            None => false,
        }
    }

    /// `set_tool_IO_mode`: 0 input, 1 output.
    pub fn set_tool_mode(&mut self, io_num: i64, mode: i64) -> bool {
        match (port_index(io_num, TOOL_PORTS), level(mode)) {
            (Some(i), Some(m)) => {
                self.tool_modes[i] = m;
                true
            }
            _ => false,
        }
    }

    /// `set_tool_DO_state`: only a tool port in output mode takes a level.
    pub fn set_tool_output(&mut self, io_num: i64, state: i64) -> bool {
        match (port_index(io_num, TOOL_PORTS), level(state)) {
            (Some(i), Some(l)) if self.tool_modes[i] == 1 => {
                self.tool_outputs[i] = l;
                true
            }
            _ => false,
        }
    }

    /// The level a tool port shows.
    pub fn tool_level(&self, i: usize) -> u8 {
        if self.tool_modes[i] == 1 {
            self.tool_outputs[i]
        } else {
            self.tool_inputs[i]
        }
    }

    /// `set_tool_voltage`.
    pub fn set_tool_supply(&mut self, voltage_type: i64) -> bool {
        match u8::try_from(voltage_type)
            .ok()
            .filter(|t| TOOL_SUPPLY_TYPES.contains(t))
        {
            Some(t) => {
                self.tool_supply_type = t;
                true
            }
            None => false,
        }
    }

    /// Check a state file's values against what the commands (and the input setters) accept;
    /// fields are named as in the file (`params.io.modes[2]`).
    pub fn validate(&self) -> Result<(), InvalidField> {
        let bad = |field: String, problem: String| Err(InvalidField::new(field, problem));
        for (i, m) in self.modes.iter().enumerate() {
            if *m > MAX_IO_MODE {
                return bad(
                    format!("params.io.modes[{i}]"),
                    format!("{m} is outside 0..={MAX_IO_MODE}"),
                );
            }
        }
        let levels: [(&str, &[u8]); 5] = [
            ("outputs", &self.outputs),
            ("inputs", &self.inputs),
            ("tool_modes", &self.tool_modes),
            ("tool_outputs", &self.tool_outputs),
            ("tool_inputs", &self.tool_inputs),
        ];
        for (name, values) in levels {
            if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| **v > 1) {
                return bad(
                    format!("params.io.{name}[{i}]"),
                    format!("{v} is not 0 or 1"),
                );
            }
        }
        for (name, values) in [
            ("analog_out_mv", &self.analog_out_mv),
            ("analog_in_mv", &self.analog_in_mv),
        ] {
            if let Some((i, v)) = values
                .iter()
                .enumerate()
                .find(|(_, v)| **v > ANALOG_FULL_SCALE_MV)
            {
                return bad(
                    format!("params.io.{name}[{i}]"),
                    format!("{v} mV is above {ANALOG_FULL_SCALE_MV} mV"),
                );
            }
        }
        if !SUPPLY_TYPES.contains(&self.supply_type) {
            return bad(
                "params.io.supply_type".into(),
                format!("{} is not 0, 2 or 3", self.supply_type),
            );
        }
        if !TOOL_SUPPLY_TYPES.contains(&self.tool_supply_type) {
            return bad(
                "params.io.tool_supply_type".into(),
                format!("{} is outside 0..=3", self.tool_supply_type),
            );
        }
        Ok(())
    }

    /// One line for the web view: each port's mode letter and level, the analog outputs and
    /// the supplies (`DIO 1:o1 2:i0 … | AO 0.000 … V | 24 V · tool 1:i0 2:o1 24 V`).
    pub fn summary(&self) -> String {
        let port =
            |mode_out: bool, level: u8| format!("{}{level}", if mode_out { 'o' } else { 'i' });
        let dio: Vec<String> = (0..DIGITAL_PORTS)
            .map(|i| {
                format!(
                    "{}:{}",
                    i + 1,
                    port(OUTPUT_MODES.contains(&self.modes[i]), self.level(i))
                )
            })
            .collect();
        let ao: Vec<String> = self
            .analog_out_mv
            .iter()
            .map(|mv| format!("{:.3}", f64::from(*mv) / 1000.0))
            .collect();
        let tool: Vec<String> = (0..TOOL_PORTS)
            .map(|i| {
                format!(
                    "{}:{}",
                    i + 1,
                    port(self.tool_modes[i] == 1, self.tool_level(i))
                )
            })
            .collect();
        format!(
            "DIO {} | AO {} V | {} V · tool {} {} V",
            dio.join(" "),
            ao.join(" "),
            supply_volts(self.supply_type),
            tool.join(" "),
            supply_volts(self.tool_supply_type)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_need_output_mode_and_levels_follow_the_mode() {
        let mut io = IoState::default();
        assert!(!io.set_output(1, 1), "port 1 boots as an input");
        assert!(io.set_mode(1, 1));
        assert!(io.set_output(1, 1));
        assert_eq!(io.level(0), 1);
        io.inputs[0] = 0;
        assert!(io.set_mode(1, 0));
        assert_eq!(io.level(0), 0, "an input shows what it reads");
        assert!(!io.set_mode(5, 1), "4 ports");
        assert!(!io.set_mode(0, 1), "ports count from 1");
        assert!(!io.set_mode(2, 15));
        assert!(!io.set_output(1, 2), "a level is 0 or 1");
    }

    #[test]
    fn analog_supply_and_tool_ranges() {
        let mut io = IoState::default();
        assert!(io.set_analog_out(4, 10_000));
        assert!(!io.set_analog_out(4, 10_001));
        assert!(!io.set_analog_out(1, -1));
        assert!(!io.set_supply(1), "1 is no controller supply setting");
        assert!(io.set_supply(2));
        assert!(io.set_tool_supply(1));
        assert!(!io.set_tool_supply(4));
        assert!(!io.set_tool_output(2, 1), "tool port 2 boots as an input");
        assert!(io.set_tool_mode(2, 1) && io.set_tool_output(2, 1));
        assert_eq!(io.tool_level(1), 1);
        assert!(!io.set_tool_mode(3, 1));
        assert_eq!(
            io.summary(),
            "DIO 1:i0 2:i0 3:i0 4:i0 | AO 0.000 0.000 0.000 10.000 V | 12 V · tool 1:i0 2:o1 5 V"
        );
    }

    #[test]
    fn validation_names_the_field() {
        let mut io = IoState::default();
        assert!(io.validate().is_ok());
        io.modes[2] = 20;
        assert!(io
            .validate()
            .unwrap_err()
            .to_string()
            .contains("params.io.modes[2]"));
        io = IoState::default();
        io.tool_outputs[1] = 3;
        assert!(io
            .validate()
            .unwrap_err()
            .to_string()
            .contains("params.io.tool_outputs[1]"));
        io = IoState::default();
        io.supply_type = 1;
        assert!(io
            .validate()
            .unwrap_err()
            .to_string()
            .contains("supply_type"));
    }
}
