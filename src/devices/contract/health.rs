//! Emulator health for the kinds whose emulator answers through a task of its own (the
//! RobStride and Damiao bus runners): the question asked after one step and judged after the
//! next ([`HealthProbe`]), and whether a bus of emulated motors is still physically finite
//! ([`motors_finite`]). See [`Device::emulator_health`](super::Device::emulator_health).

use std::future::Future;
use std::sync::{Mutex, MutexGuard};

use tokio::task::JoinHandle;

/// The emulator's state, asked for after one step and read after the next: waiting for an
/// emulator that answers through its own task between steps would let it run a tick before
/// the next step's frames and shift every recorded run.
///
/// `S` is the state the emulator answers with, `E` its error (a stopped emulator answers
/// nothing; the steps that need it report that, so an error is no verdict).
pub(crate) struct HealthProbe<S, E> {
    /// The question on its way, if one was asked and not yet judged.
    pending: Mutex<Option<JoinHandle<Result<S, E>>>>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // The slot holds a task handle or nothing: consistent whatever panicked.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl<S: Send + 'static, E: Send + 'static> HealthProbe<S, E> {
    /// No question asked yet.
    pub(crate) fn new() -> Self {
        Self {
            pending: Mutex::new(None),
        }
    }

    /// The verdict on the answer to the previous question, when it has come (waited for when
    /// `last`: the run is over), by `healthy`; then, while the emulator is sound, the next
    /// question: `ask` gives it (`None`: no emulator to ask now), and when `last` it is
    /// waited for and judged at once.
    pub(crate) async fn judge<Q>(
        &self,
        last: bool,
        ask: impl FnOnce() -> Option<Q>,
        healthy: impl Fn(&S) -> Result<(), String>,
    ) -> Result<(), String>
    where
        Q: Future<Output = Result<S, E>> + Send + 'static,
    {
        let previous = lock(&self.pending).take();
        let verdict = match previous {
            Some(probe) if last || probe.is_finished() => match probe.await {
                Ok(Ok(state)) => healthy(&state),
                _ => Ok(()),
            },
            Some(probe) => {
                *lock(&self.pending) = Some(probe);
                Ok(())
            }
            None => Ok(()),
        };
        if verdict.is_ok() {
            if let Some(question) = ask() {
                let probe = tokio::spawn(question);
                if last {
                    return match probe.await {
                        Ok(Ok(state)) => healthy(&state),
                        _ => Ok(()),
                    };
                }
                *lock(&self.pending) = Some(probe);
            }
        }
        verdict
    }
}

/// One emulated motor's physical state, as [`motors_finite`] reads it.
pub(crate) struct MotorPhysics {
    /// The identifier it is named by in the message (its CAN ID, ESC_ID).
    pub id: u32,
    /// Shaft angle (rad).
    pub angle_rad: f64,
    /// Shaft speed (rad/s).
    pub speed_rad_s: f64,
    /// Torque (N·m).
    pub torque_nm: f64,
    /// Temperature (°C).
    pub temperature_c: f64,
}

/// Whether every emulated motor's physical state is finite: `Err` naming the first quantity
/// that is not (`motor 3 speed`), through [`crate::devices::finite_state`].
pub(crate) fn motors_finite(motors: impl IntoIterator<Item = MotorPhysics>) -> Result<(), String> {
    crate::devices::finite_state(motors.into_iter().flat_map(|m| {
        let id = m.id;
        [
            (format!("motor {id} angle"), m.angle_rad),
            (format!("motor {id} speed"), m.speed_rad_s),
            (format!("motor {id} torque"), m.torque_nm),
            (format!("motor {id} temperature"), m.temperature_c),
        ]
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn motor(id: u32, speed_rad_s: f64) -> MotorPhysics {
        MotorPhysics {
            id,
            angle_rad: 0.0,
            speed_rad_s,
            torque_nm: 0.0,
            temperature_c: 25.0,
        }
    }

    #[test]
    fn the_first_quantity_that_is_not_finite_is_named() {
        assert_eq!(motors_finite([motor(1, 0.5), motor(2, 0.0)]), Ok(()));
        let err = motors_finite([motor(1, 0.5), motor(3, f64::NAN)]).unwrap_err();
        assert!(err.contains("motor 3 speed is NaN"), "{err}");
    }

    /// The answer to one question is judged when the next is asked; the last call waits.
    #[tokio::test(start_paused = true)]
    async fn a_question_is_judged_after_the_next_step_and_at_once_when_last() {
        let probe: HealthProbe<f64, ()> = HealthProbe::new();
        let healthy = |v: &f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err("diverged".to_owned())
            }
        };
        let ask = |v: f64| move || Some(async move { Ok::<_, ()>(v) });
        // Asked now, nothing to judge yet.
        assert_eq!(probe.judge(false, ask(f64::NAN), healthy).await, Ok(()));
        // The emulator's task answers while the step runs.
        tokio::time::sleep(std::time::Duration::from_millis(1)).await;
        // The NaN answer is judged now; no new question while the emulator is unsound.
        assert_eq!(
            probe.judge(false, ask(1.0), healthy).await,
            Err("diverged".to_owned())
        );
        assert_eq!(
            probe.judge(true, ask(f64::NAN), healthy).await,
            Err("diverged".to_owned())
        );
        // No emulator to ask: sound.
        let none = || None::<std::future::Ready<Result<f64, ()>>>;
        assert_eq!(probe.judge(true, none, healthy).await, Ok(()));
    }
}
