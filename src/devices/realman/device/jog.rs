//! Step and teach jogs through the driver (degrees and metres in, SI to the driver).

use driver::realman::{Axis, Direction, RealmanClient, RealmanError};

use crate::devices::realman::model::{JogAxis, JogTarget, RmCommand};

fn axis(a: JogAxis) -> Axis {
    match a {
        JogAxis::X => Axis::X,
        JogAxis::Y => Axis::Y,
        JogAxis::Z => Axis::Z,
    }
}

fn direction(positive: bool) -> Direction {
    if positive {
        Direction::Positive
    } else {
        Direction::Negative
    }
}

/// Perform a jog command (`Step`, `Teach`, `StopTeach`; anything else is a no-op).
pub(super) async fn perform(arm: &RealmanClient, cmd: &RmCommand) -> Result<(), RealmanError> {
    match *cmd {
        RmCommand::Step {
            target,
            amount,
            speed,
            block,
        } => match target {
            JogTarget::Joint(j) => arm.joint_step(j, amount.to_radians(), speed, block).await,
            JogTarget::Position(a) => arm.pos_step(axis(a), amount, speed, block).await,
            JogTarget::Orientation(a) => {
                arm.ort_step(axis(a), amount.to_radians(), speed, block)
                    .await
            }
        },
        RmCommand::Teach {
            target,
            positive,
            speed,
        } => {
            let dir = direction(positive);
            match target {
                JogTarget::Joint(j) => arm.joint_teach(j, dir, speed).await,
                JogTarget::Position(a) => arm.pos_teach(axis(a), dir, speed).await,
                JogTarget::Orientation(a) => arm.ort_teach(axis(a), dir, speed).await,
            }
        }
        RmCommand::StopTeach => arm.stop_teach().await,
        _ => Ok(()),
    }
}
