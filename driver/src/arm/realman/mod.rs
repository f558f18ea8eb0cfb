//! The Realman backend: JSON/TCP commands through [`RealmanClient`], realtime state from the
//! UDP push ([`StateFeed`]), the gripper state polled (the push does not carry it), and
//! kinematics on the DH table the controller reports.

mod api;
mod convert;

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::sync::RwLock;
use tokio::task::JoinHandle;

use super::error::{AbcErrorCode, ArmError, ArmResult};
use super::interface::Method;
use super::kinematics::Chain;
use super::params::ArmFactoryParam;
use super::realtime::RealtimeHub;
use super::types::GripperState;
use crate::realman::{
    ClientConfig, JointSpeedUnit, PushCustom, PushSettings, RealmanClient, StateFeed,
};

/// What the Realman backend implements (everything else answers `NOT_IMPLEMENTED`).
pub const REALMAN_CAPABILITIES: &[Method] = &[
    Method::Connect,
    Method::MoveJointPosition,
    Method::MoveCartesianLinear,
    Method::MoveJointPose,
    Method::MoveJointPositionCanfd,
    Method::MoveCartesianPoseCanfd,
    Method::MoveJointFollow,
    Method::MovePoseFollow,
    Method::RealtimeState,
    Method::SetArmSlowStop,
    Method::SetArmStop,
    Method::SetArmPause,
    Method::SetArmContinue,
    Method::SetPlusMode,
    Method::SetGripperRelease,
    Method::SetGripperPick,
    Method::SetGripperPickOn,
    Method::SetGripperPosition,
    Method::GetGripperState,
    Method::SetHandPosture,
    Method::SetHandAngle,
    Method::SetHandFollowAngle,
    Method::SetHandFollowPos,
    Method::SetHandSpeed,
    Method::SetHandForce,
    Method::GetJointDegree,
    Method::ForwardKinematics,
    Method::InverseKinematics,
    Method::SetModbusMode,
    Method::CloseModbusMode,
    Method::WriteRegisters,
    Method::GetErrorFlag,
];

/// Settings of a Realman arm beyond the factory parameters.
#[derive(Debug, Clone)]
pub struct RealmanArmOptions {
    /// Driver settings (reply and motion timeouts).
    pub client: ClientConfig,
    /// Poll the gripper state for the realtime samples.
    pub enable_gripper: bool,
    /// How often the gripper state is polled.
    pub gripper_poll: Duration,
    /// Push settings to apply at connect (`None` leaves the controller's as they are).
    pub push: Option<PushSettings>,
    /// Unit of `joint_speed` in the push.
    pub speed_unit: JointSpeedUnit,
}

impl Default for RealmanArmOptions {
    fn default() -> Self {
        Self {
            client: ClientConfig::default(),
            enable_gripper: false,
            gripper_poll: Duration::from_millis(100),
            push: None,
            speed_unit: JointSpeedUnit::default(),
        }
    }
}

impl RealmanArmOptions {
    /// Default options that aim the push at `ip:port` every `period_ms` at connect.
    pub fn push_to(ip: std::net::Ipv4Addr, port: u16, period_ms: u32) -> Self {
        Self {
            push: Some(push_settings(ip, port, period_ms)),
            ..Self::default()
        }
    }
}

/// Push settings aimed at `ip:port` every `period_ms`, with joint speeds and the motion status.
pub(crate) fn push_settings(ip: std::net::Ipv4Addr, port: u16, period_ms: u32) -> PushSettings {
    PushSettings {
        period_ms,
        enable: true,
        port,
        ip,
        force_coordinate: None,
        custom: PushCustom {
            joint_speed: Some(true),
            arm_current_status: Some(true),
            ..PushCustom::default()
        },
    }
}

/// A Realman arm behind the Arm API.
pub struct RealmanArm {
    name: String,
    params: Option<ArmFactoryParam>,
    options: RealmanArmOptions,
    /// A client and feed handed in by [`RealmanArm::from_client`], used by the first connect.
    prebuilt: Mutex<Option<(RealmanClient, StateFeed)>>,
    hub: Arc<RealtimeHub>,
    link: RwLock<Option<Arc<Link>>>,
}

/// An open connection.
struct Link {
    client: RealmanClient,
    /// Kept alive: dropping it stops the UDP receiver.
    feed: StateFeed,
    chain: Chain,
    gripper: Arc<Mutex<Option<GripperState>>>,
    tasks: Vec<JoinHandle<()>>,
}

impl Drop for Link {
    fn drop(&mut self) {
        for t in &self.tasks {
            t.abort();
        }
    }
}

impl RealmanArm {
    /// An arm that connects over TCP to `ip:port` and receives the push on `udp_ip:udp_port`.
    pub fn new(params: ArmFactoryParam) -> Self {
        let options = RealmanArmOptions {
            enable_gripper: params.enable_gripper,
            ..RealmanArmOptions::default()
        };
        Self {
            name: params.arm_name.clone(),
            params: Some(params),
            options,
            prebuilt: Mutex::new(None),
            hub: Arc::new(RealtimeHub::default()),
            link: RwLock::new(None),
        }
    }

    /// An arm over an already open client and state feed (for example an in-memory stream
    /// and a channel feed under a paused clock). `connect` runs the handshake and applies
    /// `options.push`; `disconnect` drops both, so this arm connects once.
    pub fn from_client(
        name: &str,
        client: RealmanClient,
        feed: StateFeed,
        options: RealmanArmOptions,
    ) -> Self {
        Self {
            name: name.to_string(),
            params: None,
            options,
            prebuilt: Mutex::new(Some((client, feed))),
            hub: Arc::new(RealtimeHub::default()),
            link: RwLock::new(None),
        }
    }

    async fn link(&self) -> ArmResult<Arc<Link>> {
        self.link
            .read()
            .await
            .clone()
            .ok_or_else(|| ArmError::not_connected(&self.name))
    }

    /// Opens client and feed from the factory parameters and aims the push at the feed.
    async fn open(
        &self,
        p: &ArmFactoryParam,
    ) -> ArmResult<(RealmanClient, StateFeed, PushSettings)> {
        let addr = SocketAddr::new(p.ip, p.port).to_string();
        let client = RealmanClient::connect(&addr, self.options.client)
            .await
            .map_err(convert::error)?;
        // Bind the address the push is aimed at; if it is not a local address (a NAT in
        // between), listen on every interface instead.
        // Arms of one process aimed at the same local port share its socket; datagrams go to
        // the arm whose controller sent them (`StateFeed::shared`).
        let controller = SocketAddr::new(p.ip, p.port);
        let unit = self.options.speed_unit;
        let feed = match StateFeed::shared(
            SocketAddr::new(p.udp_ip.into(), p.udp_port),
            controller,
            unit,
        )
        .await
        {
            Ok(f) => f,
            Err(_) => {
                let any = SocketAddr::new(std::net::Ipv4Addr::UNSPECIFIED.into(), p.udp_port);
                StateFeed::shared(any, controller, unit)
                    .await
                    .map_err(|e| ArmError::caused_by(AbcErrorCode::ArmDataReceiveFailed, e))?
            }
        };
        let port = feed.local_addr().map_or(p.udp_port, |a| a.port());
        Ok((
            client,
            feed,
            push_settings(p.udp_ip, port, p.push_period_ms()),
        ))
    }

    async fn open_link(&self) -> ArmResult<Link> {
        let taken = self
            .prebuilt
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        let (client, feed, push) = match (taken, &self.params) {
            (Some((c, f)), _) => (c, f, self.options.push.clone()),
            (None, Some(p)) => {
                let (c, f, push) = self.open(p).await?;
                (c, f, Some(push))
            }
            (None, None) => {
                return Err(ArmError::new(
                    AbcErrorCode::InvalidHandle,
                    "this arm was built from a client that is already closed",
                ))
            }
        };
        let h = client.handshake().await.map_err(convert::error)?;
        if let Some(push) = push {
            client
                .set_realtime_push(&push)
                .await
                .map_err(convert::error)?;
        }
        let gripper = Arc::new(Mutex::new(None));
        let mut tasks = vec![self.forward_states(&feed, gripper.clone())];
        if self.options.enable_gripper {
            tasks.push(self.poll_gripper(client.clone(), gripper.clone()));
        }
        tracing::info!(arm = %self.name, model = %h.software.product_version, "realman arm connected");
        Ok(Link {
            client,
            feed,
            chain: convert::chain(&h),
            gripper,
            tasks,
        })
    }

    /// Pushed samples → realtime states, with the last polled gripper state attached.
    fn forward_states(
        &self,
        feed: &StateFeed,
        gripper: Arc<Mutex<Option<GripperState>>>,
    ) -> JoinHandle<()> {
        let mut rx = feed.subscribe();
        let hub = self.hub.clone();
        let name = self.name.clone();
        let start = tokio::time::Instant::now();
        tokio::spawn(async move {
            use tokio::sync::broadcast::error::RecvError;
            loop {
                match rx.recv().await {
                    Ok(s) => {
                        let g = *gripper.lock().unwrap_or_else(|p| p.into_inner());
                        hub.publish(convert::realtime(&name, start.elapsed(), &s, g));
                    }
                    Err(RecvError::Lagged(n)) => {
                        tracing::debug!(missed = n, "realtime forwarder fell behind");
                    }
                    Err(RecvError::Closed) => break,
                }
            }
        })
    }

    fn poll_gripper(
        &self,
        client: RealmanClient,
        slot: Arc<Mutex<Option<GripperState>>>,
    ) -> JoinHandle<()> {
        let every = self.options.gripper_poll;
        tokio::spawn(async move {
            let mut tick = tokio::time::interval(every);
            tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            loop {
                tick.tick().await;
                match client.gripper_state().await {
                    Ok(g) => {
                        *slot.lock().unwrap_or_else(|p| p.into_inner()) = Some(convert::gripper(&g))
                    }
                    Err(e) => tracing::debug!(error = %e, "gripper poll failed"),
                }
            }
        })
    }
}
