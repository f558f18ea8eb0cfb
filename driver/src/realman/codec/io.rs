//! Decoders for the IO replies (docs/protocols/realman.md §7, §19): wire integers in, levels,
//! modes and volts out.

use super::decode::{int, ints, object, Body};
use super::DecodeError;

/// One controller port (`get_IO_state`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IoPortState {
    /// Port number, 1-based.
    pub io_num: u8,
    /// `IO_mode` (0 input, 1 output, 2–14 functions).
    pub mode: u8,
    /// Level the port shows (what it drives as an output, what it reads as an input).
    pub high: bool,
}

/// Every input or every output (`get_IO_input` / `get_IO_output`).
#[derive(Debug, Clone, PartialEq)]
pub struct IoLevels {
    /// Digital levels, port 1 first.
    pub digital: Vec<bool>,
    /// Analog voltages, V, channel 1 first.
    pub analog_v: Vec<f64>,
}

/// The tool's ports (`get_tool_IO_state`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ToolIoState {
    /// Whether each port is an output (else an input).
    pub output: Vec<bool>,
    /// Each port's level.
    pub high: Vec<bool>,
}

/// The 2nd-generation version codes (`get_arm_software_version`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SoftwareVersion {
    /// Planning layer: model byte << 16 | one hex digit per version number (0x6B0309).
    pub plan_version: u32,
    /// Realtime control layer, same coding.
    pub ctrl_version: u32,
    /// Realtime kernels (0x0203 = 2.3).
    pub kernel_versions: [u16; 2],
    /// Model (`Product_version`), e.g. `RM65-B`.
    pub product_version: String,
}

impl SoftwareVersion {
    /// `V3.0.9` from a code (its low 12 bits).
    pub fn version_text(code: u32) -> String {
        format!(
            "V{}.{}.{}",
            (code >> 8) & 0xF,
            (code >> 4) & 0xF,
            code & 0xF
        )
    }
}

/// The end-effector's identity (`get_rm_plus_base_info`), the fields a client needs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlusBaseInfo {
    /// Maker.
    pub manufacturer: String,
    /// 1 two-finger gripper, 2 five-finger hand, 3 three-finger gripper.
    pub device_type: i64,
    /// Degrees of freedom.
    pub dof: i64,
    /// Position limits per degree of freedom.
    pub pos_low: Vec<i64>,
    /// See `pos_low`.
    pub pos_up: Vec<i64>,
}

fn level(v: i64) -> Result<bool, DecodeError> {
    match v {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(DecodeError::Field("IO_state")),
    }
}

fn levels(body: &Body, key: &'static str) -> Result<Vec<bool>, DecodeError> {
    ints(body, key)?
        .into_iter()
        .map(|v| level(v).map_err(|_| DecodeError::Field(key)))
        .collect()
}

fn small<T: TryFrom<i64>>(body: &Body, key: &'static str) -> Result<T, DecodeError> {
    T::try_from(int(body, key)?).map_err(|_| DecodeError::Field(key))
}

/// `{"state":"IO_state","IO_Num":n,"IO_Mode":m,"IO_state":s}`.
pub fn io_port_state(body: &Body) -> Result<IoPortState, DecodeError> {
    Ok(IoPortState {
        io_num: small(body, "IO_Num")?,
        mode: small(body, "IO_Mode")?,
        high: level(int(body, "IO_state")?)?,
    })
}

/// `get_IO_input` (`DI`, `AI`) or `get_IO_output` (`DO`, `AO`): analog values in 0.001 V.
pub fn io_levels(
    body: &Body,
    digital: &'static str,
    analog: &'static str,
) -> Result<IoLevels, DecodeError> {
    Ok(IoLevels {
        digital: levels(body, digital)?,
        analog_v: ints(body, analog)?
            .into_iter()
            .map(|mv| mv as f64 / 1000.0)
            .collect(),
    })
}

/// `{"state":"tool_IO_state","IO_Mode":[..],"IO_State":[..]}`.
pub fn tool_io_state(body: &Body) -> Result<ToolIoState, DecodeError> {
    Ok(ToolIoState {
        output: levels(body, "IO_Mode")?,
        high: levels(body, "IO_State")?,
    })
}

/// `voltage_type` of `get_voltage` / `get_tool_voltage`.
pub fn voltage_type(body: &Body) -> Result<u8, DecodeError> {
    small(body, "voltage_type").and_then(|t: u8| {
        if t <= 3 {
            Ok(t)
        } else {
            Err(DecodeError::Field("voltage_type"))
        }
    })
}

/// `{"state":"arm_software_version",…}`.
pub fn software_version(body: &Body) -> Result<SoftwareVersion, DecodeError> {
    Ok(SoftwareVersion {
        plan_version: small(body, "Plan_version")?,
        ctrl_version: small(body, "Ctrl_version")?,
        kernel_versions: [
            small(body, "Real-time_Kernal1")?,
            small(body, "Real-time_Kernal2")?,
        ],
        product_version: body
            .get("Product_version")
            .and_then(|v| v.as_str())
            .unwrap_or_default()
            .to_string(),
    })
}

/// `{"command":"get_rm_plus_base_info","base_info":{…}}`; `Ok(None)` for `get_state: false`
/// (the end-effector protocol is off or no device answers).
pub fn plus_base_info(body: &Body) -> Result<Option<PlusBaseInfo>, DecodeError> {
    if body.get("get_state").and_then(|v| v.as_bool()) == Some(false) {
        return Ok(None);
    }
    let info = object(body, "base_info")?;
    Ok(Some(PlusBaseInfo {
        manufacturer: info
            .get("manu")
            .and_then(|v| v.as_str())
            .ok_or(DecodeError::Field("manu"))?
            .to_string(),
        device_type: int(info, "type")?,
        dof: int(info, "dof")?,
        pos_low: ints(info, "pos_low")?,
        pos_up: ints(info, "pos_up")?,
    }))
}
