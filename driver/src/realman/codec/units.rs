//! Conversions between SI values and the controller's wire integers (docs/protocols/realman.md §2).
//!
//! Encoding rounds to the nearest wire step and refuses values that are not finite or do not fit
//! an `i64` comfortably (the controller uses 32-bit fields; we check ±2³¹).

use super::EncodeError;

const WIRE_LIMIT: f64 = 2_147_483_647.0;

/// Rounds `value * scale` to a wire integer, naming `field` when it cannot be encoded.
pub fn to_wire(field: &'static str, value: f64, scale: f64) -> Result<i64, EncodeError> {
    let scaled = (value * scale).round();
    if !scaled.is_finite() || scaled.abs() > WIRE_LIMIT {
        return Err(EncodeError::NotEncodable { field, value });
    }
    Ok(scaled as i64)
}

/// Encodes every element of `values` with the same scale.
pub fn all_to_wire(
    field: &'static str,
    values: &[f64],
    scale: f64,
) -> Result<Vec<i64>, EncodeError> {
    values.iter().map(|&v| to_wire(field, v, scale)).collect()
}

/// Radians to 0.001° steps.
pub const RAD_TO_MDEG: f64 = 180_000.0 / std::f64::consts::PI;
/// Metres to 0.001 mm steps (1e-6 m).
pub const M_TO_UM: f64 = 1e6;
/// Radians (or rad/s, m/s …) to thousandths.
pub const MILLI: f64 = 1000.0;
/// Quaternion components to 1e-6 steps.
pub const QUAT: f64 = 1e6;
/// rad/s to 0.001 RPM (joint speed limits); the same factor maps rad/s² to 0.001 RPM/s.
pub const RAD_S_TO_MILLI_RPM: f64 = 60_000.0 / (2.0 * std::f64::consts::PI);

/// 0.001° wire value to radians.
pub fn mdeg_to_rad(v: i64) -> f64 {
    v as f64 / RAD_TO_MDEG
}

/// 1e-6 m wire value to metres.
pub fn um_to_m(v: i64) -> f64 {
    v as f64 / M_TO_UM
}

/// Thousandths to units (0.001 rad, 0.001 m/s, 0.001 °C, 0.001 V …).
pub fn milli(v: i64) -> f64 {
    v as f64 / MILLI
}

/// 0.001 RPM (or RPM/s) to rad/s (rad/s²).
pub fn milli_rpm_to_rad_s(v: i64) -> f64 {
    v as f64 / RAD_S_TO_MILLI_RPM
}

/// 0.001 mA to amperes.
pub fn micro_amp_to_a(v: i64) -> f64 {
    v as f64 * 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn documented_examples() {
        // docs §2: 10.1° → 10100, 0.1 m → 100000, 0.4 rad → 400, 30 RPM → 30000.
        assert_eq!(
            to_wire("a", 10.1f64.to_radians(), RAD_TO_MDEG).unwrap(),
            10100
        );
        assert_eq!(to_wire("p", 0.1, M_TO_UM).unwrap(), 100000);
        assert_eq!(to_wire("r", 0.4, MILLI).unwrap(), 400);
        let rpm30 = 30.0 * 2.0 * std::f64::consts::PI / 60.0;
        assert_eq!(to_wire("s", rpm30, RAD_S_TO_MILLI_RPM).unwrap(), 30000);
        assert!((milli_rpm_to_rad_s(37500) - 225f64.to_radians()).abs() < 1e-12);
        assert!((mdeg_to_rad(-178000) + 178f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn refuses_non_finite_and_huge() {
        assert!(to_wire("a", f64::NAN, MILLI).is_err());
        assert!(to_wire("a", f64::INFINITY, MILLI).is_err());
        assert!(to_wire("a", 1e7, MILLI).is_err());
    }
}
