//! Peripheral commands: Modbus RTU, the end-effector protocol mode and hand following.

use super::RealmanClient;
use crate::realman::codec::decode::int;
use crate::realman::codec::request as rq;
use crate::realman::error::RealmanError;

impl RealmanClient {
    /// `set_modbus_mode`: put `port` (0 controller RS485 master, 1 tool RS485 master, 2
    /// controller slave) in Modbus RTU at `baudrate` (9600, 115200 or 460800) with a reply
    /// timeout of `timeout_100ms` × 100 ms.
    pub async fn set_modbus_mode(
        &self,
        port: u8,
        baudrate: u32,
        timeout_100ms: u16,
    ) -> Result<(), RealmanError> {
        self.set(rq::set_modbus_mode(port, baudrate, timeout_100ms)?)
            .await
            .map(drop)
    }

    /// `close_modbus_mode` on `port`.
    pub async fn close_modbus_mode(&self, port: u8) -> Result<(), RealmanError> {
        self.set(rq::close_modbus_mode(port)?).await.map(drop)
    }

    /// `write_registers`: up to 10 holding registers from `address` of slave `device`.
    pub async fn write_registers(
        &self,
        port: u8,
        device: u8,
        address: u16,
        values: &[u16],
    ) -> Result<(), RealmanError> {
        self.set(rq::write_registers(port, device, address, values)?)
            .await
            .map(drop)
    }

    /// `read_holding_registers`: one holding register (the controller reports it signed).
    /// A port not in Modbus mode, or a slave that does not answer, is `Rejected`.
    pub async fn read_holding_register(
        &self,
        port: u8,
        device: u8,
        address: u16,
    ) -> Result<i16, RealmanError> {
        let req = rq::read_holding_registers(port, device, address)?;
        self.query(req, |body| {
            if body.get("read_state").and_then(|v| v.as_bool()) == Some(false) {
                return Ok(None);
            }
            int(body, "data").map(|v| Some(v as i16))
        })
        .await?
        .ok_or(RealmanError::Rejected {
            command: "read_holding_registers",
            key: "read_state",
        })
    }

    /// `set_rm_plus_mode`: the end-effector protocol at `mode` baud (0 off).
    pub async fn set_rm_plus_mode(&self, mode: u32) -> Result<(), RealmanError> {
        self.set(rq::set_rm_plus_mode(mode)?).await.map(drop)
    }

    /// `get_rm_plus_mode`: the end-effector protocol's baud rate (0 off).
    pub async fn rm_plus_mode(&self) -> Result<u32, RealmanError> {
        self.query(rq::get_rm_plus_mode(), |body| {
            int(body, "mode").map(|m| m as u32)
        })
        .await
    }

    /// `hand_follow_angle`: stream finger angles (the hand maker's units); with `block` the
    /// controller's acknowledgement is awaited (and a `false` is `Rejected`).
    pub async fn hand_follow_angle(
        &self,
        angles: [i16; 6],
        block: bool,
    ) -> Result<(), RealmanError> {
        self.set(rq::set_hand_follow_angle(angles, block))
            .await
            .map(drop)
    }

    /// `hand_follow_pos`: stream finger positions (the hand maker's units); `block` as for
    /// [`RealmanClient::hand_follow_angle`].
    pub async fn hand_follow_pos(
        &self,
        positions: [u16; 6],
        block: bool,
    ) -> Result<(), RealmanError> {
        self.set(rq::set_hand_follow_pos(positions, block))
            .await
            .map(drop)
    }
}
