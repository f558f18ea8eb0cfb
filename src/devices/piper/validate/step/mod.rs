//! Layer 2 of a Piper step, split by action family: [`motion`], [`queries`] and [`config`].

use super::super::model::PiperAction;
use super::super::raw::RawStep;
use crate::scenario::{Ctx, DeviceStep, Pos, Res, S};

/// A step's label (its key in the file) and action.
type Labeled = (&'static str, DeviceStep<PiperAction>);

/// Build an action step from its common arguments.
struct Common<'r> {
    device: &'r Option<S<String>>,
    timeout_ms: &'r Option<S<i64>>,
    expect_error: &'r Option<S<String>>,
}

macro_rules! common {
    ($args:expr) => {
        Common {
            device: &$args.device,
            timeout_ms: &$args.timeout_ms,
            expect_error: &$args.expect_error,
        }
    };
}

fn action(
    ctx: &Ctx<'_>,
    common: Common<'_>,
    at: Pos,
    action: PiperAction,
) -> Res<DeviceStep<PiperAction>> {
    let device = ctx.device_of_kind(common.device, at, "piper", "this step")?;
    let timeout = ctx.timeout(common.timeout_ms)?;
    let expect_error = ctx.expect_error(common.expect_error)?;
    Ok(DeviceStep {
        device,
        action,
        timeout,
        expect_error,
    })
}

// After `common!`: macros are visible to the modules declared below them.
mod config;
mod motion;
mod queries;

/// A Piper step: its label and action.
pub(crate) fn step(ctx: &Ctx<'_>, raw: &RawStep, at: Pos) -> Res<Labeled> {
    match raw {
        RawStep::Enable(_)
        | RawStep::Disable(_)
        | RawStep::Mode(_)
        | RawStep::MoveJ(_)
        | RawStep::MoveP(_)
        | RawStep::MoveL(_)
        | RawStep::MoveC(_)
        | RawStep::Mit(_)
        | RawStep::Gripper(_)
        | RawStep::GripperZero(_)
        | RawStep::Estop(_)
        | RawStep::Reset(_) => motion::step(ctx, raw, at),
        RawStep::QueryFirmware(_)
        | RawStep::QueryJointLimits(_)
        | RawStep::QueryJointAcc(_)
        | RawStep::QueryEndLimits(_)
        | RawStep::QueryCollision(_)
        | RawStep::QueryGripperParams(_) => queries::step(ctx, raw, at),
        RawStep::SetJointLimits(_)
        | RawStep::SetJointAcc(_)
        | RawStep::SetEndLimits(_)
        | RawStep::SetCollision(_)
        | RawStep::SetGripperParams(_)
        | RawStep::SetZero(_)
        | RawStep::ClearJointError(_)
        | RawStep::ResetParams(_)
        | RawStep::SetPayload(_)
        | RawStep::SetRole(_) => config::step(ctx, raw, at),
    }
}
