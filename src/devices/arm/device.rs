//! A vendor-neutral arm on the bench: the [`Device`] that drives an
//! [`ArmInterface`](driver::arm::ArmInterface) (Piper or Realman backend) against that vendor's
//! in-process emulator, and judges conditions on the arm's realtime state.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use async_trait::async_trait;
use bus::virtual_bus::{Fault, FaultHandle, FaultId, FrameFilter};
use driver::arm::{
    AbcErrorCode, ArmError, ArmInterface, ArmRealtimeState, MoveOptions, Pose, RealtimeSubscription,
};
use sim::piper::PiperFault;
use sim::realman::{RealmanFault, RealmanFaultKind, RealmanHandle};

use super::model::{ArmAction, ArmCall, ArmCond, ArmFaultKind, MoveArgs, PoseDeg};
use crate::devices::piper::device::EmulatorControl;
use crate::devices::{Action, Check, Device, DeviceError, DeviceFault, Reply, TraceColumn};
use crate::scenario::{ErrorClass, Signal};

/// The vendor's emulator behind the arm.
pub(crate) enum Emulator {
    /// A Piper on the virtual bus, with the bus's fault hooks (a cut link drops every frame).
    Piper {
        /// The emulator.
        sim: Box<dyn EmulatorControl>,
        /// Fault hooks of the bus.
        bus: FaultHandle,
        /// The drop-everything fault while the link is cut.
        cut: Mutex<Option<FaultId>>,
    },
    /// A Realman controller on in-memory streams (`None` once shut down).
    Realman(Mutex<Option<RealmanHandle>>),
}

/// One arm: the Arm API object, its emulator and the latest realtime state.
pub(crate) struct ArmDevice {
    name: String,
    arm: Arc<dyn ArmInterface>,
    emulator: Emulator,
    latest: Arc<Mutex<Option<Arc<ArmRealtimeState>>>>,
    listener: tokio::task::JoinHandle<()>,
}

/// How late a Realman's replies come while its link is cut: past the driver's 500 ms timeout,
/// so every call times out, and short enough that the stream is clean again soon after.
const REALMAN_CUT_DELAY_MS: u64 = 1000;

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The harness's error class of an Arm API code (for reports; `expect_code` compares codes).
fn class(code: AbcErrorCode) -> ErrorClass {
    match code {
        AbcErrorCode::Timeout | AbcErrorCode::ArmTimeout => ErrorClass::Timeout,
        AbcErrorCode::InvalidArgument
        | AbcErrorCode::ParamError
        | AbcErrorCode::ParamOutOfRange
        | AbcErrorCode::NotImplemented => ErrorClass::InvalidArgument,
        AbcErrorCode::ArmDataSendFailed | AbcErrorCode::ArmDataReceiveFailed => ErrorClass::Bus,
        _ => ErrorClass::Rejected,
    }
}

fn pose(p: &PoseDeg) -> Pose {
    Pose::new(p.position_m, p.euler_deg.map(f64::to_radians))
}

fn options(m: &MoveArgs) -> MoveOptions {
    MoveOptions {
        speed_percent: m.v,
        blend_radius: m.r,
        trajectory_connect: m.trajectory_connect,
        block: m.block,
    }
}

impl ArmDevice {
    /// Wrap `arm` and follow its realtime state from now on.
    pub(crate) fn new(name: &str, arm: Arc<dyn ArmInterface>, emulator: Emulator) -> Self {
        let latest = Arc::new(Mutex::new(None));
        let mut states: RealtimeSubscription = arm.subscribe_realtime();
        let into = Arc::clone(&latest);
        let listener = tokio::spawn(async move {
            while let Ok(state) = states.recv().await {
                *lock(&into) = Some(state);
            }
        });
        Self {
            name: name.to_owned(),
            arm,
            emulator,
            latest,
            listener,
        }
    }

    /// The call itself; values for the reply on success.
    async fn call(&self, call: &ArmCall) -> Result<Vec<(String, String)>, ArmError> {
        let arm = &self.arm;
        match call {
            ArmCall::Connect => arm.connect().await?,
            ArmCall::Disconnect => {
                arm.disconnect().await;
                *lock(&self.latest) = None;
            }
            ArmCall::MoveJointPosition(j, m) => arm.move_joint_position(j, options(m)).await?,
            ArmCall::MoveCartesianLinear(p, m) => {
                arm.move_cartesian_linear(&pose(p), options(m)).await?
            }
            ArmCall::MoveJointPose(p, m) => arm.move_joint_pose(&pose(p), options(m)).await?,
            ArmCall::MoveJointFollow(j) => arm.move_joint_follow(j).await?,
            ArmCall::Stop => arm.set_arm_stop().await?,
            ArmCall::SlowStop => arm.set_arm_slow_stop().await?,
            ArmCall::Pause => arm.set_arm_pause().await?,
            ArmCall::Continue => arm.set_arm_continue().await?,
            ArmCall::GripperPosition { position, block } => {
                arm.set_gripper_position(*position, *block, 10).await?
            }
            ArmCall::GripperRelease { speed, block } => {
                arm.set_gripper_release(*speed, *block, 10).await?
            }
            ArmCall::GripperPick {
                speed,
                force,
                block,
            } => arm.set_gripper_pick(*speed, *force, *block, 10).await?,
            ArmCall::GetJointDegree => {
                let joints = arm.get_joint_degree().await?;
                return Ok(joints
                    .iter()
                    .enumerate()
                    .map(|(i, d)| (format!("j{}_deg", i + 1), format!("{d:.1}")))
                    .collect());
            }
            ArmCall::GetGripperState => {
                let g = arm.get_gripper_state().await?;
                return Ok(vec![("gripper".to_owned(), format!("{g:?}"))]);
            }
        }
        Ok(Vec::new())
    }

    fn state(&self) -> Option<Arc<ArmRealtimeState>> {
        lock(&self.latest).clone()
    }

    fn check(&self, cond: &ArmCond) -> Result<(), (String, String)> {
        let state = self.state();
        let fail = |actual: String| Err((cond.expected_text(), actual));
        match (cond, &state) {
            (ArmCond::Connected(want), s) => {
                if s.is_some() == *want {
                    Ok(())
                } else {
                    fail(format!("connected {}", s.is_some()))
                }
            }
            (_, None) => fail("no realtime state (not connected)".to_owned()),
            (ArmCond::Joints(want, tol), Some(s)) => {
                let have = &s.joint_status.joint_position;
                let ok = have.len() == want.len()
                    && have.iter().zip(want).all(|(h, w)| (h - w).abs() <= *tol);
                if ok {
                    Ok(())
                } else {
                    fail(format!("joints_deg {:?}", round(have, 0.01)))
                }
            }
            (ArmCond::GripperActpos(want, tol), Some(s)) => match &s.gripper_state {
                Some(g) if (g.actpos - want).abs() <= *tol => Ok(()),
                Some(g) => fail(format!("gripper_actpos {}", g.actpos)),
                None => fail("no gripper state".to_owned()),
            },
            (ArmCond::Position(want, tol), Some(s)) => {
                let have = s.ee_pose.position_m;
                let ok = have.iter().zip(want).all(|(h, w)| (h - w).abs() <= *tol);
                if ok {
                    Ok(())
                } else {
                    fail(format!("position_m {:?}", round(&have, 0.0001)))
                }
            }
        }
    }
}

fn round(values: &[f64], quantum: f64) -> Vec<f64> {
    values
        .iter()
        .map(|v| (v / quantum).round() * quantum)
        .collect()
}

fn arm_action<'a>(action: &'a Action, name: &str) -> Result<&'a ArmAction, DeviceError> {
    match action {
        Action::Arm(a) => Ok(a),
        other => Err(DeviceError::unsupported(format!(
            "`{name}` is an arm; a {} action does not apply",
            other.kind_name()
        ))),
    }
}

#[async_trait]
impl Device for ArmDevice {
    fn name(&self) -> &str {
        &self.name
    }

    async fn perform(
        &self,
        action: &Action,
        timeout: Option<Duration>,
    ) -> Result<Reply, DeviceError> {
        let action = arm_action(action, &self.name)?;
        let result = match timeout {
            Some(t) => match tokio::time::timeout(t, self.call(&action.call)).await {
                Ok(r) => r,
                Err(_) => Err(ArmError::new(
                    AbcErrorCode::ArmTimeout,
                    format!("no result within {} ms", t.as_millis()),
                )),
            },
            None => self.call(&action.call).await,
        };
        match (result, action.expect_code) {
            (Ok(values), None) => Ok(Reply {
                values,
                mismatches: Vec::new(),
            }),
            (Ok(values), Some(want)) => Ok(Reply {
                values,
                mismatches: vec![(
                    "code".to_owned(),
                    want.to_string(),
                    "SUCCESS (0)".to_owned(),
                )],
            }),
            (Err(e), Some(want)) => Ok(Reply {
                values: vec![("code".to_owned(), e.code.to_string())],
                mismatches: if e.code == want {
                    Vec::new()
                } else {
                    vec![("code".to_owned(), want.to_string(), e.to_string())]
                },
            }),
            (Err(e), None) => Err(DeviceError::new(class(e.code), e.to_string())),
        }
    }

    fn evaluate(&self, checks: &[Check]) -> Result<(), (String, String)> {
        for check in checks {
            match check {
                Check::Arm(c) => self.check(c)?,
                other => {
                    return Err((
                        other.describe(),
                        format!("`{}` is an arm; this condition does not apply", self.name),
                    ))
                }
            }
        }
        Ok(())
    }

    fn trace_columns(&self, signals: &[Signal]) -> Vec<TraceColumn> {
        let mut columns = Vec::new();
        if signals.contains(&Signal::Joints) {
            columns.extend((1..=6).map(|j| TraceColumn {
                name: format!("j{j}_deg"),
                quantum: 0.1,
                group: "joints",
            }));
        }
        if signals.contains(&Signal::Pose) {
            columns.extend(["x_m", "y_m", "z_m"].map(|axis| TraceColumn {
                name: axis.to_owned(),
                quantum: 0.0001,
                group: "pose",
            }));
        }
        columns
    }

    fn trace_row(&self, signals: &[Signal]) -> Vec<Option<f64>> {
        let state = self.state();
        let mut row = Vec::new();
        if signals.contains(&Signal::Joints) {
            let joints = state.as_ref().map(|s| &s.joint_status.joint_position);
            row.extend((0..6).map(|j| joints.and_then(|q| q.get(j).copied())));
        }
        if signals.contains(&Signal::Pose) {
            let p = state.as_ref().map(|s| s.ee_pose.position_m);
            row.extend((0..3).map(|i| p.map(|p| p[i])));
        }
        row
    }

    async fn inject(&self, fault: &DeviceFault) -> Result<(), DeviceError> {
        self.apply(fault, true)
    }

    async fn clear(&self, fault: Option<&DeviceFault>) -> Result<(), DeviceError> {
        match fault {
            Some(f) => self.apply(f, false),
            None => {
                for kind in ArmFaultKind::ALL {
                    self.apply(&DeviceFault::Arm(super::model::ArmFault(kind)), false)?;
                }
                Ok(())
            }
        }
    }

    async fn emulator_health(&self, _last: bool) -> Result<(), String> {
        match &self.emulator {
            Emulator::Piper { sim, .. } => sim.health(),
            Emulator::Realman(handle) => match lock(handle).as_ref() {
                Some(h) => crate::devices::realman::realman_health(&h.snapshot()),
                None => Ok(()),
            },
        }
    }

    async fn shutdown(&self) {
        self.arm.disconnect().await;
        self.listener.abort();
        match &self.emulator {
            Emulator::Piper { sim, .. } => sim.shutdown().await,
            Emulator::Realman(handle) => {
                let handle = lock(handle).take();
                if let Some(h) = handle {
                    h.shutdown().await;
                }
            }
        }
    }
}

impl ArmDevice {
    /// Inject (`on`) or clear a fault on the vendor's emulator.
    fn apply(&self, fault: &DeviceFault, on: bool) -> Result<(), DeviceError> {
        let DeviceFault::Arm(fault) = fault else {
            return Err(DeviceError::unsupported(format!(
                "`{}` is an arm; a {} fault does not apply",
                self.name,
                fault.kind_name()
            )));
        };
        let emulator = |e: String| DeviceError::unsupported(format!("emulator: {e}"));
        match (&self.emulator, fault.0) {
            (Emulator::Piper { sim, .. }, ArmFaultKind::Estop) => {
                if on {
                    sim.inject(&PiperFault::Estop).map_err(emulator)
                } else {
                    sim.clear(Some(&PiperFault::Estop)).map_err(emulator)
                }
            }
            (Emulator::Piper { bus, cut, .. }, ArmFaultKind::CommLoss) => {
                let mut cut = lock(cut);
                if let Some(id) = cut.take() {
                    bus.remove(id);
                }
                if on {
                    *cut = Some(bus.inject(Fault::drop(FrameFilter::All)));
                }
                Ok(())
            }
            (Emulator::Realman(handle), ArmFaultKind::CommLoss) => match lock(handle).as_ref() {
                Some(h) if on => {
                    for f in [
                        RealmanFault::ReplyDelay {
                            delay_ms: REALMAN_CUT_DELAY_MS,
                        },
                        RealmanFault::UdpLoss { permille: 1000 },
                    ] {
                        h.inject(f).map_err(|e| emulator(e.to_string()))?;
                    }
                    Ok(())
                }
                Some(h) => {
                    h.clear(RealmanFaultKind::ReplyDelay);
                    h.clear(RealmanFaultKind::UdpLoss);
                    Ok(())
                }
                None => Err(DeviceError::unsupported("the emulator has been shut down")),
            },
            (Emulator::Realman(handle), ArmFaultKind::Estop) => match lock(handle).as_ref() {
                Some(h) if on => h
                    .inject(RealmanFault::EStop)
                    .map_err(|e| emulator(e.to_string())),
                Some(h) => {
                    h.clear(RealmanFaultKind::EStop);
                    Ok(())
                }
                None => Err(DeviceError::unsupported("the emulator has been shut down")),
            },
        }
    }
}
