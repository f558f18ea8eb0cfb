//! A Realman arm on the bench: the [`Device`] that drives `driver::realman` against the
//! in-process `sim::realman` emulator over in-memory streams (virtual or real time), with the
//! UDP push carried to the driver's state feed through a channel. The later command families
//! live in [`stream`], [`jog`] and [`params`].

mod jog;
mod params;
mod stream;

use std::collections::VecDeque;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use async_trait::async_trait;
use driver::realman::{
    ClientConfig, Connect, JointSpeedUnit, MoveOpts, Pose, PushCustom, PushSettings, RealmanClient,
    RealmanError, StateFeed,
};
use sim::realman::model::ArmModel;
use sim::realman::{ControllerConfig, EmulatorConfig, RealmanEmulator, RealmanHandle, Transport};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use super::model::{Motion, PoseDeg, RealmanAction, RealmanSettings, RmCommand, RmFault};
use super::observe::Observation;
use super::trace;
use crate::devices::{within, Device, DeviceError, Reply, TraceColumn};
use crate::devices::{Action, Check, DeviceFault};
use crate::scenario::{ErrorClass, Signal};

/// The IP the driver's host has on the emulated network (the push aims at it).
pub(crate) const HOST_IP: Ipv4Addr = Ipv4Addr::new(192, 168, 1, 10);
/// The port the driver's state feed listens on (the controller's default push port).
pub(crate) const PUSH_PORT: u16 = 8089;

fn classify(error: &RealmanError) -> ErrorClass {
    match error {
        RealmanError::Timeout { .. } | RealmanError::MotionTimeout { .. } => ErrorClass::Timeout,
        RealmanError::Rejected { .. } | RealmanError::MotionFailed { .. } => ErrorClass::Rejected,
        RealmanError::Connect { .. }
        | RealmanError::Io { .. }
        | RealmanError::Disconnected { .. }
        | RealmanError::Malformed { .. } => ErrorClass::Bus,
        RealmanError::Encode(_) | RealmanError::NoAddress => ErrorClass::InvalidArgument,
    }
}

fn derr(error: RealmanError) -> DeviceError {
    DeviceError::new(classify(&error), error.to_string())
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Push settings as the bench uses them: to the host, with the motion status and joint speeds.
fn push_settings(period_ms: u32, enable: bool) -> PushSettings {
    PushSettings {
        period_ms,
        enable,
        port: PUSH_PORT,
        ip: HOST_IP,
        force_coordinate: None,
        custom: PushCustom {
            joint_speed: Some(true),
            arm_current_status: Some(true),
            ..PushCustom::default()
        },
    }
}

/// A scenario pose in the driver's units.
fn pose(p: &PoseDeg) -> Pose {
    Pose {
        position_m: p.position_m,
        euler_rad: p.euler_deg.map(f64::to_radians),
    }
}

fn opts(m: &Motion) -> MoveOpts {
    MoveOpts {
        speed_percent: m.speed,
        blend_percent: m.blend,
        connect: if m.queue {
            Connect::Queue
        } else {
            Connect::Start
        },
    }
}

/// A Realman emulator on in-memory streams with the driver's state feed fed by its push
/// (datagrams aimed at the host only, as on a real network), and the push arrival times.
pub(crate) struct Emulated {
    /// The emulator.
    pub emu: RealmanHandle,
    /// Joints of the model.
    pub dof: usize,
    /// The driver's state feed.
    pub feed: StateFeed,
    /// Arrival times of the push datagrams of the last second.
    pub stamps: Arc<Mutex<VecDeque<Instant>>>,
}

impl Emulated {
    /// Start the emulator for `settings`; clients connect with [`Emulated::client`].
    pub(crate) async fn spawn(name: &str, settings: &RealmanSettings) -> Result<Self, String> {
        let model = ArmModel::from_product(settings.model)
            .ok_or_else(|| format!("device `{name}`: no emulator model {}", settings.model))?;
        let dof = model.dof;
        let mut controller = ControllerConfig::new(model);
        controller.gripper = settings.gripper;
        controller.initial_joints_rad = settings
            .initial_joints_deg
            .as_ref()
            .map(|j| j.iter().map(|d| d.to_radians()).collect());
        let emu = RealmanEmulator::spawn(EmulatorConfig::new(controller), Transport::InMemory)
            .await
            .map_err(|e| format!("device `{name}`: emulator: {e}"))?;
        let mut datagrams = emu
            .take_datagrams()
            .ok_or_else(|| format!("device `{name}`: emulator gives no datagram stream"))?;
        let (tx, rx) = tokio::sync::mpsc::channel(1024);
        let stamps = Arc::new(Mutex::new(VecDeque::new()));
        let host = SocketAddr::new(IpAddr::V4(HOST_IP), PUSH_PORT);
        let seen = Arc::clone(&stamps);
        tokio::spawn(async move {
            // The emulated network: only datagrams addressed to the host's feed arrive.
            while let Some(d) = datagrams.recv().await {
                if d.to != host {
                    continue;
                }
                let now = Instant::now();
                {
                    let mut s = lock(&seen);
                    s.push_back(now);
                    while s.front().is_some_and(|t| now - *t > Duration::from_secs(1)) {
                        s.pop_front();
                    }
                }
                if tx.send(d.payload.into_bytes()).await.is_err() {
                    break;
                }
            }
        });
        let feed = StateFeed::from_channel(rx, JointSpeedUnit::default());
        Ok(Self {
            emu,
            dof,
            feed,
            stamps,
        })
    }

    /// Open one more driver connection to the emulator.
    pub(crate) async fn client(&self, name: &str) -> Result<RealmanClient, String> {
        let stream = self
            .emu
            .connect(IpAddr::V4(HOST_IP))
            .map_err(|e| format!("device `{name}`: connect: {e}"))?;
        Ok(RealmanClient::from_stream(stream, ClientConfig::default()).await)
    }
}

/// One Realman arm: the emulator, the driver's connections and its state feed.
pub(crate) struct RealmanDevice {
    name: String,
    dof: usize,
    /// The emulator (`None` once shut down).
    emu: Mutex<Option<RealmanHandle>>,
    clients: Vec<RealmanClient>,
    feed: StateFeed,
    /// Arrival times of the push datagrams of the last second.
    stamps: Arc<Mutex<VecDeque<Instant>>>,
    active: Mutex<Vec<RmFault>>,
    /// A stream running in the background (`block: false`).
    streaming: Mutex<Option<JoinHandle<()>>>,
}

impl RealmanDevice {
    /// Start the emulator, connect `settings.clients` driver connections and the state feed.
    pub(crate) async fn start(name: &str, settings: &RealmanSettings) -> Result<Self, String> {
        let emulated = Emulated::spawn(name, settings).await?;
        let mut clients = Vec::new();
        for _ in 0..settings.clients {
            clients.push(emulated.client(name).await?);
        }
        let Emulated {
            emu,
            dof,
            feed,
            stamps,
        } = emulated;
        clients[0]
            .set_realtime_push(&push_settings(5, true))
            .await
            .map_err(|e| format!("device `{name}`: realtime push: {e}"))?;
        // Conditions judge the push: start with a sample in hand (one comes every 5 ms).
        let mut first = feed.watch();
        tokio::time::timeout(Duration::from_secs(1), first.wait_for(Option::is_some))
            .await
            .map_err(|_| format!("device `{name}`: no realtime push within 1 s"))?
            .map_err(|_| format!("device `{name}`: the state feed stopped"))?;
        Ok(Self {
            name: name.to_owned(),
            dof,
            emu: Mutex::new(Some(emu)),
            clients,
            feed,
            stamps,
            active: Mutex::new(Vec::new()),
            streaming: Mutex::new(None),
        })
    }

    fn client(&self, index: usize) -> Result<&RealmanClient, DeviceError> {
        self.clients.get(index).ok_or_else(|| {
            DeviceError::unsupported(format!(
                "`{}` has {} client(s); `client: {}` is not one",
                self.name,
                self.clients.len(),
                index + 1
            ))
        })
    }

    /// Run `f` on the emulator.
    fn with_emu<R>(
        &self,
        f: impl FnOnce(&RealmanHandle) -> Result<R, String>,
    ) -> Result<R, DeviceError> {
        match lock(&self.emu).as_ref() {
            Some(h) => f(h).map_err(|e| DeviceError::unsupported(format!("emulator: {e}"))),
            None => Err(DeviceError::unsupported("the emulator has been shut down")),
        }
    }

    fn observe(&self) -> Observation {
        let now = Instant::now();
        let push_hz = lock(&self.stamps)
            .iter()
            .filter(|t| now - **t <= Duration::from_secs(1))
            .count() as f64;
        let connected = self.clients.iter().all(RealmanClient::is_connected);
        match self.feed.latest() {
            Some(s) => Observation::from_sample(&s, push_hz, connected),
            None => Observation {
                push_hz,
                connected,
                ..Observation::default()
            },
        }
    }

    async fn act(&self, a: &RealmanAction) -> Result<Reply, DeviceError> {
        let arm = self.client(a.client)?;
        let mut reply = Reply::default();
        match &a.command {
            RmCommand::Handshake => {
                let h = arm.handshake().await.map_err(derr)?;
                reply
                    .values
                    .push(("product".to_owned(), h.software.product_version));
                reply
                    .values
                    .push(("dof".to_owned(), h.software.dof.to_string()));
            }
            RmCommand::MoveJ(j, m) => {
                let q: Vec<f64> = j.iter().map(|d| d.to_radians()).collect();
                arm.movej(&q, opts(m), m.block).await.map_err(derr)?;
            }
            RmCommand::MoveL(p, m) => arm.movel(&pose(p), opts(m), m.block).await.map_err(derr)?,
            RmCommand::MoveJP(p, m) => {
                arm.movej_p(&pose(p), opts(m), m.block)
                    .await
                    .map_err(derr)?;
            }
            RmCommand::MoveC {
                via,
                to,
                loops,
                motion,
            } => arm
                .movec(&pose(via), &pose(to), *loops, opts(motion), motion.block)
                .await
                .map_err(derr)?,
            RmCommand::Stop => arm.stop().await.map_err(derr)?,
            RmCommand::SlowStop => arm.slow_stop().await.map_err(derr)?,
            RmCommand::Pause => arm.pause().await.map_err(derr)?,
            RmCommand::Continue => arm.resume().await.map_err(derr)?,
            RmCommand::DeleteTrajectories => arm.delete_all_trajectories().await.map_err(derr)?,
            RmCommand::ClearErrors => arm.clear_errors().await.map_err(derr)?,
            RmCommand::Power(on) => arm.set_power(*on).await.map_err(derr)?,
            RmCommand::Push { period_ms, enable } => arm
                .set_realtime_push(&push_settings(*period_ms, *enable))
                .await
                .map_err(derr)?,
            RmCommand::GripperPosition { position, block } => {
                arm.gripper_position(*position, *block)
                    .await
                    .map_err(derr)?;
            }
            RmCommand::GripperPick {
                speed,
                force,
                block,
            } => arm
                .gripper_pick(*speed, *force, *block)
                .await
                .map_err(derr)?,
            RmCommand::GripperRelease { speed, block } => {
                arm.gripper_release(*speed, *block).await.map_err(derr)?;
            }
            RmCommand::ReadGripper { expect } => {
                let g = arm.gripper_state().await.map_err(derr)?;
                let shown = g.position.to_string();
                reply.values.push(("position".to_owned(), shown.clone()));
                reply
                    .values
                    .push(("mode".to_owned(), format!("{:?}", g.mode)));
                if let Some(e) = expect {
                    if (g.position as f64 - e.value).abs() > e.tolerance {
                        reply.mismatches.push((
                            "position".to_owned(),
                            format!("{} ± {}", e.value, e.tolerance),
                            shown,
                        ));
                    }
                }
            }
            RmCommand::HandPosture { posture, block } => {
                arm.hand_posture(*posture, *block).await.map_err(derr)?;
            }
            RmCommand::HandAngles { angles, block } => {
                arm.hand_angles(*angles, *block).await.map_err(derr)?;
            }
            RmCommand::ReadJoints => {
                let q = arm.joint_positions().await.map_err(derr)?;
                let deg: Vec<String> = q.iter().map(|r| format!("{:.2}", r.to_degrees())).collect();
                reply
                    .values
                    .push(("joints_deg".to_owned(), format!("[{}]", deg.join(", "))));
            }
            RmCommand::Reconnect => {
                let stream =
                    self.with_emu(|h| h.connect(IpAddr::V4(HOST_IP)).map_err(|e| e.to_string()))?;
                arm.reconnect_with(stream).await;
            }
            RmCommand::Stream(s) => self.start_stream(arm, s).await?,
            RmCommand::Step { .. } | RmCommand::Teach { .. } | RmCommand::StopTeach => {
                jog::perform(arm, &a.command).await.map_err(derr)?;
            }
            RmCommand::SetParam { .. }
            | RmCommand::GetParam { .. }
            | RmCommand::ResetParams
            | RmCommand::ResetDh
            | RmCommand::SetZeroOffset(_)
            | RmCommand::JointEnable { .. } => params::perform(arm, &a.command, &mut reply).await?,
        }
        Ok(reply)
    }

    /// Send a stream: here (`block`) or in a background task that a later stream replaces.
    async fn start_stream(
        &self,
        arm: &RealmanClient,
        s: &super::model::Stream,
    ) -> Result<(), DeviceError> {
        if let Some(previous) = lock(&self.streaming).take() {
            previous.abort();
        }
        if s.block {
            return stream::run(arm, s).await.map_err(derr);
        }
        let (arm, s) = (arm.clone(), s.clone());
        let name = self.name.clone();
        let task = tokio::spawn(async move {
            if let Err(e) = stream::run(&arm, &s).await {
                tracing::warn!(device = %name, error = %e, "Realman background stream stopped");
            }
        });
        *lock(&self.streaming) = Some(task);
        Ok(())
    }
}

#[async_trait]
impl Device for RealmanDevice {
    fn name(&self) -> &str {
        &self.name
    }

    async fn perform(
        &self,
        action: &Action,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let Action::Realman(a) = action else {
            return Err(DeviceError::step_of_another_kind(
                &self.name,
                "a Realman arm",
                action,
            ));
        };
        let late = || format!("{}: not done", a.command.name());
        within(timeout, late, self.act(a)).await
    }

    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)> {
        let obs = self.observe();
        for check in checks {
            let Check::Realman(cond) = check else {
                return Err((
                    check.describe(),
                    format!("`{}` is a Realman arm", self.name),
                ));
            };
            if !cond.holds(&obs) {
                return Err((cond.expected_text(), cond.actual_text(&obs)));
            }
        }
        Ok(())
    }

    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn> {
        trace::columns(signals, self.dof)
    }

    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>> {
        trace::row(signals, self.dof, &self.observe())
    }

    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError> {
        let f = rm_fault(fault, &self.name)?;
        self.with_emu(|h| h.inject(f.0.clone()).map_err(|e| e.to_string()))?;
        lock(&self.active).push(f);
        Ok(())
    }

    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError> {
        let faults = match fault {
            Some(f) => {
                let f = rm_fault(f, &self.name)?;
                lock(&self.active).retain(|a| *a != f);
                vec![f]
            }
            None => std::mem::take(&mut *lock(&self.active)),
        };
        for f in faults {
            self.with_emu(|h| {
                h.clear(f.kind());
                Ok(())
            })?;
        }
        Ok(())
    }

    async fn emulator_health(&self, _last: bool) -> Result<(), String> {
        match lock(&self.emu).as_ref() {
            Some(emu) => crate::devices::realman::realman_health(&emu.snapshot()),
            None => Ok(()),
        }
    }

    async fn shutdown(&self) {
        if let Some(task) = lock(&self.streaming).take() {
            task.abort();
        }
        let emu = lock(&self.emu).take();
        if let Some(emu) = emu {
            emu.shutdown().await;
        }
    }
}

/// The Realman fault inside a device fault.
fn rm_fault(fault: &DeviceFault, name: &str) -> Result<RmFault, DeviceError> {
    match fault {
        DeviceFault::Realman(f) => Ok(f.clone()),
        other => Err(DeviceError::fault_of_another_kind(
            name,
            "a Realman arm",
            other,
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn driver_errors_get_the_scenario_error_classes() {
        assert_eq!(
            classify(&RealmanError::Rejected {
                command: "movej",
                key: "receive_state"
            }),
            ErrorClass::Rejected
        );
        assert_eq!(
            classify(&RealmanError::Timeout {
                command: "get_joint_degree",
                after: Duration::from_millis(500)
            }),
            ErrorClass::Timeout
        );
        assert_eq!(
            classify(&RealmanError::Disconnected { command: "movej" }),
            ErrorClass::Bus
        );
    }
}
