//! `stream_joints` / `stream_pose`: points interpolated between two ends, sent every period
//! (in the run's clock, virtual or real) through the driver's passthrough or follow commands.
//! The controller does not answer them (docs/protocols/realman.md §4); the push shows the arm.

use std::time::Duration;

use driver::realman::{CartesianTarget, RealmanClient, RealmanError, Smoothing};
use tokio::time::Instant;

use super::pose;
use crate::devices::realman::model::{PoseDeg, Stream, StreamMode, StreamPath};

fn lerp(a: f64, b: f64, f: f64) -> f64 {
    a + (b - a) * f
}

fn lerp3(a: [f64; 3], b: [f64; 3], f: f64) -> [f64; 3] {
    [
        lerp(a[0], b[0], f),
        lerp(a[1], b[1], f),
        lerp(a[2], b[2], f),
    ]
}

/// Send the point at fraction `f` (0 = first, 1 = last) of the path.
async fn send_point(arm: &RealmanClient, s: &Stream, f: f64) -> Result<(), RealmanError> {
    match &s.path {
        StreamPath::Joints { from_deg, to_deg } => {
            let q: Vec<f64> = from_deg
                .iter()
                .zip(to_deg)
                .map(|(a, b)| lerp(*a, *b, f).to_radians())
                .collect();
            match s.mode {
                StreamMode::Canfd => arm.movej_canfd(&q, false, Smoothing::Raw).await,
                StreamMode::CanfdFollow => arm.movej_canfd(&q, true, Smoothing::Raw).await,
                StreamMode::Follow => arm.movej_follow(&q).await,
            }
        }
        StreamPath::Pose { from, to } => {
            let p = PoseDeg {
                position_m: lerp3(from.position_m, to.position_m, f),
                euler_deg: lerp3(from.euler_deg, to.euler_deg, f),
            };
            let target = CartesianTarget::Euler(pose(&p));
            match s.mode {
                StreamMode::Canfd => arm.movep_canfd(&target, false, Smoothing::Raw).await,
                StreamMode::CanfdFollow => arm.movep_canfd(&target, true, Smoothing::Raw).await,
                StreamMode::Follow => arm.movep_follow(&target).await,
            }
        }
    }
}

/// Send the whole stream: a point at t = 0, every `period_ms`, and the last one at
/// `duration_ms`.
pub(super) async fn run(arm: &RealmanClient, s: &Stream) -> Result<(), RealmanError> {
    let start = Instant::now();
    let mut t_ms = 0;
    loop {
        tokio::time::sleep_until(start + Duration::from_millis(u64::from(t_ms))).await;
        send_point(arm, s, f64::from(t_ms) / f64::from(s.duration_ms)).await?;
        if t_ms >= s.duration_ms {
            return Ok(());
        }
        t_ms = (t_ms + s.period_ms).min(s.duration_ms);
    }
}
