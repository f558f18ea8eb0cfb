//! Wire units from field names: the driver's codec names every scaled integer with its unit
//! (`_mdeg`, `_um`, `_mrad_s` …); this turns such a name into a scale and a display unit.

/// Scale and unit of a wire field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitSpec {
    /// Physical value = raw × `scale`.
    pub scale: f64,
    /// Display unit (ASCII, as a DBC file needs it); empty for plain numbers.
    pub unit: &'static str,
}

/// Suffixes, longest first so `_mrad_s` wins over `_mrad`.
const SUFFIXES: [(&str, f64, &str); 11] = [
    ("_mrad_s2", 0.001, "rad/s2"),
    ("_mrad_s", 0.001, "rad/s"),
    ("_mm_s2", 0.001, "m/s2"),
    ("_mm_s", 0.001, "m/s"),
    ("_mrad", 0.001, "rad"),
    ("_mdeg", 0.001, "deg"),
    ("_mnm", 0.001, "N.m"),
    ("_um", 0.001, "mm"),
    ("_ma", 0.001, "A"),
    ("_dv", 0.1, "V"),
    ("_c", 1.0, "degC"),
];

/// The unit a field name carries, or scale 1 without a unit.
pub fn unit_of(field: &str) -> UnitSpec {
    SUFFIXES
        .iter()
        .find(|(suffix, _, _)| field.ends_with(suffix))
        .map_or(
            UnitSpec {
                scale: 1.0,
                unit: "",
            },
            |&(_, scale, unit)| UnitSpec { scale, unit },
        )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn longest_suffix_wins() {
        assert_eq!(unit_of("speed_mrad_s").unit, "rad/s");
        assert_eq!(unit_of("position_mrad").unit, "rad");
        assert_eq!(unit_of("bus_voltage_dv").scale, 0.1);
        assert_eq!(unit_of("trajectory_num").unit, "");
    }
}
