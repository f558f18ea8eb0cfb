//! What the motor-bus kinds share (a bus of motors, each addressed by its identifier:
//! `robstride`, `damiao`), around each kind's own motor entry, conditions and observation:
//!
//! - layer 1: the settings ([`RawMotorBus`]) and conditions ([`RawPerMotor`]) as written;
//! - layer 2: the `motors:` list written and not empty ([`listed`]), the numbers their steps
//!   send as `f32` ([`wire_f32`]), the expected value of a read ([`expectation`]), the motion
//!   conditions every motor has ([`motion_conditions`]);
//! - on the bench: values as replies show them ([`fixed`]) and the per-motor trace columns
//!   ([`motor_columns`], [`motor_row`]).

use std::collections::BTreeMap;
use std::fmt::Display;

use serde::Deserialize;

use super::TraceColumn;
use crate::scenario::{pos, Ctx, Near, Pos, Res, Signal, S};

/// A motor bus's settings as written (after `kind:`): the bench bus it is on and its motors,
/// each an `M` (the kind's motor entry). Named `RawSettings` to serde, as each kind's was.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "RawSettings")]
pub(crate) struct RawMotorBus<M> {
    /// `bus:`, the bench bus's name.
    pub bus: Option<S<String>>,
    /// `motors:`.
    pub motors: Option<S<Vec<S<M>>>>,
}

/// A motor bus's conditions in `expect` and `wait_until` as written: `motors: {ID: C}`, `C`
/// the kind's conditions on one motor. Named `RawConds` to serde, as each kind's was.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename = "RawConds")]
pub(crate) struct RawPerMotor<C> {
    /// The conditions by motor identifier.
    pub motors: Option<S<BTreeMap<i64, S<C>>>>,
}

/// The keys of [`RawPerMotor`].
pub(crate) const PER_MOTOR_CONDITION_KEYS: [&str; 1] = ["motors"];

/// The `motors:` list of a motor bus at `at`, written and not empty; `needs` is the error when
/// it is not written (it shows an entry).
pub(crate) fn listed<'m, M>(
    ctx: &Ctx<'_>,
    motors: &'m Option<S<Vec<S<M>>>>,
    needs: &str,
    at: Pos,
) -> Res<&'m [S<M>]> {
    let Some(list) = motors else {
        return Err(ctx.err(at, needs));
    };
    if list.value.is_empty() {
        return Err(ctx.err(pos(list), "`motors` is empty"));
    }
    Ok(&list.value)
}

/// A number the driver sends as `f32`: finite in `f32` too (1e308 would become infinity on
/// the way).
pub(crate) fn wire_f32(ctx: &Ctx<'_>, v: &S<f64>, key: &str) -> Res<f32> {
    let single = ctx.finite(v, key)? as f32;
    if single.is_finite() {
        Ok(single)
    } else {
        Err(ctx.err(
            pos(v),
            format!("`{key}` is too large (beyond ±3.4e38, the range of the motor's numbers)"),
        ))
    }
}

/// A value `key` and its tolerance `tolerance_key` (`default` when not written, else `>= 0`).
fn near(
    ctx: &Ctx<'_>,
    v: &S<f64>,
    key: &str,
    tolerance: &Option<S<f64>>,
    tolerance_key: &str,
    default: f64,
) -> Res<Near> {
    Ok(Near {
        value: ctx.finite(v, key)?,
        tolerance: tolerance
            .as_ref()
            .map_or(Ok(default), |t| ctx.non_negative(t, tolerance_key))?,
    })
}

/// `expect:` and `tolerance:` of a read (a parameter, a register): `None` without `expect`,
/// the tolerance `default` when not written.
pub(crate) fn expectation(
    ctx: &Ctx<'_>,
    expect: &Option<S<f64>>,
    tolerance: &Option<S<f64>>,
    default: f64,
) -> Res<Option<Near>> {
    expect
        .as_ref()
        .map(|e| near(ctx, e, "expect", tolerance, "tolerance", default))
        .transpose()
}

/// A motor's motion conditions (in `expect` and `wait_until`): each key, the key of its
/// tolerance and the tolerance when that is not written.
const MOTION_CONDITIONS: [(&str, &str, f64); 3] = [
    ("position_rad", "tolerance_rad", 0.05),
    ("velocity_rad_s", "tolerance_rad_s", 0.2),
    ("torque_nm", "tolerance_nm", 0.5),
];

/// A condition's value and its tolerance, as written.
pub(crate) type WithTolerance<'a> = (&'a Option<S<f64>>, &'a Option<S<f64>>);

/// A motor's motion conditions as written, each a value and its tolerance: `position_rad`
/// (`tolerance_rad`, 0.05 when not written), `velocity_rad_s` (`tolerance_rad_s`, 0.2) and
/// `torque_nm` (`tolerance_nm`, 0.5), made into the kind's conditions by `make` (in that
/// order), for those written.
pub(crate) fn motion_conditions<C>(
    ctx: &Ctx<'_>,
    written: [WithTolerance<'_>; 3],
    make: [fn(Near) -> C; 3],
) -> Res<Vec<C>> {
    let mut out = Vec::new();
    for ((value, tolerance), (make, (key, tolerance_key, default))) in written
        .into_iter()
        .zip(make.into_iter().zip(MOTION_CONDITIONS))
    {
        if let Some(v) = value {
            out.push(make(near(ctx, v, key, tolerance, tolerance_key, default)?));
        }
    }
    Ok(out)
}

/// `v` with `places` decimals, never `-0.00`.
pub(crate) fn fixed(v: f64, places: usize) -> String {
    let t = format!("{v:.places$}");
    if t.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        t.trim_start_matches('-').to_owned()
    } else {
        t
    }
}

/// One per-motor column of a signal: the suffix of its name (`m{id}_{suffix}`), its quantum
/// and its plot group.
pub(crate) type MotorColumn = (&'static str, f64, &'static str);

/// The trace columns of `signals` for the motors `ids` (in bench order): signal by signal,
/// each of its columns (`of`, empty for a signal the kind has no value for) for every motor.
pub(crate) fn motor_columns(
    signals: &[Signal],
    ids: &[impl Display],
    of: fn(Signal) -> &'static [MotorColumn],
) -> Vec<TraceColumn> {
    let mut cols = Vec::new();
    for signal in signals {
        for (suffix, quantum, group) in of(*signal) {
            for id in ids {
                cols.push(TraceColumn {
                    name: format!("m{id}_{suffix}"),
                    quantum: *quantum,
                    group,
                });
            }
        }
    }
    cols
}

/// One trace row, matching [`motor_columns`] with the same `of`: `motors` in the order of the
/// ids given there (`None`: not seen), each column's value by `value` (from its suffix).
pub(crate) fn motor_row<M>(
    signals: &[Signal],
    motors: &[Option<&M>],
    of: fn(Signal) -> &'static [MotorColumn],
    value: fn(&str, &M) -> Option<f64>,
) -> Vec<Option<f64>> {
    let mut out = Vec::new();
    for signal in signals {
        for (suffix, _, _) in of(*signal) {
            for m in motors {
                out.push(m.and_then(|m| value(suffix, m)));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::fixed;

    #[test]
    fn fixed_never_shows_a_negative_zero() {
        assert_eq!(fixed(-0.001, 2), "0.00");
        assert_eq!(fixed(-0.0004, 3), "0.000");
        assert_eq!(fixed(-0.005, 3), "-0.005");
        assert_eq!(fixed(1.2345, 2), "1.23");
    }
}
