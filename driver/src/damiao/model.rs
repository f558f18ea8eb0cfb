//! Per-model MIT mapping ranges (PMAX, VMAX, TMAX: docs/protocols/damiao.md §10) the driver
//! encodes MIT commands with and decodes feedback with.
//!
//! Host and motor must agree on them: the motor holds its own in registers 21–23
//! ([`crate::damiao::DamiaoMotor::read_ranges`] reads them). The published tables disagree on
//! the DM4340's VMAX (10 or 8 rad/s); [`RangeTable::Current`] (10) is the default and
//! [`RangeTable::Legacy`] gives 8.

/// A Damiao joint-motor model; parsed from its name in any case, `-` or `_` before a voltage
/// suffix (`dm4310`, `DM4310-48V`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, strum::EnumString)]
#[strum(ascii_case_insensitive)]
pub enum Model {
    /// DM3507.
    DM3507,
    /// DM-J4310-2EC (24 V).
    DM4310,
    /// DM-J4310 48 V variant.
    DM4310_48V,
    /// DM-J4340(P) (24 V).
    DM4340,
    /// DM-J4340 48 V variant.
    DM4340_48V,
    /// DM-J6006.
    DM6006,
    /// DM-J8006.
    DM8006,
    /// DM-J8009.
    DM8009,
    /// DM-J10010L.
    DM10010L,
    /// DM-J10010.
    DM10010,
    /// DM-H3510.
    H3510,
    /// DM-G6215.
    G6215,
    /// DM-H6220.
    H6220,
}

/// Which published range table to use where they disagree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RangeTable {
    /// The current vendor tables (default): DM4340 VMAX 10 rad/s.
    #[default]
    Current,
    /// The older tables some clients still ship: DM4340 VMAX 8 rad/s.
    Legacy,
}

/// The symmetric MIT mapping ranges of one motor: positions over ±`pmax`, velocities over
/// ±`vmax`, torques over ±`tmax`. Gains always map over 0..=500 (kp) and 0..=5 (kd).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranges {
    /// PMAX (rad), register 21.
    pub pmax: f32,
    /// VMAX (rad/s), register 22.
    pub vmax: f32,
    /// TMAX (N·m), register 23.
    pub tmax: f32,
}

impl Ranges {
    /// Ranges from PMAX, VMAX and TMAX.
    pub fn new(pmax: f32, vmax: f32, tmax: f32) -> Self {
        Self { pmax, vmax, tmax }
    }

    /// True when every limit is finite and above zero (the codec needs a non-empty span).
    pub fn is_valid(&self) -> bool {
        [self.pmax, self.vmax, self.tmax]
            .iter()
            .all(|x| x.is_finite() && *x > 0.0)
    }
}

impl Model {
    /// Every model, in table order.
    pub const ALL: [Model; 13] = [
        Self::DM3507,
        Self::DM4310,
        Self::DM4310_48V,
        Self::DM4340,
        Self::DM4340_48V,
        Self::DM6006,
        Self::DM8006,
        Self::DM8009,
        Self::DM10010L,
        Self::DM10010,
        Self::H3510,
        Self::G6215,
        Self::H6220,
    ];

    /// Parse `DM4310`, `dm4310`, `DM4310-48V` or `DM4310_48V`.
    pub fn parse(name: &str) -> Option<Self> {
        name.trim().replace('-', "_").parse().ok()
    }

    /// The model's ranges in `table`.
    pub fn ranges(self, table: RangeTable) -> Ranges {
        let (pmax, vmax, tmax) = match self {
            Self::DM3507 => (12.5, 50.0, 5.0),
            Self::DM4310 => (12.5, 30.0, 10.0),
            Self::DM4310_48V => (12.5, 50.0, 10.0),
            Self::DM4340 if table == RangeTable::Legacy => (12.5, 8.0, 28.0),
            Self::DM4340 | Self::DM4340_48V => (12.5, 10.0, 28.0),
            Self::DM6006 => (12.5, 45.0, 20.0),
            Self::DM8006 => (12.5, 45.0, 40.0),
            Self::DM8009 => (12.5, 45.0, 54.0),
            Self::DM10010L => (12.5, 25.0, 200.0),
            Self::DM10010 => (12.5, 20.0, 200.0),
            Self::H3510 => (12.5, 280.0, 1.0),
            Self::G6215 | Self::H6220 => (12.5, 45.0, 10.0),
        };
        Ranges::new(pmax, vmax, tmax)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn models_parse_by_name_in_any_case_and_separator() {
        assert_eq!(Model::parse("DM4310"), Some(Model::DM4310));
        assert_eq!(Model::parse(" dm8009 "), Some(Model::DM8009));
        assert_eq!(Model::parse("DM4340-48V"), Some(Model::DM4340_48V));
        assert_eq!(Model::parse("dm4340_48v"), Some(Model::DM4340_48V));
        assert_eq!(Model::parse("DM9999"), None);
    }

    #[test]
    fn only_the_dm4340_changes_with_the_table() {
        for model in Model::ALL {
            let (current, legacy) = (
                model.ranges(RangeTable::Current),
                model.ranges(RangeTable::Legacy),
            );
            assert!(current.is_valid() && legacy.is_valid(), "{model:?}");
            if model == Model::DM4340 {
                assert_eq!((current.vmax, legacy.vmax), (10.0, 8.0));
            } else {
                assert_eq!(current, legacy, "{model:?}");
            }
        }
        assert!(!Ranges::new(12.5, 0.0, 10.0).is_valid());
        assert!(!Ranges::new(f32::NAN, 30.0, 10.0).is_valid());
    }
}
