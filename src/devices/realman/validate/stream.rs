//! `stream_joints` / `stream_pose`: interpolated points sent at a fixed period through
//! `movej_canfd` / `movep_canfd` / `movej_follow` / `movep_follow`.

use super::super::model::{RmCommand, Stream, StreamMode, StreamPath, STREAM_MODES};
use super::super::raw::RawRmStep;
use super::step::pose;
use super::{int_in, joints};
use crate::scenario::error::Pos;
use crate::scenario::{pos, Ctx, Res};

/// Shortest period: a 3rd-generation controller on a wired link takes a point every 2 ms
/// (docs/protocols/realman.md §4).
const MIN_PERIOD_MS: i64 = 2;
/// Longest stream a scenario may send, ms.
const MAX_DURATION_MS: i64 = 600_000;

/// A stream step.
pub(super) fn command(ctx: &Ctx<'_>, a: &RawRmStep, name: &str, at: Pos) -> Res<RmCommand> {
    let path = if name == "stream_joints" {
        let from = ctx.required(&a.from_deg, "from_deg", name, at)?;
        let to = ctx.required(&a.to_deg, "to_deg", name, at)?;
        let dof = from.value.len().clamp(6, 7);
        let from_deg = joints(ctx, from, "from_deg", dof)?;
        let to_deg = joints(ctx, to, "to_deg", dof)?;
        StreamPath::Joints { from_deg, to_deg }
    } else {
        StreamPath::Pose {
            from: pose(
                ctx,
                &a.from_position_m,
                &a.from_euler_deg,
                ("from_position_m", "from_euler_deg"),
                name,
                at,
            )?,
            to: pose(
                ctx,
                &a.position_m,
                &a.euler_deg,
                ("position_m", "euler_deg"),
                name,
                at,
            )?,
        }
    };
    let duration = ctx.required(&a.duration_ms, "duration_ms", name, at)?;
    let duration_ms = int_in(ctx, duration, "duration_ms", 1, MAX_DURATION_MS)?;
    let period_ms = match &a.period_ms {
        Some(p) => {
            let period = int_in(ctx, p, "period_ms", MIN_PERIOD_MS, 1000)?;
            if period > duration_ms {
                return Err(ctx.err(
                    pos(p),
                    format!("`period_ms` {period} is longer than `duration_ms` {duration_ms}"),
                ));
            }
            period
        }
        None => 10.min(duration_ms).max(MIN_PERIOD_MS),
    };
    let mode = match &a.mode {
        Some(m) => ctx.choice(m, "mode", &STREAM_MODES)?,
        None => StreamMode::Canfd,
    };
    Ok(RmCommand::Stream(Stream {
        path,
        duration_ms: duration_ms as u32,
        period_ms: period_ms as u32,
        mode,
        block: a.block.as_ref().is_none_or(|b| b.value),
    }))
}
