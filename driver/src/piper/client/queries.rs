//! Queries: send, then await the typed reply or a typed error within the query timeout.

use bus::CanFrame;
use tokio::sync::broadcast::error::RecvError;
use tokio::time::Instant;

use super::{lock, Piper, Reply};
use crate::piper::codec::{
    encode_firmware_query, encode_joint_query, si, Ack, AckedCommand, CpvFrame, CpvMode,
    EmergencyStop, FirmwareInfo, GripperTeachParams as WireGripperTeach, JointQuery, Message,
    MotionCtrl1, ParamCommand, ParamQuery, TrackCommand,
};
use crate::piper::error::PiperError;
use crate::piper::types::{EndLimits, GripperTeachParams, JointLimits, TrajectoryAck};

fn trajectory_ack(ack: Ack) -> TrajectoryAck {
    TrajectoryAck {
        point: ack.traj_index,
        name_index: ack.name_index,
        crc16: ack.crc16,
    }
}

impl Piper {
    /// Send `frames`, then wait for replies until `collect` returns `Some` (one query at a
    /// time per driver, so replies are not confused).
    async fn query<T>(
        &self,
        frames: &[CanFrame],
        what: &'static str,
        before_send: impl FnOnce(),
        mut collect: impl FnMut(&Reply) -> Option<T>,
    ) -> Result<T, PiperError> {
        self.ensure_connected()?;
        let timeout = self.inner.config.timeouts.query;
        let _guard = self.inner.query_lock.lock().await;
        let mut replies = self.inner.replies.subscribe();
        before_send();
        // The deadline starts before sending: a full transmit queue counts against it.
        let deadline = Instant::now() + timeout;
        self.send_frames(frames).await?;
        loop {
            match tokio::time::timeout_at(deadline, replies.recv()).await {
                Ok(Ok(reply)) => {
                    if let Some(value) = collect(&reply) {
                        return Ok(value);
                    }
                }
                Ok(Err(RecvError::Lagged(missed))) => {
                    tracing::warn!(missed, what, "query replies lagged")
                }
                Ok(Err(RecvError::Closed)) => return Err(PiperError::Disconnected),
                Err(_) => {
                    tracing::debug!(what, ?timeout, "query timed out");
                    return Err(PiperError::Timeout {
                        what,
                        waited: timeout,
                    });
                }
            }
        }
    }

    /// Send a set command and wait for its 0x476 acknowledgement.
    pub(crate) async fn send_acked(
        &self,
        frame: CanFrame,
        command: AckedCommand,
    ) -> Result<Ack, PiperError> {
        self.query(
            &[frame],
            "0x476 acknowledgement",
            || {},
            |reply| match reply {
                Reply::Frame(Message::Ack(ack)) if ack.cmd == command => Some(*ack),
                _ => None,
            },
        )
        .await
    }

    /// Firmware version (0x4AF, 11-frame reply). With [`super::FirmwareSelection::Auto`] the
    /// reply also selects the firmware profile (MIT packing, MIT mode code, DH table).
    pub async fn query_firmware(&self) -> Result<FirmwareInfo, PiperError> {
        let inner = &self.inner;
        let info = self
            .query(
                &[encode_firmware_query()],
                "0x4AF firmware reply",
                || lock(&inner.firmware).reset(),
                |reply| match reply {
                    Reply::Firmware(info) => Some(info.clone()),
                    _ => None,
                },
            )
            .await?;
        if matches!(inner.config.firmware, super::FirmwareSelection::Auto) {
            if let Some(version) = info.version {
                *lock(&inner.firmware_version) = Some(version);
                tracing::info!(%version, packing = ?version.mit_packing(), "piper firmware detected");
            }
        }
        Ok(info)
    }

    /// Angle limits and max speed of joint 1–6 (0x472 → 0x473).
    pub async fn query_joint_limits(&self, joint: u8) -> Result<JointLimits, PiperError> {
        check(joint)?;
        self.query(
            &[encode_joint_query(joint, JointQuery::Limits)],
            "0x473 joint limits",
            || {},
            |reply| match reply {
                Reply::Frame(Message::JointLimits(l)) if l.joint == joint => {
                    Some(si::joint_limits(l))
                }
                _ => None,
            },
        )
        .await
    }

    /// Limits of all six joints (six queries in one burst, as the SDK's connect does).
    pub async fn query_all_joint_limits(&self) -> Result<[JointLimits; 6], PiperError> {
        let frames: Vec<_> = (1..=6)
            .map(|j| encode_joint_query(j, JointQuery::Limits))
            .collect();
        let mut got: [Option<JointLimits>; 6] = [None; 6];
        self.query(
            &frames,
            "0x473 joint limits (all)",
            || {},
            |reply| {
                if let Reply::Frame(Message::JointLimits(l)) = reply {
                    got[usize::from(l.joint - 1)] = Some(si::joint_limits(l));
                }
                all(&got)
            },
        )
        .await
    }

    /// Max acceleration of joint 1–6, rad/s² (0x472 → 0x47C).
    pub async fn query_joint_max_acc(&self, joint: u8) -> Result<f64, PiperError> {
        check(joint)?;
        self.query(
            &[encode_joint_query(joint, JointQuery::MaxAcc)],
            "0x47C joint max acc",
            || {},
            |reply| match reply {
                Reply::Frame(Message::JointMaxAcc(a)) if a.joint == joint => {
                    Some(si::max_acc(a.max_acc_crad_s2))
                }
                _ => None,
            },
        )
        .await
    }

    /// Max acceleration of all six joints, rad/s².
    pub async fn query_all_joint_max_acc(&self) -> Result<[f64; 6], PiperError> {
        let frames: Vec<_> = (1..=6)
            .map(|j| encode_joint_query(j, JointQuery::MaxAcc))
            .collect();
        let mut got: [Option<f64>; 6] = [None; 6];
        self.query(
            &frames,
            "0x47C joint max acc (all)",
            || {},
            |reply| {
                if let Reply::Frame(Message::JointMaxAcc(a)) = reply {
                    got[usize::from(a.joint - 1)] = Some(si::max_acc(a.max_acc_crad_s2));
                }
                all(&got)
            },
        )
        .await
    }

    /// Send a 0x477 parameter query and wait for the reply `pick` recognises.
    async fn param_query<T>(
        &self,
        query: ParamQuery,
        what: &'static str,
        pick: impl FnMut(&Reply) -> Option<T>,
    ) -> Result<T, PiperError> {
        let frame = ParamCommand {
            query: Some(query),
            ..Default::default()
        }
        .encode();
        self.query(&[frame], what, || {}, pick).await
    }

    /// End-effector velocity / acceleration limits (0x477 `01` → 0x478).
    pub async fn query_end_limits(&self) -> Result<EndLimits, PiperError> {
        self.param_query(
            ParamQuery::EndParams,
            "0x478 end params",
            |reply| match reply {
                Reply::Frame(Message::EndParams(p)) => Some(si::end_limits(p)),
                _ => None,
            },
        )
        .await
    }

    /// Collision-protection levels 0–8 per joint (0x477 `02` → 0x47B).
    pub async fn query_collision_levels(&self) -> Result<[u8; 6], PiperError> {
        self.param_query(
            ParamQuery::Collision,
            "0x47B collision levels",
            |reply| match reply {
                Reply::Frame(Message::Collision(c)) => Some(c.levels),
                _ => None,
            },
        )
        .await
    }

    /// Gripper / teach-pendant parameters (0x477 `04` → 0x47E, fw >= V1.5-2).
    pub async fn query_gripper_teach_params(&self) -> Result<GripperTeachParams, PiperError> {
        self.query_gripper_teach_wire()
            .await
            .map(|wire| si::gripper_teach(&wire))
    }

    pub(crate) async fn query_gripper_teach_wire(&self) -> Result<WireGripperTeach, PiperError> {
        self.param_query(
            ParamQuery::GripperTeach,
            "0x47E gripper/teach params",
            |reply| match reply {
                Reply::Frame(Message::GripperTeach(g)) => Some(*g),
                _ => None,
            },
        )
        .await
    }

    /// Current offline-trajectory index (0x477 `03` → 0x476 with the index in bytes 4–7).
    pub async fn query_trajectory_index(&self) -> Result<TrajectoryAck, PiperError> {
        self.param_query(
            ParamQuery::TrajectoryIndex,
            "0x476 trajectory index",
            |reply| match reply {
                Reply::Frame(Message::Ack(ack)) if ack.cmd == AckedCommand::ParamSettings => {
                    Some(trajectory_ack(*ack))
                }
                _ => None,
            },
        )
        .await
    }

    /// Offline-trajectory transfer of point `index` (0x150 `00 07 00 N`): waits for the
    /// 0x476 acknowledgement of that point (the caller resends on [`PiperError::Timeout`],
    /// as the spec asks).
    pub async fn trajectory_transfer_point(&self, index: u8) -> Result<TrajectoryAck, PiperError> {
        let frame = MotionCtrl1 {
            track: TrackCommand::Transfer,
            traj_index: index,
            ..MotionCtrl1::estop(EmergencyStop::None)
        }
        .encode();
        self.query(
            &[frame],
            "0x476 trajectory point ack",
            || {},
            |reply| match reply {
                Reply::Frame(Message::Ack(ack))
                    if ack.cmd == AckedCommand::TrajectoryPoint && ack.traj_index == index =>
                {
                    Some(trajectory_ack(*ack))
                }
                _ => None,
            },
        )
        .await
    }

    /// End of an offline-trajectory transfer (0x150 `00 08`, package name index and CRC-16).
    /// A package CRC failure (0x476 byte 3 = 0xEE) is [`PiperError::Rejected`].
    pub async fn trajectory_transfer_end(
        &self,
        last_index: u8,
        name_index: u16,
        crc16: u16,
    ) -> Result<TrajectoryAck, PiperError> {
        let frame = MotionCtrl1 {
            track: TrackCommand::TransferEnd,
            traj_index: last_index,
            name_index,
            crc16,
            ..MotionCtrl1::estop(EmergencyStop::None)
        }
        .encode();
        let ack = self
            .query(
                &[frame],
                "0x476 trajectory package ack",
                || {},
                |reply| match reply {
                    Reply::Frame(Message::Ack(ack))
                        if ack.cmd == AckedCommand::TrajectoryPoint && ack.pkg_status != 0 =>
                    {
                        Some(*ack)
                    }
                    _ => None,
                },
            )
            .await?;
        if ack.pkg_status == 0xAE {
            Ok(trajectory_ack(ack))
        } else {
            Err(PiperError::Rejected {
                command: AckedCommand::TrajectoryPoint,
                reason: "trajectory package CRC failure",
            })
        }
    }

    /// Wait for the next 0x476 acknowledgement of `command` without sending anything (for
    /// commands sent with [`Piper::send_frame`]).
    pub async fn wait_ack(&self, command: AckedCommand) -> Result<(), PiperError> {
        self.query(
            &[],
            "0x476 acknowledgement",
            || {},
            |reply| match reply {
                Reply::Frame(Message::Ack(ack)) if ack.cmd == command => Some(()),
                _ => None,
            },
        )
        .await
    }

    /// Read a CPV parameter of motor 1–7 (`'r'` → `'a'` on the same id). CPV parameters are
    /// undocumented vendor registers: the value is returned as the arm sent it.
    pub async fn cpv_read(&self, motor: u8, param: [u8; 2]) -> Result<i32, PiperError> {
        if !(1..=7).contains(&motor) {
            return Err(PiperError::InvalidJoint { joint: motor });
        }
        let request = CpvFrame {
            motor,
            mode: CpvMode::Read,
            param,
            value: 0,
        };
        self.query(
            &[request.encode()],
            "CPV answer",
            || {},
            |reply| match reply {
                Reply::Frame(Message::Cpv(cpv)) if cpv.motor == motor && cpv.param == param => {
                    Some(cpv.value)
                }
                _ => None,
            },
        )
        .await
    }
}

fn check(joint: u8) -> Result<(), PiperError> {
    if (1..=6).contains(&joint) {
        Ok(())
    } else {
        Err(PiperError::InvalidJoint { joint })
    }
}

fn all<T: Copy>(slots: &[Option<T>; 6]) -> Option<[T; 6]> {
    let mut out = [slots[0]?; 6];
    for (i, slot) in slots.iter().enumerate() {
        out[i] = (*slot)?;
    }
    Some(out)
}
