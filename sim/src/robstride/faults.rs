//! Faults and warnings: the type-21 fault word, the status-frame fault bits, and the typed
//! faults the harness injects (spec §9).

use serde::{Deserialize, Serialize};

/// A fault the harness can inject (and the models can raise on their own).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Fault {
    /// Winding over-temperature: the injection heats the winding past the fault threshold.
    OverTemperature,
    /// Supply below 12 V: the injection drops the supply to 10 V.
    UnderVoltage,
    /// Supply above the model's limit: the injection raises the supply 2 V past it.
    OverVoltage,
    /// Phase over-current on one phase (one-shot event).
    PhaseOverCurrent(Phase),
    /// Encoder not calibrated: the motor sits in calibration state until calibrated.
    EncoderNotCalibrated,
    /// Stall / I²t overload protection (one-shot event).
    StallOverload,
    /// Gate-driver chip fault (one-shot event).
    GateDriver,
}

/// A motor phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Phase {
    /// Phase A (fault word bit 16).
    A,
    /// Phase B (fault word bit 4).
    B,
    /// Phase C (fault word bit 5).
    C,
}

impl Fault {
    /// Every fault the emulator can inject.
    pub const ALL: [Fault; 9] = [
        Fault::OverTemperature,
        Fault::UnderVoltage,
        Fault::OverVoltage,
        Fault::PhaseOverCurrent(Phase::A),
        Fault::PhaseOverCurrent(Phase::B),
        Fault::PhaseOverCurrent(Phase::C),
        Fault::EncoderNotCalibrated,
        Fault::StallOverload,
        Fault::GateDriver,
    ];

    /// The fault's name in scenario files, logs and reports.
    pub fn name(self) -> &'static str {
        match self {
            Fault::OverTemperature => "over_temperature",
            Fault::UnderVoltage => "under_voltage",
            Fault::OverVoltage => "over_voltage",
            Fault::PhaseOverCurrent(Phase::A) => "phase_a_over_current",
            Fault::PhaseOverCurrent(Phase::B) => "phase_b_over_current",
            Fault::PhaseOverCurrent(Phase::C) => "phase_c_over_current",
            Fault::EncoderNotCalibrated => "encoder_not_calibrated",
            Fault::StallOverload => "stall_overload",
            Fault::GateDriver => "gate_driver",
        }
    }

    /// The fault with this [`name`](Fault::name).
    pub fn from_name(name: &str) -> Option<Fault> {
        Fault::ALL.into_iter().find(|f| f.name() == name)
    }

    /// The bit of the type-21 fault word (spec §9.1).
    pub fn word_bit(self) -> u32 {
        match self {
            Fault::OverTemperature => 1 << 0,
            Fault::GateDriver => 1 << 1,
            Fault::UnderVoltage => 1 << 2,
            Fault::OverVoltage => 1 << 3,
            Fault::PhaseOverCurrent(Phase::B) => 1 << 4,
            Fault::PhaseOverCurrent(Phase::C) => 1 << 5,
            Fault::EncoderNotCalibrated => 1 << 7,
            Fault::StallOverload => 1 << 14,
            Fault::PhaseOverCurrent(Phase::A) => 1 << 16,
        }
    }
}

/// Fault word bit 0 of the warning word: over-temperature warning.
pub const WARNING_OVER_TEMP: u32 = 1;

/// The six status-frame fault bits (bits 21..16 of a type-2 identifier, as 0..5) for a fault
/// word, per the spec's §9.2 mapping. Over-voltage has no status bit of its own (the vendor
/// sample's mapping to the encoder bit looks like a bug), so it shows only in the type-21 word.
pub fn status_bits(fault_word: u32) -> u8 {
    let mut bits = 0u8;
    if fault_word & Fault::UnderVoltage.word_bit() != 0 {
        bits |= 1 << 0;
    }
    let over_current = Fault::PhaseOverCurrent(Phase::A).word_bit()
        | Fault::PhaseOverCurrent(Phase::B).word_bit()
        | Fault::PhaseOverCurrent(Phase::C).word_bit()
        | Fault::GateDriver.word_bit();
    if fault_word & over_current != 0 {
        bits |= 1 << 1;
    }
    if fault_word & Fault::OverTemperature.word_bit() != 0 {
        bits |= 1 << 2;
    }
    // Bit 3 (magnetic encoder fault) has no injectable cause; bit 19 stays clear.
    if fault_word & Fault::StallOverload.word_bit() != 0 {
        bits |= 1 << 4;
    }
    if fault_word & Fault::EncoderNotCalibrated.word_bit() != 0 {
        bits |= 1 << 5;
    }
    bits
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_fault_has_its_own_name_and_word_bit() {
        for (i, a) in Fault::ALL.iter().enumerate() {
            assert_eq!(Fault::from_name(a.name()), Some(*a));
            for b in &Fault::ALL[i + 1..] {
                assert_ne!(a.name(), b.name());
                assert_ne!(a.word_bit(), b.word_bit());
            }
        }
        assert_eq!(Fault::from_name("melted"), None);
    }

    #[test]
    fn status_bits_follow_the_documented_mapping() {
        assert_eq!(status_bits(Fault::OverTemperature.word_bit()), 0x04);
        assert_eq!(status_bits(Fault::UnderVoltage.word_bit()), 0x01);
        assert_eq!(
            status_bits(Fault::PhaseOverCurrent(Phase::A).word_bit()),
            0x02
        );
        assert_eq!(status_bits(Fault::GateDriver.word_bit()), 0x02);
        assert_eq!(status_bits(Fault::StallOverload.word_bit()), 0x10);
        assert_eq!(status_bits(Fault::EncoderNotCalibrated.word_bit()), 0x20);
        assert_eq!(status_bits(Fault::OverVoltage.word_bit()), 0);
    }
}
