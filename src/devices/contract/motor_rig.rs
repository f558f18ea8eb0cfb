//! The rig a motor of a motor-bus kind (RobStride's, Damiao's) drives on the bench, as its
//! `motors:` entry writes it (`load`, `start_angle_rad`, `friction_nm_s_per_rad`) and checked
//! within what keeps the rig's physics finite: the same rig (`sim::robstride::Load`) for
//! every such motor.

use serde::Deserialize;
use sim::robstride::Load;

use crate::scenario::onekey::one_key_enum;
use crate::scenario::{pos, Ctx, Res, S};

/// `load: none`: a bare shaft.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawNoLoad {}

/// `load: {disc: …}`: a flywheel on the shaft.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDisc {
    /// `mass_kg:`.
    pub mass_kg: S<f64>,
    /// `radius_m:`.
    pub radius_m: S<f64>,
}

/// `load: {pendulum: …}`: a point mass on a massless arm, under gravity.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPendulum {
    /// `mass_kg:`.
    pub mass_kg: S<f64>,
    /// `length_m:`.
    pub length_m: S<f64>,
}

one_key_enum! {
    /// What a motor drives.
    pub(crate) enum RawLoad ("load") {
        "none" => NoLoad(RawNoLoad) [bare],
        "disc" => Disc(RawDisc),
        "pendulum" => Pendulum(RawPendulum),
    }
}

/// A number `> 0`.
fn positive(ctx: &Ctx<'_>, v: &S<f64>, key: &str) -> Res<f64> {
    let x = ctx.finite(v, key)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(ctx.err(pos(v), format!("`{key}` must be > 0, got {x}")))
    }
}

/// Largest load mass, kg: far beyond any motor's rig, small enough for finite physics.
const MAX_MASS_KG: f64 = 1000.0;
/// Largest disc radius or pendulum length, m.
const MAX_LENGTH_M: f64 = 10.0;
/// Largest rig friction, N·m·s/rad.
const MAX_FRICTION_NM_S_PER_RAD: f64 = 1000.0;
/// Largest |start angle|, rad (RobStride's position range is ±4π).
const MAX_START_ANGLE_RAD: f64 = 100.0;

/// A physical parameter in `min ..= max` (`min` itself excluded when `positive`); a finite
/// but absurd value (`mass_kg: 1e308`) would turn the rig's physics into NaN.
fn bounded(ctx: &Ctx<'_>, v: &S<f64>, key: &str, positive_only: bool, max: f64) -> Res<f64> {
    let x = if positive_only {
        positive(ctx, v, key)?
    } else {
        ctx.finite(v, key)?
    };
    if x.abs() > max {
        let range = if positive_only {
            format!("at most {max}")
        } else {
            format!("between -{max} and {max}")
        };
        return Err(ctx.err(pos(v), format!("`{key}` must be {range}, got {x:?}")));
    }
    Ok(x)
}

/// A motor's rig as its entry gives it (each `None` where not written): what a RobStride and a
/// Damiao motor's shaft drives alike (`sim::robstride::Load`).
pub(crate) struct Rig {
    /// `load:`.
    pub load: Option<Load>,
    /// `start_angle_rad:`.
    pub start_angle_rad: Option<f64>,
    /// `friction_nm_s_per_rad:`.
    pub friction_nm_s_per_rad: Option<f64>,
}

/// A motor entry's `load`, `start_angle_rad` and `friction_nm_s_per_rad`, each checked within
/// what keeps the rig's physics finite.
pub(crate) fn rig(
    ctx: &Ctx<'_>,
    load: &Option<S<RawLoad>>,
    start_angle_rad: &Option<S<f64>>,
    friction: &Option<S<f64>>,
) -> Res<Rig> {
    let load = load
        .as_ref()
        .map(|load| -> Res<Load> {
            Ok(match &load.value {
                RawLoad::NoLoad(_) => Load::None,
                RawLoad::Disc(disc) => Load::Disc {
                    mass_kg: bounded(ctx, &disc.mass_kg, "mass_kg", true, MAX_MASS_KG)?,
                    radius_m: bounded(ctx, &disc.radius_m, "radius_m", true, MAX_LENGTH_M)?,
                },
                RawLoad::Pendulum(p) => Load::Pendulum {
                    mass_kg: bounded(ctx, &p.mass_kg, "mass_kg", true, MAX_MASS_KG)?,
                    length_m: bounded(ctx, &p.length_m, "length_m", true, MAX_LENGTH_M)?,
                },
            })
        })
        .transpose()?;
    let start_angle_rad = start_angle_rad
        .as_ref()
        .map(|a| bounded(ctx, a, "start_angle_rad", false, MAX_START_ANGLE_RAD))
        .transpose()?;
    let friction_nm_s_per_rad = friction
        .as_ref()
        .map(|f| {
            let friction = ctx.non_negative(f, "friction_nm_s_per_rad")?;
            bounded(
                ctx,
                f,
                "friction_nm_s_per_rad",
                false,
                MAX_FRICTION_NM_S_PER_RAD,
            )
            .map(|_| friction)
        })
        .transpose()?;
    Ok(Rig {
        load,
        start_angle_rad,
        friction_nm_s_per_rad,
    })
}

impl Rig {
    /// The motor's rig as given: each part written replaces the configuration's own.
    pub(crate) fn apply(
        self,
        load: &mut Load,
        start_angle_rad: &mut f64,
        friction_nm_s_per_rad: &mut f64,
    ) {
        if let Some(l) = self.load {
            *load = l;
        }
        if let Some(angle) = self.start_angle_rad {
            *start_angle_rad = angle;
        }
        if let Some(friction) = self.friction_nm_s_per_rad {
            *friction_nm_s_per_rad = friction;
        }
    }
}
