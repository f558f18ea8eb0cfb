//! Client-side joint and gripper limits (the SDK's `start_sdk_joint_limit` /
//! `start_sdk_gripper_limit`), applied to commands before they reach the bus.

use super::error::{LimitedAxis, PiperError};

/// What to do with a command outside its limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub enum LimitPolicy {
    /// Send as given (the firmware enforces its own limits).
    #[default]
    Off,
    /// Clamp into the limit.
    Clamp,
    /// Refuse with [`PiperError::OutOfLimit`].
    Reject,
}

/// Joint and gripper limits in SI units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClientLimits {
    /// (min, max) per joint, rad.
    pub joints_rad: [(f64, f64); 6],
    /// (min, max) gripper stroke, m.
    pub gripper_m: (f64, f64),
}

impl Default for ClientLimits {
    /// The SDK's soft limits (`piper_param_manager`, spec §9.1 column 1) and a 0–70 mm gripper.
    // 3.14 is the SDK's literal J2 limit, not an approximation of π.
    #[allow(clippy::approx_constant)]
    fn default() -> Self {
        Self {
            joints_rad: [
                (-2.6179, 2.6179),
                (0.0, 3.14),
                (-2.967, 0.0),
                (-1.745, 1.745),
                (-1.22, 1.22),
                (-2.09439, 2.09439),
            ],
            gripper_m: (0.0, 0.07),
        }
    }
}

fn apply(
    axis: LimitedAxis,
    value: f64,
    (min, max): (f64, f64),
    policy: LimitPolicy,
) -> Result<f64, PiperError> {
    if !value.is_finite() {
        return Err(PiperError::InvalidValue {
            field: "target",
            value,
        });
    }
    match policy {
        LimitPolicy::Off => Ok(value),
        LimitPolicy::Clamp => Ok(value.clamp(min, max)),
        LimitPolicy::Reject if value < min => Err(PiperError::OutOfLimit {
            joint: axis,
            value,
            limit: min,
        }),
        LimitPolicy::Reject if value > max => Err(PiperError::OutOfLimit {
            joint: axis,
            value,
            limit: max,
        }),
        LimitPolicy::Reject => Ok(value),
    }
}

impl ClientLimits {
    /// Apply `policy` to six joint targets (rad).
    pub fn check_joints(
        &self,
        targets_rad: [f64; 6],
        policy: LimitPolicy,
    ) -> Result<[f64; 6], PiperError> {
        let mut out = targets_rad;
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = apply(
                LimitedAxis::Joint(i as u8 + 1),
                *slot,
                self.joints_rad[i],
                policy,
            )?;
        }
        Ok(out)
    }

    /// Apply `policy` to a gripper stroke (m).
    pub fn check_gripper(&self, stroke_m: f64, policy: LimitPolicy) -> Result<f64, PiperError> {
        apply(LimitedAxis::Gripper, stroke_m, self.gripper_m, policy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_reject_and_off_behave_differently() {
        let limits = ClientLimits::default();
        let target = [3.0, 0.5, -0.5, 0.0, 0.0, 0.0];
        assert_eq!(
            limits.check_joints(target, LimitPolicy::Off).ok(),
            Some(target)
        );
        let clamped = limits.check_joints(target, LimitPolicy::Clamp).ok();
        assert_eq!(clamped.map(|c| c[0]), Some(2.6179));
        match limits.check_joints(target, LimitPolicy::Reject) {
            Err(PiperError::OutOfLimit {
                joint: LimitedAxis::Joint(1),
                value,
                limit,
            }) => {
                assert_eq!((value, limit), (3.0, 2.6179));
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            limits.check_gripper(-0.01, LimitPolicy::Reject),
            Err(PiperError::OutOfLimit {
                joint: LimitedAxis::Gripper,
                ..
            })
        ));
        assert!(matches!(
            limits.check_joints([f64::NAN; 6], LimitPolicy::Off),
            Err(PiperError::InvalidValue { .. })
        ));
    }
}
