//! [`ArmInterface`] for [`PiperArm`].

use async_trait::async_trait;
use tokio::time::{Duration, Instant};

use super::convert::{self, pose_to_pp};
use super::{Link, PiperArm, PIPER_CAPABILITIES};
use crate::arm::error::{AbcErrorCode, ArmError, ArmResult};
use crate::arm::interface::{ArmInterface, Method};
use crate::arm::kinematics::{pose_distance, unreachable};
use crate::arm::params::Vendor;
use crate::arm::realtime::RealtimeHub;
use crate::arm::types::{
    in_range, joints_to_rad, GripperState, IkMode, MoveOptions, Pose, TrajectoryMode,
};
use crate::piper::{GripperCommand, MotionStatus, MoveKind, Piper, PiperState};

/// Status frames after a command before an error status counts as the answer to it (the
/// frames already in flight still describe the previous command).
const STATUS_SETTLE_FRAMES: u64 = 2;

fn six(q: Vec<f64>) -> [f64; 6] {
    let mut out = [0.0; 6];
    out.copy_from_slice(&q);
    out
}

fn status_seq(s: &PiperState) -> u64 {
    s.arm_status.as_ref().map_or(0, |a| a.seq)
}

/// Waits until `done` holds for a state, failing on an arm error status reported after the
/// command, on timeout and on a lost driver.
async fn wait_for(
    piper: &Piper,
    timeout: Duration,
    what: &str,
    done: impl Fn(&PiperState) -> bool,
) -> ArmResult<()> {
    let mut rx = piper.subscribe_state();
    let start_seq = status_seq(&rx.borrow());
    let deadline = Instant::now() + timeout;
    loop {
        {
            let s = rx.borrow_and_update();
            if let Some(a) = &s.arm_status {
                if a.seq >= start_seq + STATUS_SETTLE_FRAMES {
                    if let Some(code) = convert::status_error(a.value.status) {
                        return Err(ArmError::new(
                            code,
                            format!("{what}: the arm reports {}", a.value.status),
                        ));
                    }
                }
            }
            if done(&s) {
                return Ok(());
            }
        }
        // The state changes hundreds of times a second while the link is up: a silence of
        // FEEDBACK_TIMEOUT means it is down, and waiting out the whole motion timeout would
        // only delay the same answer.
        let wake = (Instant::now() + FEEDBACK_TIMEOUT).min(deadline);
        match tokio::time::timeout_at(wake, rx.changed()).await {
            Err(_) if Instant::now() >= deadline => {
                return Err(ArmError::new(
                    AbcErrorCode::ArmTimeout,
                    format!("{what}: not done within {timeout:?}"),
                ))
            }
            Err(_) => {
                return Err(ArmError::new(
                    AbcErrorCode::ArmTimeout,
                    format!(
                        "{what}: no feedback from the arm for {} ms",
                        FEEDBACK_TIMEOUT.as_millis()
                    ),
                ))
            }
            Ok(Err(_)) => {
                return Err(ArmError::new(
                    AbcErrorCode::ArmDataReceiveFailed,
                    "the Piper driver stopped",
                ))
            }
            Ok(Ok(())) => {}
        }
    }
}

fn reached(s: &PiperState) -> bool {
    s.arm_status
        .as_ref()
        .is_some_and(|a| a.value.motion == MotionStatus::Reached)
}

/// Joint feedback older than this (20 periods at 200 Hz) means the link is gone.
const FEEDBACK_TIMEOUT: Duration = Duration::from_millis(100);

impl PiperArm {
    fn check_move(&self, opts: &MoveOptions) -> ArmResult<()> {
        opts.validate()?;
        if opts.trajectory_connect {
            return Err(ArmError::new(
                AbcErrorCode::NotImplemented,
                "trajectory_connect = 1 (queued moves) is not available on piper arms",
            ));
        }
        Ok(())
    }

    /// The latest joint angles; `ARM_TIMEOUT` when the feedback (200 Hz) has stopped, so a
    /// lost link reads as a timeout, as it does on a Realman, instead of a frozen arm.
    fn current_rad(link: &Link) -> ArmResult<[f64; 6]> {
        let state = link.piper.state();
        let age = state.joints.as_ref().map(|j| j.received_at.elapsed());
        if let Some(age) = age.filter(|a| *a > FEEDBACK_TIMEOUT) {
            return Err(ArmError::new(
                AbcErrorCode::ArmTimeout,
                format!("no joint feedback for {} ms", age.as_millis()),
            ));
        }
        state.joints_rad().ok_or_else(|| {
            ArmError::new(
                AbcErrorCode::ArmDataReceiveFailed,
                "no joint feedback from the arm yet",
            )
        })
    }

    async fn cartesian(&self, kind: MoveKind, pose: &Pose, opts: MoveOptions) -> ArmResult<()> {
        let link = self.link().await?;
        self.check_move(&opts)?;
        pose.check_finite()?;
        let seed = Self::current_rad(&link)?;
        if link
            .chain
            .inverse(pose, &seed, IkMode::IterativeSearch)
            .is_none()
        {
            return Err(unreachable(pose));
        }
        let p = &link.piper;
        p.set_move_mode(kind, opts.speed_percent)
            .await
            .map_err(convert::error)?;
        p.end_pose(pose_to_pp(pose)).await.map_err(convert::error)?;
        if !opts.block {
            return Ok(());
        }
        let (chain, target, tol) = (&link.chain, *pose, self.options.arrival_tolerance_m);
        wait_for(p, self.options.motion_timeout, "cartesian move", |s| {
            reached(s)
                && s.joints_rad().is_some_and(|q| {
                    let (dp, dr) = pose_distance(&chain.forward(&q), &target);
                    dp <= tol && dr <= tol * 10.0
                })
        })
        .await
    }

    async fn gripper(
        &self,
        stroke_m: f64,
        effort_nm: f64,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        let cmd = GripperCommand {
            stroke_m,
            effort_nm,
            enable: true,
            clear_error: false,
        };
        link.piper.gripper(cmd).await.map_err(convert::error)?;
        if !block {
            return Ok(());
        }
        let timeout = Duration::from_secs(u64::from(if timeout_s == 0 { 10 } else { timeout_s }));
        self.wait_gripper_steady(&link.piper, stroke_m, timeout)
            .await
    }

    /// The gripper has stopped when it is at the target or its opening has not changed by
    /// more than 0.1 mm for 200 ms (held by an object).
    async fn wait_gripper_steady(
        &self,
        piper: &Piper,
        target_m: f64,
        timeout: Duration,
    ) -> ArmResult<()> {
        let deadline = Instant::now() + timeout;
        let start = Instant::now();
        let mut last: Option<(f64, Instant)> = None;
        loop {
            if let Some(now_m) = piper.state().gripper_stroke_m() {
                if (now_m - target_m).abs() < 0.001 {
                    return Ok(());
                }
                match last {
                    Some((m, since)) if (m - now_m).abs() <= 0.0001 => {
                        if since.elapsed() >= Duration::from_millis(200)
                            && start.elapsed() >= Duration::from_millis(200)
                        {
                            return Ok(());
                        }
                    }
                    _ => last = Some((now_m, Instant::now())),
                }
            }
            if Instant::now() >= deadline {
                return Err(ArmError::new(
                    AbcErrorCode::ArmTimeout,
                    format!("the gripper did not stop within {timeout:?}"),
                ));
            }
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    }
}

#[async_trait]
impl ArmInterface for PiperArm {
    fn name(&self) -> &str {
        &self.name
    }

    fn vendor(&self) -> Vendor {
        Vendor::Piper
    }

    fn capabilities(&self) -> &'static [Method] {
        PIPER_CAPABILITIES
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
        if let Some(link) = self.link.write().await.take() {
            link.piper.disconnect().await;
        }
    }

    async fn move_joint_position(&self, joints_deg: &[f64], opts: MoveOptions) -> ArmResult<()> {
        let link = self.link().await?;
        self.check_move(&opts)?;
        let target = six(joints_to_rad(joints_deg, 6)?);
        let p = &link.piper;
        p.move_joints_rad(target, opts.speed_percent)
            .await
            .map_err(convert::error)?;
        if !opts.block {
            return Ok(());
        }
        let tol = self.options.arrival_tolerance_deg.to_radians();
        wait_for(p, self.options.motion_timeout, "joint move", |s| {
            reached(s)
                && s.joints_rad()
                    .is_some_and(|q| q.iter().zip(&target).all(|(a, b)| (a - b).abs() <= tol))
        })
        .await
    }

    async fn move_cartesian_linear(&self, pose: &Pose, opts: MoveOptions) -> ArmResult<()> {
        self.cartesian(MoveKind::L, pose, opts).await
    }

    async fn move_joint_pose(&self, pose: &Pose, opts: MoveOptions) -> ArmResult<()> {
        self.cartesian(MoveKind::P, pose, opts).await
    }

    async fn move_joint_position_canfd(
        &self,
        joints_deg: &[f64],
        follow: bool,
        mode: TrajectoryMode,
    ) -> ArmResult<()> {
        let link = self.link().await?;
        if mode != TrajectoryMode::Passthrough {
            return Err(ArmError::new(
                AbcErrorCode::NotImplemented,
                "curve fitting and filtering are not available on piper arms",
            ));
        }
        let target = six(joints_to_rad(joints_deg, 6)?);
        let kind = if follow {
            MoveKind::HighFollow
        } else {
            MoveKind::J
        };
        link.piper
            .set_move_mode(kind, 100)
            .await
            .map_err(convert::error)?;
        link.piper.joints_rad(target).await.map_err(convert::error)
    }

    async fn move_joint_follow(&self, joints_deg: &[f64]) -> ArmResult<()> {
        let link = self.link().await?;
        let target = six(joints_to_rad(joints_deg, 6)?);
        link.piper
            .set_move_mode(MoveKind::J, 100)
            .await
            .map_err(convert::error)?;
        link.piper.joints_rad(target).await.map_err(convert::error)
    }

    async fn move_pose_follow(&self, pose: &Pose) -> ArmResult<()> {
        let link = self.link().await?;
        pose.check_finite()?;
        link.piper
            .set_move_mode(MoveKind::P, 100)
            .await
            .map_err(convert::error)?;
        link.piper
            .end_pose(pose_to_pp(pose))
            .await
            .map_err(convert::error)
    }

    async fn set_arm_stop(&self) -> ArmResult<()> {
        let link = self.link().await?;
        link.piper.emergency_stop().await.map_err(convert::error)
    }

    async fn set_gripper_release(&self, speed: u16, block: bool, timeout_s: u32) -> ArmResult<()> {
        in_range("speed", i64::from(speed), 1, 1000)?;
        let o = self.options;
        self.gripper(
            o.gripper_max_stroke_m,
            o.gripper_move_effort_nm,
            block,
            timeout_s,
        )
        .await
    }

    async fn set_gripper_pick(
        &self,
        speed: u16,
        force: u16,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        in_range("speed", i64::from(speed), 1, 1000)?;
        let force = in_range("force", i64::from(force), 50, 1000)?;
        let effort = f64::from(force) / 1000.0 * self.options.gripper_max_effort_nm;
        self.gripper(0.0, effort, block, timeout_s).await
    }

    async fn set_gripper_pick_on(
        &self,
        speed: u16,
        force: u16,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        // The Piper's gripper holds its torque limit continuously: pick and pick-on agree.
        self.set_gripper_pick(speed, force, block, timeout_s).await
    }

    async fn set_gripper_position(
        &self,
        position: u16,
        block: bool,
        timeout_s: u32,
    ) -> ArmResult<()> {
        let position = in_range("position", i64::from(position), 1, 1000)?;
        let o = self.options;
        let stroke = f64::from(position) / 1000.0 * o.gripper_max_stroke_m;
        self.gripper(stroke, o.gripper_move_effort_nm, block, timeout_s)
            .await
    }

    async fn get_gripper_state(&self) -> ArmResult<GripperState> {
        let link = self.link().await?;
        let state = link.piper.state();
        let g = state.gripper.as_ref().ok_or_else(|| {
            ArmError::new(
                AbcErrorCode::ArmDataReceiveFailed,
                "no gripper feedback from the arm yet",
            )
        })?;
        Ok(convert::gripper(
            &g.value,
            self.options.gripper_max_stroke_m,
        ))
    }

    async fn get_joint_degree(&self) -> ArmResult<Vec<f64>> {
        let link = self.link().await?;
        Ok(Self::current_rad(&link)?
            .iter()
            .map(|r| r.to_degrees())
            .collect())
    }

    async fn forward_kinematics(&self, joints_deg: &[f64]) -> ArmResult<Pose> {
        let link = self.link().await?;
        Ok(link.chain.forward(&joints_to_rad(joints_deg, 6)?))
    }

    async fn inverse_kinematics(
        &self,
        pose: &Pose,
        ref_joints_deg: &[f64],
        mode: IkMode,
    ) -> ArmResult<Vec<f64>> {
        let link = self.link().await?;
        pose.check_finite()?;
        let seed = joints_to_rad(ref_joints_deg, 6)?;
        let q = link
            .chain
            .inverse(pose, &seed, mode)
            .ok_or_else(|| unreachable(pose))?;
        Ok(q.iter().map(|r| r.to_degrees()).collect())
    }
}
