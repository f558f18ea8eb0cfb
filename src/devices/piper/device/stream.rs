//! `every_ms`: motion commands re-sent in the background, as SDK clients do (their demos send
//! mode control + target every 5 ms in a loop).
//!
//! The arm and the gripper each have one stream. The next step that commands the same part
//! replaces it (a stop, reset, enable, disable or mode step ends both), and the device's
//! shutdown ends all. Re-sends run on `tokio::time`, so under a paused clock they are as
//! deterministic as the rest of a scenario.

use std::sync::Mutex;
use std::time::Duration;

use driver::piper::{CirclePoint, GripperCommand, MoveKind, Piper, PiperError};
use tokio::task::JoinHandle;
use tokio::time::{interval_at, Instant, MissedTickBehavior};

use super::actions::pose;
use crate::devices::piper::model::PiperAction;

/// A background task that ends when dropped.
#[derive(Debug)]
struct Task(JoinHandle<()>);

impl Drop for Task {
    fn drop(&mut self) {
        self.0.abort();
    }
}

/// Which streams an action ends before it is performed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Part {
    /// Arm motion (MOVE J/P/L/C, MIT).
    Arm,
    /// The gripper.
    Gripper,
    /// Both (stop, reset, enable, disable, mode).
    Both,
}

/// The running re-send tasks of one device.
#[derive(Debug, Default)]
pub(crate) struct Streams {
    arm: Mutex<Option<Task>>,
    gripper: Mutex<Option<Task>>,
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl Streams {
    /// End the streams `part` covers.
    pub(super) fn stop(&self, part: Part) {
        if matches!(part, Part::Arm | Part::Both) {
            lock(&self.arm).take();
        }
        if matches!(part, Part::Gripper | Part::Both) {
            lock(&self.gripper).take();
        }
    }

    /// End every stream.
    pub(crate) fn stop_all(&self) {
        self.stop(Part::Both);
    }

    /// Re-send `action` every `period` from one period from now, replacing the part's stream.
    pub(super) fn start(&self, driver: &Piper, action: &PiperAction, period: Duration) {
        let part = match action {
            PiperAction::Gripper { .. } => &self.gripper,
            _ => &self.arm,
        };
        let driver = driver.clone();
        let action = action.clone();
        let task = tokio::spawn(async move {
            let mut clock = interval_at(Instant::now() + period, period);
            clock.set_missed_tick_behavior(MissedTickBehavior::Delay);
            loop {
                clock.tick().await;
                match send_command(&driver, &action).await {
                    Some(Ok(())) => {}
                    Some(Err(PiperError::Disconnected)) | None => break,
                    Some(Err(e)) => tracing::debug!(error = %e, "every_ms re-send failed"),
                }
            }
        });
        *lock(part) = Some(Task(task));
    }
}

/// The part whose streams `action` ends, if it commands motion at all.
pub(super) fn part_of(action: &PiperAction) -> Option<Part> {
    match action {
        PiperAction::MoveJ { .. }
        | PiperAction::MoveP { .. }
        | PiperAction::MoveL { .. }
        | PiperAction::MoveC { .. }
        | PiperAction::Mit { .. } => Some(Part::Arm),
        PiperAction::Gripper { .. } | PiperAction::GripperZero => Some(Part::Gripper),
        PiperAction::Enable { .. }
        | PiperAction::Disable { .. }
        | PiperAction::Mode { .. }
        | PiperAction::Estop
        | PiperAction::Reset => Some(Part::Both),
        _ => None,
    }
}

/// The `every_ms` of a streamable action.
pub(super) fn period_of(action: &PiperAction) -> Option<Duration> {
    let ms = match action {
        PiperAction::MoveJ { every_ms, .. }
        | PiperAction::MoveP { every_ms, .. }
        | PiperAction::MoveL { every_ms, .. }
        | PiperAction::MoveC { every_ms, .. }
        | PiperAction::Gripper { every_ms, .. } => *every_ms,
        _ => None,
    }?;
    Some(Duration::from_millis(u64::from(ms)))
}

/// Whether `action` is a command an `every_ms` stream can re-send.
fn streamable(action: &PiperAction) -> bool {
    matches!(
        action,
        PiperAction::MoveJ { .. }
            | PiperAction::MoveP { .. }
            | PiperAction::MoveL { .. }
            | PiperAction::MoveC { .. }
            | PiperAction::Gripper { .. }
    )
}

/// Send a MOVE J/P/L/C or gripper command once, as the step does: mode control and target
/// (MOVE C: the three points, then the mode). `None` for any other action.
pub(super) async fn send_command(
    d: &Piper,
    action: &PiperAction,
) -> Option<Result<(), PiperError>> {
    if streamable(action) {
        Some(send(d, action).await)
    } else {
        None
    }
}

async fn send(d: &Piper, action: &PiperAction) -> Result<(), PiperError> {
    match action {
        PiperAction::MoveJ {
            joints_deg,
            speed_pct,
            ..
        } => {
            d.move_joints_rad(joints_deg.map(f64::to_radians), *speed_pct)
                .await
        }
        PiperAction::MoveP {
            pose: p, speed_pct, ..
        } => {
            d.set_move_mode(MoveKind::P, *speed_pct).await?;
            d.end_pose(pose(p)).await
        }
        PiperAction::MoveL {
            pose: p, speed_pct, ..
        } => {
            d.set_move_mode(MoveKind::L, *speed_pct).await?;
            d.end_pose(pose(p)).await
        }
        PiperAction::MoveC {
            start,
            middle,
            end,
            speed_pct,
            ..
        } => {
            for (p, point) in [
                (start, CirclePoint::Start),
                (middle, CirclePoint::Middle),
                (end, CirclePoint::End),
            ] {
                d.end_pose(pose(p)).await?;
                d.move_c_point(point).await?;
            }
            d.set_move_mode(MoveKind::C, *speed_pct).await
        }
        PiperAction::Gripper {
            stroke_mm,
            torque_nm,
            enable,
            clear_error,
            ..
        } => {
            d.gripper(GripperCommand {
                stroke_m: stroke_mm / 1000.0,
                effort_nm: *torque_nm,
                enable: *enable,
                clear_error: *clear_error,
            })
            .await
        }
        // Filtered out by `streamable`.
        _ => Ok(()),
    }
}
