//! [`ArmInterface`] for [`RealmanArm`].

use std::future::Future;
use std::time::Duration;

use async_trait::async_trait;

use super::convert::{self, pose_to_rm};
use super::{Link, RealmanArm, REALMAN_CAPABILITIES};
use crate::arm::error::{AbcErrorCode, ArmError, ArmResult};
use crate::arm::interface::{ArmInterface, Method};
use crate::arm::kinematics::unreachable;
use crate::arm::params::Vendor;
use crate::arm::realtime::RealtimeHub;
use crate::arm::types::{
    in_range, joints_to_rad, ErrorFlags, GripperState, IkMode, MoveOptions,
    PeripheralReadWriteParams, Pose, TrajectoryMode,
};
use crate::realman::{CartesianTarget, Connect, MoveOpts, RealmanError};

fn move_opts(o: &MoveOptions) -> ArmResult<MoveOpts> {
    o.validate()?;
    Ok(MoveOpts {
        speed_percent: o.speed_percent,
        blend_percent: o.blend_radius,
        connect: if o.trajectory_connect {
            Connect::Queue
        } else {
            Connect::Start
        },
    })
}

/// Runs a gripper or hand command; a blocking one with a nonzero `timeout_s` gives up after it
/// with `ARM_TIMEOUT`.
async fn bounded(
    block: bool,
    timeout_s: u32,
    f: impl Future<Output = Result<(), RealmanError>>,
) -> ArmResult<()> {
    if block && timeout_s > 0 {
        match tokio::time::timeout(Duration::from_secs(u64::from(timeout_s)), f).await {
            Ok(r) => r.map_err(convert::error),
            Err(_) => Err(ArmError::new(
                AbcErrorCode::ArmTimeout,
                format!("the device did not arrive within {timeout_s} s"),
            )),
        }
    } else {
        f.await.map_err(convert::error)
    }
}

impl RealmanArm {
    /// The current joints (rad): the latest push sample, else a query.
    async fn current_rad(&self, link: &Link) -> ArmResult<Vec<f64>> {
        match link.feed.latest() {
            Some(s) => Ok(s.joints_rad.clone()),
            None => link.client.joint_positions().await.map_err(convert::error),
        }
    }

    /// `ARM_OUT_OF_RANGE` when no joint solution reaches `pose` (the same check and code as
    /// the Piper backend, so an unreachable pose reads the same on every vendor).
    async fn check_reachable(&self, link: &Link, pose: &Pose) -> ArmResult<()> {
        pose.check_finite()?;
        let seed = self.current_rad(link).await?;
        match link.chain.inverse(pose, &seed, IkMode::IterativeSearch) {
            Some(_) => Ok(()),
            None => Err(unreachable(pose)),
        }
    }
}

fn hand_values(v: [i32; 6]) -> ArmResult<[Option<u16>; 6]> {
    let mut out = [None; 6];
    for (o, x) in out.iter_mut().zip(v) {
        *o = match x {
            -1 => None,
            x => Some(in_range("hand_angle", i64::from(x), 0, 1000)?),
        };
    }
    Ok(out)
}

#[async_trait]
impl ArmInterface for RealmanArm {
    fn name(&self) -> &str {
        &self.name
    }

    fn vendor(&self) -> Vendor {
        Vendor::Realman
    }

    fn capabilities(&self) -> &'static [Method] {
        REALMAN_CAPABILITIES
    }

    fn realtime_hub(&self) -> &RealtimeHub {
        &self.hub
    }

    async fn connect(&self) -> ArmResult<()> {
        let mut slot = self.link.write().await;
        if slot.is_none() {
            *slot = Some(std::sync::Arc::new(self.open_link().await?));
        }
        Ok(())
    }

    async fn disconnect(&self) {
        self.link.write().await.take();
    }

    async fn move_joint_position(&self, joints_deg: &[f64], opts: MoveOptions) -> ArmResult<()> {
        let link = self.link().await?;
        let o = move_opts(&opts)?;
        let q = joints_to_rad(joints_deg, link.chain.dof())?;
        link.client
            .movej(&q, o, opts.block)
            .await
            .map_err(convert::error)
    }

    async fn move_cartesian_linear(&self, pose: &Pose, opts: MoveOptions) -> ArmResult<()> {
        let link = self.link().await?;
        let o = move_opts(&opts)?;
        self.check_reachable(&link, pose).await?;
        let p = pose_to_rm(pose);
        link.client
            .movel(&p, o, opts.block)
            .await
            .map_err(convert::error)
    }

    async fn move_joint_pose(&self, pose: &Pose, opts: MoveOptions) -> ArmResult<()> {
        let link = self.link().await?;
        let o = move_opts(&opts)?;
        self.check_reachable(&link, pose).await?;
        let p = pose_to_rm(pose);
        link.client
            .movej_p(&p, o, opts.block)
            .await
            .map_err(convert::error)
    }

    async fn move_joint_position_canfd(
        &self,
        joints_deg: &[f64],
        follow: bool,
        mode: TrajectoryMode,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        let q = joints_to_rad(joints_deg, link.chain.dof())?;
        link.client
            .movej_canfd(&q, follow, convert::smoothing(mode))
            .await
            .map_err(convert::error)
    }

    async fn move_cartesian_pose_canfd(
        &self,
        pose: &Pose,
        follow: bool,
        mode: TrajectoryMode,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        pose.check_finite()?;
        let target = CartesianTarget::Euler(pose_to_rm(pose));
        link.client
            .movep_canfd(&target, follow, convert::smoothing(mode))
            .await
            .map_err(convert::error)
    }

    async fn move_joint_follow(&self, joints_deg: &[f64]) -> ArmResult<()> {
        let link = self.link().await?;
        let q = joints_to_rad(joints_deg, link.chain.dof())?;
        link.client.movej_follow(&q).await.map_err(convert::error)
    }

    async fn move_pose_follow(&self, pose: &Pose) -> ArmResult<()> {
        let link = self.link().await?;
        pose.check_finite()?;
        let target = CartesianTarget::Euler(pose_to_rm(pose));
        link.client
            .movep_follow(&target)
            .await
            .map_err(convert::error)
    }

    async fn set_arm_slow_stop(&self) -> ArmResult<()> {
        let link = self.link().await?;
        link.client.slow_stop().await.map_err(convert::error)
    }

    async fn set_arm_stop(&self) -> ArmResult<()> {
        let link = self.link().await?;
        link.client.stop().await.map_err(convert::error)
    }

    async fn set_arm_pause(&self) -> ArmResult<()> {
        let link = self.link().await?;
        link.client.pause().await.map_err(convert::error)
    }

    async fn set_arm_continue(&self) -> ArmResult<()> {
        let link = self.link().await?;
        link.client.resume().await.map_err(convert::error)
    }

    async fn set_gripper_release(&self, speed: u16, block: bool, timeout_s: u32) -> ArmResult<()> {
        let link = self.link().await?;
        let speed = in_range("speed", i64::from(speed), 1, 1000)?;
        bounded(block, timeout_s, link.client.gripper_release(speed, block)).await
    }

    async fn set_gripper_pick(
        &self,
        speed: u16,
        force: u16,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        let speed = in_range("speed", i64::from(speed), 1, 1000)?;
        let force = in_range("force", i64::from(force), 50, 1000)?;
        bounded(
            block,
            timeout_s,
            link.client.gripper_pick(speed, force, block),
        )
        .await
    }

    async fn set_gripper_pick_on(
        &self,
        speed: u16,
        force: u16,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        let speed = in_range("speed", i64::from(speed), 1, 1000)?;
        let force = in_range("force", i64::from(force), 50, 1000)?;
        bounded(
            block,
            timeout_s,
            link.client.gripper_pick_on(speed, force, block),
        )
        .await
    }

    async fn set_gripper_position(
        &self,
        position: u16,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        let position = in_range("position", i64::from(position), 1, 1000)?;
        bounded(
            block,
            timeout_s,
            link.client.gripper_position(position, block),
        )
        .await
    }

    async fn get_gripper_state(&self) -> ArmResult<GripperState> {
        let link = self.link().await?;
        let g = link.client.gripper_state().await.map_err(convert::error)?;
        let g = convert::gripper(&g);
        *link.gripper.lock().unwrap_or_else(|p| p.into_inner()) = Some(g);
        Ok(g)
    }

    async fn set_hand_posture(
        &self,
        posture_num: u8,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        let n = in_range("posture_num", i64::from(posture_num), 1, 40)? as u8;
        bounded(block, timeout_s, link.client.hand_posture(n, block)).await
    }

    async fn set_hand_angle(&self, hand_angle: [i32; 6]) -> ArmResult<()> {
        let link = self.link().await?;
        let v = hand_values(hand_angle)?;
        link.client
            .hand_angles(v, false)
            .await
            .map_err(convert::error)
    }

    async fn set_hand_follow_angle(&self, hand_angle: [i32; 6], block_ms: u32) -> ArmResult<()> {
        let link = self.link().await?;
        let mut angles = [0i16; 6];
        for (slot, v) in angles.iter_mut().zip(hand_angle) {
            *slot = in_range_i16("hand_angle", v)?;
        }
        link.client
            .hand_follow_angle(angles, block_ms > 0)
            .await
            .map_err(convert::error)
    }

    async fn set_hand_follow_pos(&self, hand_pos: [i32; 6], block_ms: u32) -> ArmResult<()> {
        let link = self.link().await?;
        let mut positions = [0u16; 6];
        for (slot, v) in positions.iter_mut().zip(hand_pos) {
            *slot = in_range("hand_pos", i64::from(v), 0, 65_535)?;
        }
        link.client
            .hand_follow_pos(positions, block_ms > 0)
            .await
            .map_err(convert::error)
    }

    async fn set_plus_mode(&self, mode: u32) -> ArmResult<()> {
        // The driver's encoder refuses a mode outside its table (PARAM_OUT_OF_RANGE).
        let link = self.link().await?;
        link.client
            .set_rm_plus_mode(mode)
            .await
            .map_err(convert::error)
    }

    async fn set_modbus_mode(&self, port: u8, baudrate: u32, timeout_100ms: u32) -> ArmResult<()> {
        let link = self.link().await?;
        let port = rtu_port(port)?;
        // The baud rate is checked by the driver's encoder (PARAM_OUT_OF_RANGE).
        let timeout = in_range("timeout", i64::from(timeout_100ms), 0, 65_535)?;
        link.client
            .set_modbus_mode(port, baudrate, timeout)
            .await
            .map_err(convert::error)
    }

    async fn close_modbus_mode(&self, port: u8) -> ArmResult<()> {
        let link = self.link().await?;
        link.client
            .close_modbus_mode(rtu_port(port)?)
            .await
            .map_err(convert::error)
    }

    async fn write_registers(
        &self,
        params: &PeripheralReadWriteParams,
        values: &[u16],
    ) -> ArmResult<()> {
        let link = self.link().await?;
        let port = rtu_port(params.port)?;
        if usize::from(params.num) != values.len() {
            return Err(ArmError::new(
                AbcErrorCode::ParamError,
                format!(
                    "num is {} but {} values were given",
                    params.num,
                    values.len()
                ),
            ));
        }
        // 1..=10 registers: checked by the driver's encoder (PARAM_OUT_OF_RANGE).
        link.client
            .write_registers(port, params.device, params.address, values)
            .await
            .map_err(convert::error)
    }

    async fn set_hand_speed(&self, speed: u16) -> ArmResult<()> {
        let link = self.link().await?;
        let speed = in_range("speed", i64::from(speed), 1, 1000)?;
        link.client.hand_speed(speed).await.map_err(convert::error)
    }

    async fn set_hand_force(&self, hand_force: u16) -> ArmResult<()> {
        let link = self.link().await?;
        let force = in_range("hand_force", i64::from(hand_force), 1, 1000)?;
        link.client.hand_force(force).await.map_err(convert::error)
    }

    async fn get_joint_degree(&self) -> ArmResult<Vec<f64>> {
        let link = self.link().await?;
        let q = link
            .client
            .joint_positions()
            .await
            .map_err(convert::error)?;
        Ok(q.iter().map(|r| r.to_degrees()).collect())
    }

    async fn forward_kinematics(&self, joints_deg: &[f64]) -> ArmResult<Pose> {
        let link = self.link().await?;
        let q = joints_to_rad(joints_deg, link.chain.dof())?;
        Ok(link.chain.forward(&q))
    }

    async fn inverse_kinematics(
        &self,
        pose: &Pose,
        ref_joints_deg: &[f64],
        mode: IkMode,
    ) -> ArmResult<Vec<f64>> {
        let link = self.link().await?;
        pose.check_finite()?;
        let seed = joints_to_rad(ref_joints_deg, link.chain.dof())?;
        let q = link
            .chain
            .inverse(pose, &seed, mode)
            .ok_or_else(|| unreachable(pose))?;
        Ok(q.iter().map(|r| r.to_degrees()).collect())
    }

    async fn get_error_flag(&self) -> ArmResult<ErrorFlags> {
        let link = self.link().await?;
        let f = link.client.joint_flags().await.map_err(convert::error)?;
        Ok(ErrorFlags {
            joint_errors: f.errors.iter().map(|e| u32::from(e.0)).collect(),
            brake_engaged: f.brake_engaged,
        })
    }
}

/// A Modbus RTU port (0 controller RS485, 1 tool RS485, 2 controller slave); port 3, the
/// controller's Modbus TCP master, is not implemented by the Realman driver.
fn rtu_port(port: u8) -> ArmResult<u8> {
    match port {
        0..=2 => Ok(port),
        3 => Err(ArmError::not_implemented("realman", "Modbus TCP (port 3)")),
        _ => Err(ArmError::out_of_range("port", port, "0..=3")),
    }
}

/// `PARAM_OUT_OF_RANGE` unless `value` fits a signed 16-bit word.
fn in_range_i16(field: &str, value: i32) -> ArmResult<i16> {
    i16::try_from(value).map_err(|_| ArmError::out_of_range(field, value, "-32768..=32767"))
}
