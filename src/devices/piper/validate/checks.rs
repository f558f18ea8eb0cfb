//! Layer 2 of a Piper step's conditions.

use super::PiperCtx;
use crate::devices::piper::model::*;
use crate::devices::piper::raw::*;
use crate::devices::piper::validate::*;
use crate::scenario::{pos, Ctx, Pos, Res, S};

/// A Piper's conditions.
pub(crate) fn checks(ctx: &Ctx<'_>, c: &RawConds, step: &str, at: Pos) -> Res<Vec<Check>> {
    let mut out = Vec::new();
    let tolerance_deg = match &c.tolerance_deg {
        Some(t) => ctx.non_negative(t, "tolerance_deg")?,
        None => DEFAULT_TOLERANCE_DEG,
    };
    let tolerance_mm = match &c.tolerance_mm {
        Some(t) => ctx.non_negative(t, "tolerance_mm")?,
        None => DEFAULT_TOLERANCE_MM,
    };
    if let Some(j) = &c.joints_deg {
        out.push(Check::JointsNear {
            targets_deg: ctx.optional_list(j, "joints_deg")?,
            tolerance_deg,
        });
    }
    if let Some(j) = &c.joints_min_deg {
        out.push(Check::JointsMin {
            bounds_deg: ctx.optional_list(j, "joints_min_deg")?,
        });
    }
    if let Some(j) = &c.joints_max_deg {
        out.push(Check::JointsMax {
            bounds_deg: ctx.optional_list(j, "joints_max_deg")?,
        });
    }
    if let Some(s) = &c.max_speed_deg_s {
        out.push(Check::MaxSpeed {
            deg_s: ctx.non_negative(s, "max_speed_deg_s")?,
        });
    }
    if let Some(s) = &c.max_current_a {
        out.push(Check::MaxCurrent {
            amps: ctx.non_negative(s, "max_current_a")?,
        });
    }
    if let Some(p) = &c.position_mm {
        out.push(Check::PositionNear {
            mm: ctx.array::<3>(p, "position_mm")?,
            tolerance_mm,
        });
    }
    if let Some(o) = &c.orientation_deg {
        out.push(Check::OrientationNear {
            deg: ctx.array::<3>(o, "orientation_deg")?,
            tolerance_deg,
        });
    }
    if let Some(g) = &c.gripper_mm {
        out.push(Check::GripperNear {
            mm: ctx.non_negative(g, "gripper_mm")?,
            tolerance_mm,
        });
    }
    if let Some(s) = &c.arm_status {
        let name = vocab::resolve_arm_status(&s.value).ok_or_else(|| {
            let names = vocab::arm_status_names();
            ctx.err(
                pos(s),
                format!(
                    "`arm_status`: unknown value `{}`; expected a code 0x00..=0x0F or one of: {}",
                    s.value,
                    names.join(", ")
                ),
            )
        })?;
        out.push(Check::Status {
            field: "arm_status",
            value: name.to_owned(),
        });
    }
    if let Some(s) = &c.ctrl_mode {
        let name = vocab::resolve_ctrl_mode(&s.value).ok_or_else(|| {
            let names = vocab::ctrl_mode_names();
            ctx.err(
                pos(s),
                format!(
                    "`ctrl_mode`: unknown value `{}`; expected one of: {}",
                    s.value,
                    names.join(", ")
                ),
            )
        })?;
        out.push(Check::Status {
            field: "ctrl_mode",
            value: name.to_owned(),
        });
    }
    for (key, field, table) in [
        (&c.move_mode, "move_mode", vocab::move_mode_names()),
        (&c.motion, "motion", vocab::motion_names()),
        (&c.feedback, "feedback", vocab::FEEDBACK.to_vec()),
    ] {
        if let Some(s) = key {
            if !table.contains(&s.value.as_str()) {
                return Err(ctx.err(
                    pos(s),
                    format!(
                        "`{field}`: unknown value `{}`; expected one of: {}",
                        s.value,
                        table.join(", ")
                    ),
                ));
            }
            out.push(Check::Status {
                field,
                value: s.value.clone(),
            });
        }
    }
    if let Some(l) = c.leader_frames {
        out.push(Check::Status {
            field: "leader_frames",
            value: l.to_string(),
        });
    }
    if let Some(e) = c.enabled {
        out.push(Check::Enabled(e));
    }
    if let Some(j) = &c.enabled_joints {
        out.push(Check::EnabledJoints(ctx.joints_list(j, "enabled_joints")?));
    }
    if let Some(e) = c.gripper_enabled {
        out.push(Check::GripperEnabled(e));
    }
    if let Some(j) = &c.comm_error_joints {
        out.push(Check::CommErrorJoints(
            ctx.joints_list(j, "comm_error_joints")?,
        ));
    }
    if let Some(j) = &c.limit_error_joints {
        out.push(Check::LimitErrorJoints(
            ctx.joints_list(j, "limit_error_joints")?,
        ));
    }
    if let Some(map) = &c.joint_faults {
        for (joint, flags) in &map.value {
            if !(1..=PIPER_JOINTS as i64).contains(joint) {
                return Err(ctx.err(
                    pos(map),
                    format!("`joint_faults`: joint index {joint} out of range, expected 1..=6"),
                ));
            }
            let flags = flag_list(ctx, flags, &vocab::joint_flags(), "joint_faults")?;
            out.push(Check::JointFaults {
                joint: *joint as u8,
                flags,
            });
        }
    }
    if let Some(flags) = &c.gripper_faults {
        out.push(Check::GripperFaults(flag_list(
            ctx,
            &flags.value,
            &vocab::gripper_flags(),
            "gripper_faults",
        )?));
    }
    if out.is_empty() {
        return Err(ctx.err(
            at,
            format!(
                "`{step}` has no condition (for example `joints_deg`, `arm_status`, `enabled`)"
            ),
        ));
    }
    Ok(out)
}

fn flag_list(ctx: &Ctx<'_>, flags: &[S<String>], table: &[&str], key: &str) -> Res<Vec<String>> {
    let mut out = Vec::new();
    for f in flags {
        if !table.contains(&f.value.as_str()) {
            return Err(ctx.err(
                pos(f),
                format!(
                    "`{key}`: unknown flag `{}`; expected one of: {}",
                    f.value,
                    table.join(", ")
                ),
            ));
        }
        out.push(f.value.clone());
    }
    out.sort();
    out.dedup();
    Ok(out)
}
