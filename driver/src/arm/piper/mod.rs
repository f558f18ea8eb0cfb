//! The Piper backend: CAN through the Piper driver ([`Piper`]), planned moves with the
//! firmware's MOVE J / P / L modes, joint streaming with joint control frames, realtime state
//! from the CAN feedback (one sample per joint-feedback cycle), kinematics on the driver's
//! DH table.

mod api;
mod convert;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::sync::RwLock;
use tokio::task::JoinHandle;

use super::error::{ArmError, ArmResult};
use super::interface::Method;
use super::kinematics::Chain;
use super::params::ArmFactoryParam;
use super::realtime::RealtimeHub;
#[cfg(target_os = "linux")]
use crate::piper::PiperBuilder;
use crate::piper::{MotorSelect, Piper, PiperState};

/// What the Piper backend implements (everything else answers `NOT_IMPLEMENTED`).
pub const PIPER_CAPABILITIES: &[Method] = &[
    Method::Connect,
    Method::MoveJointPosition,
    Method::MoveCartesianLinear,
    Method::MoveJointPose,
    Method::MoveJointPositionCanfd,
    Method::MoveJointFollow,
    Method::MovePoseFollow,
    Method::RealtimeState,
    Method::SetArmStop,
    Method::SetGripperRelease,
    Method::SetGripperPick,
    Method::SetGripperPickOn,
    Method::SetGripperPosition,
    Method::GetGripperState,
    Method::GetJointDegree,
    Method::ForwardKinematics,
    Method::InverseKinematics,
];

/// Settings of a Piper arm.
#[derive(Debug, Clone, Copy)]
pub struct PiperArmOptions {
    /// Enable all motors at connect (moves need them enabled).
    pub enable_on_connect: bool,
    /// Longest wait of a blocking move.
    pub motion_timeout: Duration,
    /// A blocking joint move has arrived when every joint is this close, degrees.
    pub arrival_tolerance_deg: f64,
    /// A blocking Cartesian move has arrived when the flange is this close, metres.
    pub arrival_tolerance_m: f64,
    /// Gripper stroke that API aperture 1000 stands for, metres.
    pub gripper_max_stroke_m: f64,
    /// Gripper torque that API force 1000 stands for, N·m.
    pub gripper_max_effort_nm: f64,
    /// Gripper torque of release and position moves, N·m.
    pub gripper_move_effort_nm: f64,
}

impl Default for PiperArmOptions {
    fn default() -> Self {
        Self {
            enable_on_connect: true,
            motion_timeout: Duration::from_secs(60),
            arrival_tolerance_deg: 0.2,
            arrival_tolerance_m: 0.002,
            gripper_max_stroke_m: 0.07,
            gripper_max_effort_nm: 5.0,
            gripper_move_effort_nm: 1.0,
        }
    }
}

/// Opens the driver on a SocketCAN interface.
#[cfg(target_os = "linux")]
async fn open_interface(iface: &str) -> ArmResult<Piper> {
    PiperBuilder::interface(iface).connect().await.map_err(|e| {
        let mut err = convert::error(e);
        err.message = format!("CAN interface {iface:?}: {}", err.message);
        err
    })
}

/// SocketCAN exists only on Linux; elsewhere a Piper is reached through
/// [`PiperArm::from_client`] over another bus (socketcand, the virtual bus).
#[cfg(not(target_os = "linux"))]
async fn open_interface(iface: &str) -> ArmResult<Piper> {
    Err(ArmError::new(
        super::AbcErrorCode::NotImplemented,
        format!("CAN interface {iface:?}: SocketCAN is available on Linux only"),
    ))
}

/// Opens the driver on bus `bus_name` of the socketcand server at `addr` (no re-open when
/// the connection drops: the link then reads as lost, as an unplugged adapter does).
async fn open_socketcand(addr: &str, bus_name: &str) -> ArmResult<Piper> {
    let bus = bus::socketcand::SocketcandBus::connect(addr, bus_name)
        .await
        .map_err(|e| ArmError::caused_by(super::AbcErrorCode::ArmDataSendFailed, e))?;
    crate::piper::PiperBuilder::new(Arc::new(bus))
        .connect()
        .await
        .map_err(|e| {
            let mut err = convert::error(e);
            err.message = format!("socketcand {addr} bus {bus_name:?}: {}", err.message);
            err
        })
}

/// Where a Piper created from parameters finds its bus.
#[derive(Debug, Clone)]
enum BusPlace {
    /// A SocketCAN interface.
    Interface(String),
    /// A bus on a socketcand server.
    Socketcand {
        /// `HOST:PORT`.
        addr: String,
        /// The bus name opened on the server.
        bus_name: String,
    },
}

/// A Piper arm behind the Arm API.
pub struct PiperArm {
    name: String,
    bus_place: Option<BusPlace>,
    options: PiperArmOptions,
    prebuilt: Mutex<Option<Piper>>,
    hub: Arc<RealtimeHub>,
    link: RwLock<Option<Arc<Link>>>,
}

struct Link {
    piper: Piper,
    chain: Chain,
    forwarder: JoinHandle<()>,
}

impl Drop for Link {
    fn drop(&mut self) {
        self.forwarder.abort();
    }
}

impl PiperArm {
    /// An arm on the SocketCAN interface named in `params.can_interface`, or with
    /// `params.socketcand` on that bus of the socketcand server.
    pub fn new(params: ArmFactoryParam) -> Self {
        let place = match params.socketcand {
            Some(addr) => BusPlace::Socketcand {
                addr,
                bus_name: params.can_interface,
            },
            None => BusPlace::Interface(params.can_interface),
        };
        Self {
            name: params.arm_name,
            bus_place: Some(place),
            options: PiperArmOptions::default(),
            prebuilt: Mutex::new(None),
            hub: Arc::new(RealtimeHub::default()),
            link: RwLock::new(None),
        }
    }

    /// An arm over an already connected driver (for example on a virtual bus). `connect`
    /// enables the motors (per `options`) and starts the realtime stream.
    pub fn from_client(name: &str, piper: Piper, options: PiperArmOptions) -> Self {
        Self {
            name: name.to_string(),
            bus_place: None,
            options,
            prebuilt: Mutex::new(Some(piper)),
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

    async fn open_link(&self) -> ArmResult<Link> {
        let taken = self
            .prebuilt
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        let piper = match (taken, &self.bus_place) {
            (Some(p), _) => p,
            (None, Some(BusPlace::Interface(iface))) => open_interface(iface).await?,
            (None, Some(BusPlace::Socketcand { addr, bus_name })) => {
                open_socketcand(addr, bus_name).await?
            }
            (None, None) => {
                return Err(ArmError::new(
                    super::AbcErrorCode::InvalidHandle,
                    "this arm was built from a driver that is already closed",
                ))
            }
        };
        if self.options.enable_on_connect {
            if let Err(e) = piper.enable(MotorSelect::All).await {
                piper.disconnect().await;
                return Err(convert::error(e));
            }
        }
        let chain = convert::chain(piper.dh_variant());
        let forwarder = self.forward_states(piper.subscribe_state());
        tracing::info!(arm = %self.name, "piper arm connected");
        Ok(Link {
            piper,
            chain,
            forwarder,
        })
    }

    /// Publishes one sample per joint-feedback cycle (when the joint angles' sequence moves).
    fn forward_states(&self, mut rx: tokio::sync::watch::Receiver<PiperState>) -> JoinHandle<()> {
        let hub = self.hub.clone();
        let name = self.name.clone();
        let stroke = self.options.gripper_max_stroke_m;
        let start = tokio::time::Instant::now();
        tokio::spawn(async move {
            let mut last_seq = 0;
            while rx.changed().await.is_ok() {
                // Converted under the borrow: most changes are other frames of the cycle and
                // cost one comparison, not a copy of the state.
                let sample = {
                    let state = rx.borrow_and_update();
                    let seq = state.joints.as_ref().map_or(0, |j| j.seq);
                    if seq == last_seq {
                        continue;
                    }
                    last_seq = seq;
                    convert::realtime(&name, start.elapsed(), &state, stroke)
                };
                if let Some(s) = sample {
                    hub.publish(s);
                }
            }
        })
    }
}
