//! Layer 2 of the Piper's vocabulary: check its raw settings (here), steps ([`step`]),
//! conditions ([`checks`], with the status words of [`vocab`]) and emulator faults ([`fault`],
//! the scenario front end of the emulator's fault builder), with file:line:col errors.

mod checks;
mod fault;
mod step;
#[cfg(test)]
mod tests;
mod vocab;

pub(crate) use checks::checks;
pub(crate) use fault::fault;
pub(crate) use step::step;

use std::path::PathBuf;

use super::model::*;
use super::raw::*;
use crate::devices::named_bus;
use crate::scenario::error::Pos;
use crate::scenario::Near;
use crate::scenario::S;
use crate::scenario::{pos, Ctx, Res};

/// Default MOVE speed percentage.
const DEFAULT_SPEED_PCT: u8 = 50;
/// Longest `every_ms` re-send period, ms.
const MAX_EVERY_MS: i64 = 10_000;
/// Default tolerance on joint angles.
const DEFAULT_TOLERANCE_DEG: f64 = 0.5;
/// Default tolerance on positions and gripper stroke.
const DEFAULT_TOLERANCE_MM: f64 = 1.0;
/// Default firmware profile.
pub const DEFAULT_FIRMWARE: &str = "S-V1.8-8";

/// Validation helpers for the Piper's joint-indexed values.
trait PiperCtx {
    fn joint(&self, value: &S<i64>, key: &str, allow_all: bool) -> Res<u8>;
    fn joint_required(
        &self,
        value: &Option<S<i64>>,
        action: &str,
        at: Pos,
        allow_all: bool,
    ) -> Res<u8>;
    fn pct(&self, value: &Option<S<i64>>) -> Res<u8>;
    fn every_ms(&self, value: &Option<S<i64>>) -> Res<Option<u32>>;
    fn optional_list(&self, value: &S<Vec<Option<f64>>>, key: &str) -> Res<Vec<Option<f64>>>;
    fn joints_list(&self, value: &S<Vec<i64>>, key: &str) -> Res<Vec<u8>>;
}

impl PiperCtx for Ctx<'_> {
    fn joint(&self, value: &S<i64>, key: &str, allow_all: bool) -> Res<u8> {
        let max = if allow_all { 7 } else { PIPER_JOINTS as i64 };
        if (1..=max).contains(&value.value) {
            Ok(value.value as u8)
        } else {
            let range = if allow_all {
                "1..=6, or 7 for all joints"
            } else {
                "1..=6"
            };
            Err(self.err(
                pos(value),
                format!(
                    "`{key}`: joint index {} out of range, expected {range}",
                    value.value
                ),
            ))
        }
    }

    fn joint_required(
        &self,
        value: &Option<S<i64>>,
        action: &str,
        at: Pos,
        allow_all: bool,
    ) -> Res<u8> {
        let v = self.required(value, "joint", action, at)?;
        self.joint(v, "joint", allow_all)
    }

    fn pct(&self, value: &Option<S<i64>>) -> Res<u8> {
        match value {
            None => Ok(DEFAULT_SPEED_PCT),
            Some(v) if (0..=100).contains(&v.value) => Ok(v.value as u8),
            Some(v) => Err(self.err(
                pos(v),
                format!("`speed_pct` must be 0..=100, got {}", v.value),
            )),
        }
    }

    fn every_ms(&self, value: &Option<S<i64>>) -> Res<Option<u32>> {
        match value {
            None => Ok(None),
            Some(v) if (1..=MAX_EVERY_MS).contains(&v.value) => Ok(Some(v.value as u32)),
            Some(v) => Err(self.err(
                pos(v),
                format!("`every_ms` must be 1..={MAX_EVERY_MS}, got {}", v.value),
            )),
        }
    }

    fn optional_list(&self, value: &S<Vec<Option<f64>>>, key: &str) -> Res<Vec<Option<f64>>> {
        if value.value.len() != PIPER_JOINTS {
            return Err(self.err(
                pos(value),
                format!(
                    "`{key}` needs one entry per joint ({PIPER_JOINTS}; use ~ for joints not checked), got {}",
                    value.value.len()
                ),
            ));
        }
        if value.value.iter().flatten().any(|v| !v.is_finite()) {
            return Err(self.err(pos(value), format!("`{key}` must hold finite numbers")));
        }
        Ok(value.value.clone())
    }

    fn joints_list(&self, value: &S<Vec<i64>>, key: &str) -> Res<Vec<u8>> {
        let mut joints = Vec::new();
        for j in &value.value {
            if !(1..=PIPER_JOINTS as i64).contains(j) {
                return Err(self.err(
                    pos(value),
                    format!("`{key}`: joint index {j} out of range, expected 1..=6"),
                ));
            }
            joints.push(*j as u8);
        }
        joints.sort_unstable();
        joints.dedup();
        Ok(joints)
    }
}

/// The settings of a `kind: piper` device.
pub(crate) fn settings(ctx: &Ctx<'_>, d: &RawSettings, _at: Pos) -> Res<PiperSettings> {
    let firmware = match &d.firmware {
        Some(fw) => fw
            .value
            .parse::<sim::piper::FirmwareProfile>()
            .map_err(|_| {
                let names: Vec<&str> = sim::piper::FirmwareProfile::ALL
                    .iter()
                    .map(|p| p.version_string())
                    .collect();
                ctx.err(
                    pos(fw),
                    format!(
                        "`firmware`: unknown Piper firmware `{}`; the emulator implements: {}",
                        fw.value,
                        names.join(", ")
                    ),
                )
            })?
            .version_string()
            .to_owned(),
        None => DEFAULT_FIRMWARE.to_owned(),
    };
    let urdf = match &d.urdf {
        Some(path) => {
            let p = PathBuf::from(&path.value);
            let resolved = if p.is_absolute() || p.exists() {
                p
            } else {
                ctx.file.parent().map_or(p.clone(), |dir| dir.join(&p))
            };
            if !resolved.exists() {
                return Err(ctx.err(
                    pos(path),
                    format!("`urdf`: file `{}` not found", path.value),
                ));
            }
            Some(resolved)
        }
        None => None,
    };
    let initial_joints_deg = match &d.initial_joints_deg {
        Some(list) => ctx.array::<PIPER_JOINTS>(list, "initial_joints_deg")?,
        None => [0.0; PIPER_JOINTS],
    };
    let gripper_max_mm = match &d.gripper_max_mm {
        Some(v) if matches!(v.value, 0 | 70 | 100) => Some(v.value as u8),
        Some(v) => {
            return Err(ctx.err(
                pos(v),
                format!(
                    "`gripper_max_mm` must be 0 (never set), 70 or 100, got {}",
                    v.value
                ),
            ))
        }
        None => None,
    };
    let collision_levels = d
        .collision_levels
        .as_ref()
        .map(|l| levels(ctx, l))
        .transpose()?;
    let mut obstacles = Vec::new();
    for (i, o) in d.obstacles.iter().flatten().enumerate() {
        let at_m = ctx.array::<3>(&o.value.at_m, "at_m")?;
        let shape = match (&o.value.box_m, &o.value.sphere_radius_m) {
            (Some(size), None) => {
                let size_m = ctx.array::<3>(size, "box_m")?;
                if size_m.iter().any(|s| *s <= 0.0) {
                    return Err(ctx.err(pos(size), "`box_m` edge lengths must be > 0"));
                }
                ObstacleShape::Box { size_m }
            }
            (None, Some(r)) => {
                let radius_m = ctx.non_negative(r, "sphere_radius_m")?;
                ObstacleShape::Sphere { radius_m }
            }
            _ => return Err(ctx.err(
                pos(o),
                "an obstacle needs exactly one shape: `box_m: [x, y, z]` or `sphere_radius_m: r`",
            )),
        };
        obstacles.push(Obstacle {
            name: o
                .value
                .name
                .clone()
                .unwrap_or_else(|| format!("obstacle{}", i + 1)),
            shape,
            at_m,
        });
    }
    Ok(PiperSettings {
        bus: named_bus(ctx, &d.bus)?,
        role: match &d.role {
            Some(r) => ctx.choice(
                r,
                "role",
                &[(Role::Leader, "leader"), (Role::Follower, "follower")],
            )?,
            None => Role::Follower,
        },
        firmware,
        urdf,
        initial_joints_deg,
        gripper_max_mm,
        collision_levels,
        obstacles,
    })
}

fn pose(
    ctx: &Ctx<'_>,
    position: &Option<S<Vec<f64>>>,
    orientation: &Option<S<Vec<f64>>>,
    action: &str,
    at: Pos,
) -> Res<Pose> {
    let p = ctx.required(position, "position_mm", action, at)?;
    let o = ctx.required(orientation, "orientation_deg", action, at)?;
    Ok(Pose {
        position_mm: ctx.array::<3>(p, "position_mm")?,
        orientation_deg: ctx.array::<3>(o, "orientation_deg")?,
    })
}

fn raw_pose(ctx: &Ctx<'_>, raw: &Option<S<RawPose>>, key: &str, at: Pos) -> Res<Pose> {
    let p = ctx.required(raw, key, "move_c", at)?;
    Ok(Pose {
        position_mm: ctx.array::<3>(&p.value.position_mm, "position_mm")?,
        orientation_deg: ctx.array::<3>(&p.value.orientation_deg, "orientation_deg")?,
    })
}

fn near(ctx: &Ctx<'_>, value: &Option<S<f64>>, key: &str, tolerance: f64) -> Res<Option<Near>> {
    value
        .as_ref()
        .map(|v| {
            Ok(Near {
                value: ctx.finite(v, key)?,
                tolerance,
            })
        })
        .transpose()
}

fn small_uint(
    ctx: &Ctx<'_>,
    value: &Option<S<i64>>,
    key: &str,
    range: std::ops::RangeInclusive<i64>,
) -> Res<Option<u16>> {
    match value {
        None => Ok(None),
        Some(v) if range.contains(&v.value) => Ok(Some(v.value as u16)),
        Some(v) => Err(ctx.err(
            pos(v),
            format!(
                "`{key}` must be {}..={}, got {}",
                range.start(),
                range.end(),
                v.value
            ),
        )),
    }
}

fn levels(ctx: &Ctx<'_>, raw: &S<Vec<i64>>) -> Res<[u8; PIPER_JOINTS]> {
    if raw.value.len() != PIPER_JOINTS {
        return Err(ctx.err(
            pos(raw),
            format!(
                "`levels` needs exactly 6 values (one per joint), got {}",
                raw.value.len()
            ),
        ));
    }
    let mut out = [0u8; PIPER_JOINTS];
    for (slot, v) in out.iter_mut().zip(&raw.value) {
        if !(0..=8).contains(v) {
            return Err(ctx.err(pos(raw), format!("collision levels are 0..=8, got {v}")));
        }
        *slot = *v as u8;
    }
    Ok(out)
}

fn offset(ctx: &Ctx<'_>, raw: &Option<S<i64>>, key: &str) -> Res<u8> {
    match raw {
        None => Ok(0),
        Some(v) if matches!(v.value, 0 | 0x10 | 0x20) => Ok(v.value as u8),
        Some(v) => Err(ctx.err(
            pos(v),
            format!("`{key}` must be 0, 0x10 or 0x20, got {}", v.value),
        )),
    }
}
