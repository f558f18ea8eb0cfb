//! IO commands: the controller's and the tool's ports, their supplies, the 2nd-generation
//! version query and the end-effector identity.

use super::RealmanClient;
use crate::realman::codec::io::{
    self as dio, IoLevels, IoPortState, PlusBaseInfo, SoftwareVersion, ToolIoState,
};
use crate::realman::codec::request as rq;
use crate::realman::error::RealmanError;

impl RealmanClient {
    /// `set_IO_mode`: controller port `io_num` (1–4) to `mode` (0 input, 1 output, 2–14).
    pub async fn set_io_mode(&self, io_num: u8, mode: u8) -> Result<(), RealmanError> {
        self.set(rq::set_io_mode(io_num, mode)?).await.map(drop)
    }

    /// `set_DO_state`: drive an output port; a port not in output mode is `Rejected`.
    pub async fn set_do_state(&self, io_num: u8, high: bool) -> Result<(), RealmanError> {
        self.set(rq::set_do_state(io_num, high)?).await.map(drop)
    }

    /// `get_IO_state`: one port's mode and level.
    pub async fn io_state(&self, io_num: u8) -> Result<IoPortState, RealmanError> {
        self.query(rq::get_io_state(io_num)?, dio::io_port_state)
            .await
    }

    /// `get_IO_input`: every digital input and analog input (V).
    pub async fn io_input(&self) -> Result<IoLevels, RealmanError> {
        self.query(rq::get_io_input(), |b| dio::io_levels(b, "DI", "AI"))
            .await
    }

    /// `get_IO_output`: every digital output and analog output (V).
    pub async fn io_output(&self) -> Result<IoLevels, RealmanError> {
        self.query(rq::get_io_output(), |b| dio::io_levels(b, "DO", "AO"))
            .await
    }

    /// `set_AO_state`: analog output `io_num` (1–4) to `volts` (0–10 V).
    pub async fn set_ao_state(&self, io_num: u8, volts: f64) -> Result<(), RealmanError> {
        self.set(rq::set_ao_state(io_num, volts)?).await.map(drop)
    }

    /// `set_voltage`: controller IO supply (0 → 0 V, 2 → 12 V, 3 → 24 V).
    pub async fn set_voltage(&self, voltage_type: u8) -> Result<(), RealmanError> {
        self.set(rq::set_voltage(voltage_type)?).await.map(drop)
    }

    /// `get_voltage`: controller IO supply setting.
    pub async fn voltage(&self) -> Result<u8, RealmanError> {
        self.query(rq::get_voltage(), dio::voltage_type).await
    }

    /// `set_tool_IO_mode`: tool port `io_num` (1–2) as output (true) or input.
    pub async fn set_tool_io_mode(&self, io_num: u8, output: bool) -> Result<(), RealmanError> {
        self.set(rq::set_tool_io_mode(io_num, output)?)
            .await
            .map(drop)
    }

    /// `set_tool_DO_state`: drive a tool output port.
    pub async fn set_tool_do_state(&self, io_num: u8, high: bool) -> Result<(), RealmanError> {
        self.set(rq::set_tool_do_state(io_num, high)?)
            .await
            .map(drop)
    }

    /// `get_tool_IO_state`: both tool ports' modes and levels.
    pub async fn tool_io_state(&self) -> Result<ToolIoState, RealmanError> {
        self.query(rq::get_tool_io_state(), dio::tool_io_state)
            .await
    }

    /// `set_tool_voltage`: tool supply (0 → 0 V, 1 → 5 V, 2 → 12 V, 3 → 24 V).
    pub async fn set_tool_voltage(&self, voltage_type: u8) -> Result<(), RealmanError> {
        self.set(rq::set_tool_voltage(voltage_type)?)
            .await
            .map(drop)
    }

    /// `get_tool_voltage`: tool supply setting.
    pub async fn tool_voltage(&self) -> Result<u8, RealmanError> {
        self.query(rq::get_tool_voltage(), dio::voltage_type).await
    }

    /// `get_arm_software_version`: the 2nd-generation version codes.
    pub async fn software_version(&self) -> Result<SoftwareVersion, RealmanError> {
        self.query(rq::get_arm_software_version(), dio::software_version)
            .await
    }

    /// `get_rm_plus_base_info`: the end-effector's identity; `None` while the end-effector
    /// protocol is off or nothing answers on the tool port.
    pub async fn rm_plus_base_info(&self) -> Result<Option<PlusBaseInfo>, RealmanError> {
        self.query(rq::get_rm_plus_base_info(), dio::plus_base_info)
            .await
    }
}
