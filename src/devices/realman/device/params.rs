//! Motion parameters through the driver: the scenario's units (named in the parameter names)
//! converted to the driver's SI, per-joint values picked out of the driver's tables, DH rows
//! written back whole.

use driver::realman::{RealmanClient, RealmanError};

use crate::devices::realman::model::{Param, RmCommand};
use crate::devices::{DeviceError, Reply};

use super::derr;

/// A value shown in a reply: rounded to 1e-6 so float noise does not reach the snapshot.
fn shown(v: f64) -> String {
    let r = (v * 1e6).round() / 1e6;
    format!("{}", if r == 0.0 { 0.0 } else { r })
}

fn joint_value(values: &[f64], joint: Option<u8>) -> Result<f64, DeviceError> {
    let j = usize::from(joint.unwrap_or(1));
    values.get(j.wrapping_sub(1)).copied().ok_or_else(|| {
        DeviceError::unsupported(format!(
            "joint {j}: the controller reports {} joints",
            values.len()
        ))
    })
}

/// A whole-number parameter as the driver's `u8`; the driver's own range check follows.
fn small_int(param: Param, value: f64) -> Result<u8, DeviceError> {
    u8::try_from(value as i64).map_err(|_| {
        DeviceError::new(
            crate::scenario::ErrorClass::InvalidArgument,
            format!("{}: {value} does not fit the command", param.name()),
        )
    })
}

async fn read(arm: &RealmanClient, param: Param, joint: Option<u8>) -> Result<f64, DeviceError> {
    let deg = |v: Vec<f64>| v.into_iter().map(f64::to_degrees).collect::<Vec<_>>();
    Ok(match param {
        Param::MaxLineSpeed => arm.max_line_speed().await.map_err(derr)?,
        Param::MaxLineAcc => arm.max_line_acc().await.map_err(derr)?,
        Param::MaxAngularSpeed => arm.max_angular_speed().await.map_err(derr)?,
        Param::MaxAngularAcc => arm.max_angular_acc().await.map_err(derr)?,
        Param::CollisionStage => f64::from(arm.collision_stage().await.map_err(derr)?),
        Param::SelfCollision => f64::from(u8::from(arm.self_collision().await.map_err(derr)?)),
        Param::JointMaxSpeed => {
            joint_value(&deg(arm.joint_max_speed().await.map_err(derr)?), joint)?
        }
        Param::JointMaxAcc => joint_value(&deg(arm.joint_max_acc().await.map_err(derr)?), joint)?,
        Param::JointMinPos => joint_value(&deg(arm.joint_min_pos().await.map_err(derr)?), joint)?,
        Param::JointMaxPos => joint_value(&deg(arm.joint_max_pos().await.map_err(derr)?), joint)?,
        Param::DhAlpha | Param::DhA | Param::DhD | Param::DhOffset => {
            let rows = arm.dh_table().await.map_err(derr)?;
            let j = usize::from(joint.unwrap_or(1));
            let row = rows.get(j.wrapping_sub(1)).ok_or_else(|| {
                DeviceError::unsupported(format!("DH row {j}: the table has {} rows", rows.len()))
            })?;
            match param {
                Param::DhAlpha => row.alpha_rad.to_degrees(),
                Param::DhA => row.a_m,
                Param::DhD => row.d_m,
                _ => row.offset_rad.to_degrees(),
            }
        }
    })
}

async fn write(
    arm: &RealmanClient,
    param: Param,
    joint: Option<u8>,
    value: f64,
) -> Result<(), DeviceError> {
    let j = joint.unwrap_or(1);
    let r: Result<(), RealmanError> = match param {
        Param::MaxLineSpeed => arm.set_max_line_speed(value).await,
        Param::MaxLineAcc => arm.set_max_line_acc(value).await,
        Param::MaxAngularSpeed => arm.set_max_angular_speed(value).await,
        Param::MaxAngularAcc => arm.set_max_angular_acc(value).await,
        Param::CollisionStage => arm.set_collision_stage(small_int(param, value)?).await,
        Param::SelfCollision => arm.set_self_collision(value != 0.0).await,
        Param::JointMaxSpeed => arm.set_joint_max_speed(j, value.to_radians()).await,
        Param::JointMaxAcc => arm.set_joint_max_acc(j, value.to_radians()).await,
        Param::JointMinPos => arm.set_joint_min_pos(j, value.to_radians()).await,
        Param::JointMaxPos => arm.set_joint_max_pos(j, value.to_radians()).await,
        Param::DhAlpha | Param::DhA | Param::DhD | Param::DhOffset => {
            // The controller takes the whole table: read it, change one value, write it back.
            let mut rows = arm.dh_table().await.map_err(derr)?;
            let count = rows.len();
            let row = rows
                .get_mut(usize::from(j).wrapping_sub(1))
                .ok_or_else(|| {
                    DeviceError::unsupported(format!("DH row {j}: the table has {count} rows"))
                })?;
            match param {
                Param::DhAlpha => row.alpha_rad = value.to_radians(),
                Param::DhA => row.a_m = value,
                Param::DhD => row.d_m = value,
                _ => row.offset_rad = value.to_radians(),
            }
            arm.set_dh_table(&rows).await
        }
    };
    r.map_err(derr)
}

/// Perform a parameter command, filling `reply` for `get_param`.
pub(super) async fn perform(
    arm: &RealmanClient,
    cmd: &RmCommand,
    reply: &mut Reply,
) -> Result<(), DeviceError> {
    match cmd {
        RmCommand::SetParam {
            param,
            joint,
            value,
        } => write(arm, *param, *joint, *value).await?,
        RmCommand::GetParam {
            param,
            joint,
            expect,
        } => {
            let v = read(arm, *param, *joint).await?;
            let text = shown(v);
            reply.values.push((param.name().to_owned(), text.clone()));
            if let Some(e) = expect {
                if (v - e.value).abs() > e.tolerance {
                    reply.mismatches.push((
                        param.name().to_owned(),
                        format!("{} ± {}", e.value, e.tolerance),
                        text,
                    ));
                }
            }
        }
        RmCommand::ResetParams => arm.reset_motion_params().await.map_err(derr)?,
        RmCommand::ResetDh => arm.reset_dh_table().await.map_err(derr)?,
        RmCommand::SetZeroOffset(deg) => {
            let rad: Vec<f64> = deg.iter().map(|d| d.to_radians()).collect();
            arm.set_joint_zero_offset(&rad).await.map_err(derr)?;
        }
        RmCommand::JointEnable { joint, on } => {
            arm.set_joint_enabled(*joint, *on).await.map_err(derr)?;
        }
        _ => {}
    }
    Ok(())
}
