//! Streamed targets (`movej_canfd`, `movep_canfd`, `movej_follow`, `movep_follow`,
//! docs/protocols/realman.md §4): each frame replaces the target, clamped to the joint limits.
//! High-follow passthrough (`movej_canfd` / `movep_canfd` with `follow: true`) moves the
//! set-point straight at the target, at no more than each joint's speed limit. Low-follow
//! passthrough and the `*_follow` commands go through the online planner firmware v3.7.3
//! introduced: the set-point also respects each joint's acceleration limit and brakes to stop
//! on the target, so a jump in the target becomes a smooth move.

/// A target no new frame refreshes is dropped once reached and this old, ms.
pub(super) const STREAM_IDLE_MS: u32 = 200;

/// How a stream's set-point approaches its target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tracking {
    /// High follow: straight at the target, speed-limited only.
    Direct,
    /// Online planning: speed- and acceleration-limited, braking onto the target.
    Planned,
}

/// A streamed target.
#[derive(Debug, Clone, PartialEq)]
pub struct Stream {
    /// Target joints, rad.
    pub target_rad: Vec<f64>,
    /// `arm_current_status` while streaming.
    pub status: &'static str,
    /// ms since the last frame.
    pub idle_ms: u32,
    /// How the set-point follows.
    pub tracking: Tracking,
    /// Set-point speeds of the planned tracking, rad/s.
    pub speed_rad_s: Vec<f64>,
}

/// Per-joint limits of one tick.
#[derive(Debug, Clone, Copy)]
pub(super) struct JointLimits {
    /// Position range, rad.
    pub min_rad: f64,
    /// See `min_rad`.
    pub max_rad: f64,
    /// Speed limit, rad/s.
    pub speed_rad_s: f64,
    /// Acceleration limit, rad/s².
    pub acc_rad_s2: f64,
}

impl Stream {
    /// A new stream toward `target_rad`, starting at rest (or with the speeds of the stream it
    /// replaces, so a new frame does not jerk the arm).
    pub(super) fn new(
        target_rad: Vec<f64>,
        status: &'static str,
        tracking: Tracking,
        previous: Option<&Stream>,
    ) -> Self {
        let speed_rad_s = previous
            .map(|p| p.speed_rad_s.clone())
            .filter(|s| s.len() == target_rad.len())
            .unwrap_or_else(|| vec![0.0; target_rad.len()]);
        Self {
            target_rad,
            status,
            idle_ms: 0,
            tracking,
            speed_rad_s,
        }
    }

    /// Advance the set-point one tick of `dt_s`; true when every joint is on its target.
    pub(super) fn advance(
        &mut self,
        setpoint_rad: &mut [f64],
        limits: &[JointLimits],
        dt_s: f64,
    ) -> bool {
        self.idle_ms += 1;
        let mut done = true;
        for (j, q) in setpoint_rad.iter_mut().enumerate() {
            let (Some(l), Some(target), Some(v)) = (
                limits.get(j),
                self.target_rad.get(j),
                self.speed_rad_s.get_mut(j),
            ) else {
                continue;
            };
            let target = target.clamp(l.min_rad, l.max_rad);
            match self.tracking {
                Tracking::Direct => {
                    let max_step = l.speed_rad_s * dt_s;
                    *q += (target - *q).clamp(-max_step, max_step);
                }
                Tracking::Planned => planned_step(q, v, target, l, dt_s),
            }
            done &= (target - *q).abs() < 1e-9;
        }
        done
    }
}

/// One tick of a speed- and acceleration-limited approach: the speed that still allows a stop
/// on the target, reached at no more than the acceleration limit.
fn planned_step(q: &mut f64, v: &mut f64, target: f64, l: &JointLimits, dt_s: f64) {
    let error = target - *q;
    let dv = l.acc_rad_s2 * dt_s;
    if error.abs() <= dv * dt_s && v.abs() <= dv {
        // Close enough to land this tick.
        *q = target;
        *v = 0.0;
        return;
    }
    // Braking distance v²/2a must not exceed the distance left (one tick of margin).
    let brake = (2.0 * l.acc_rad_s2 * (error.abs() - v.abs() * dt_s).max(0.0)).sqrt();
    let wanted = error.signum() * brake.min(l.speed_rad_s);
    *v += (wanted - *v).clamp(-dv, dv);
    let step = *v * dt_s;
    // Never step past the target.
    *q = if step.abs() >= error.abs() && step.signum() == error.signum() {
        *v = 0.0;
        target
    } else {
        *q + step
    };
}
