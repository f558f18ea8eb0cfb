//! How many bit times a CAN data frame occupies on the wire, classic or CAN FD, and how long
//! that takes.
//!
//! Frame lengths count every bit from start-of-frame through the 3-bit intermission that must
//! follow before the next frame may start, so back-to-back frames are spaced by exactly their
//! length.
//!
//! **Classic frames.** Without stuffing a standard (11-bit) frame is `47 + 8n` bits and an
//! extended (29-bit) frame `67 + 8n` bits for `n` data bytes. Bit stuffing (a complementary bit
//! after five equal bits) applies from start-of-frame through the CRC: `34 + 8n` bits for
//! standard frames and `54 + 8n` for extended, adding at most `(stuffable - 1) / 4` bits,
//! hence the worst cases `55 + 10n` and `80 + 10n`.
//!
//! **CAN FD frames** (ISO 11898-1:2015 frame format; the stuffing rules as Vector's CAN FD
//! e-learning pages state them: dynamic stuffing ends with the data field, then the stuff
//! count, then a fixed stuff bit before the stuff count and after every fourth bit of the CRC
//! field):
//!
//! | field | base (11-bit) | extended (29-bit) | rate |
//! |---|---|---|---|
//! | SOF, identifier, SRR + IDE (extended), RRS, IDE (base), FDF, res, BRS | 17 | 36 | nominal |
//! | ESI, DLC, data | `5 + 8n` | `5 + 8n` | data |
//! | dynamic stuff bits over all the bits above | `≤ (17 + 5 + 8n − 1) / 4` | `≤ (36 + 5 + 8n − 1) / 4` | where they fall |
//! | stuff count (3-bit Gray count + parity) | 4 | 4 | data |
//! | CRC sequence: 17 bits up to 16 data bytes, 21 bits above | 17 / 21 | 17 / 21 | data |
//! | fixed stuff bits: `⌈(4 + crc) / 4⌉` | 6 / 7 | 6 / 7 | data |
//! | CRC delimiter | 1 | 1 | data |
//! | ACK slot, ACK delimiter, EOF (7), intermission (3) | 12 | 12 | nominal |
//!
//! So without dynamic stuffing a CAN FD frame is `29` nominal bits plus `34 + 8n` (CRC-17) or
//! `39 + 8n` (CRC-21) data-rate bits with an 11-bit identifier, `48` nominal bits plus the same
//! with a 29-bit one. The rate switches at the sample point of the BRS bit and back at the
//! sample point of the CRC delimiter: counting BRS wholly at the nominal rate and the CRC
//! delimiter wholly at the data rate is exact when both bit timings put their sample points at
//! the same fraction of the bit, and off by less than one bit time otherwise. A dynamic stuff
//! bit belongs to the phase in which it is sent: one that follows the BRS bit is sent at the
//! data rate. A run of five equal bits ending with the last data bit counts one dynamic stuff
//! bit, as a run ending anywhere else does. Without BRS every bit is sent at the nominal rate.
//! The CRC field's length does not depend on the CRC's value (its stuff bits are fixed), so the
//! CAN FD CRC is not computed.

use std::time::Duration;

use crate::{CanFrame, CanId};

/// Which stuff bits the wire model adds to a frame's length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StuffingPolicy {
    /// No stuff bits: the shortest possible frame (`47 + 8n` / `67 + 8n` bits classic).
    None,
    /// The maximum number of stuff bits any frame of that format and length can need
    /// (`55 + 10n` / `80 + 10n` bits classic), the figure bus-load budgets use.
    WorstCase,
    /// The stuff bits this exact frame needs, computed from its bit sequence (including the
    /// CRC of a classic frame). Deterministic and the most faithful choice, hence the default.
    #[default]
    Exact,
}

/// Frame bits outside the stuffed region: CRC delimiter, ACK slot and delimiter, 7-bit end of
/// frame and the 3-bit intermission.
const UNSTUFFED_TAIL_BITS: u32 = 1 + 1 + 1 + 7 + 3;

/// CAN FD bits from SOF through BRS (sent at the nominal rate), 11-bit identifier: SOF,
/// identifier, RRS, IDE, FDF, res, BRS.
const FD_ARBITRATION_BITS_BASE: u32 = 1 + 11 + 1 + 1 + 1 + 1 + 1;
/// The same with a 29-bit identifier: SOF, base identifier, SRR, IDE, identifier extension,
/// RRS, FDF, res, BRS.
const FD_ARBITRATION_BITS_EXTENDED: u32 = 1 + 11 + 1 + 1 + 18 + 1 + 1 + 1 + 1;
/// CAN FD bits after the CRC delimiter (nominal rate): ACK slot and delimiter, EOF,
/// intermission.
const FD_TAIL_BITS: u32 = 1 + 1 + 7 + 3;
/// Payloads up to this many bytes are protected by CRC-17, longer ones by CRC-21.
const FD_CRC17_MAX_BYTES: usize = 16;

/// A frame's length in bit times, split by the bit rate each bit is sent at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PhaseBits {
    /// Bits sent at the nominal (arbitration) bit rate: every bit of a classic frame, and of a
    /// CAN FD frame without BRS.
    pub nominal: u32,
    /// Bits sent at the data bit rate: the data phase of a CAN FD frame with BRS (ESI through
    /// the CRC delimiter); zero for any other frame.
    pub data: u32,
}

impl PhaseBits {
    /// All bits, whatever their rate.
    pub fn total(self) -> u32 {
        self.nominal + self.data
    }
}

/// The number of bits from start-of-frame through the CRC of a classic frame, before stuffing.
fn stuffable_bits(frame: &CanFrame) -> u32 {
    let data_bits = 8 * frame.len() as u32;
    if frame.is_extended() {
        54 + data_bits
    } else {
        34 + data_bits
    }
}

/// The frame's length in bit times under the given stuffing policy, whatever rate its bits
/// are sent at (for a CAN FD frame, [`phase_bits`] splits them by rate).
pub fn frame_bits(frame: &CanFrame, policy: StuffingPolicy) -> u32 {
    if frame.is_fd() {
        return fd_phase_bits(frame, policy).total();
    }
    let stuffable = stuffable_bits(frame);
    let stuff = match policy {
        StuffingPolicy::None => 0,
        StuffingPolicy::WorstCase => (stuffable - 1) / 4,
        StuffingPolicy::Exact => count_stuff_bits(&unstuffed_bits(frame)),
    };
    stuffable + stuff + UNSTUFFED_TAIL_BITS
}

/// The frame's length in bit times under the given stuffing policy, split by the rate the
/// bits are sent at (see the module documentation for the CAN FD figures).
pub fn phase_bits(frame: &CanFrame, policy: StuffingPolicy) -> PhaseBits {
    if frame.is_fd() {
        fd_phase_bits(frame, policy)
    } else {
        PhaseBits {
            nominal: frame_bits(frame, policy),
            data: 0,
        }
    }
}

/// How long the frame occupies the wire at `nominal_bps`, its data phase (a CAN FD frame
/// with BRS) at `data_bps`. A zero rate is treated as 1 bit/s.
pub fn frame_duration(
    frame: &CanFrame,
    policy: StuffingPolicy,
    nominal_bps: u32,
    data_bps: u32,
) -> Duration {
    phases_duration(phase_bits(frame, policy), nominal_bps, data_bps)
}

/// The time `bits` take, nominal bits at `nominal_bps` and data-phase bits at `data_bps`
/// (a zero rate is treated as 1 bit/s), rounded down to the nanosecond once.
pub fn phases_duration(bits: PhaseBits, nominal_bps: u32, data_bps: u32) -> Duration {
    let nominal_bps = u128::from(nominal_bps.max(1));
    let data_bps = u128::from(data_bps.max(1));
    let numerator =
        1_000_000_000 * (u128::from(bits.nominal) * data_bps + u128::from(bits.data) * nominal_bps);
    let nanos = numerator / (nominal_bps * data_bps);
    Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX))
}

/// The time `bits` bit times take at `bitrate_bps` (a zero bitrate is treated as 1 bit/s).
pub fn bits_duration(bits: u32, bitrate_bps: u32) -> Duration {
    let nanos = u64::from(bits) * 1_000_000_000 / u64::from(bitrate_bps.max(1));
    Duration::from_nanos(nanos)
}

/// The length of a CAN FD frame, by phase.
fn fd_phase_bits(frame: &CanFrame, policy: StuffingPolicy) -> PhaseBits {
    let arbitration = if frame.is_extended() {
        FD_ARBITRATION_BITS_EXTENDED
    } else {
        FD_ARBITRATION_BITS_BASE
    };
    // ESI, DLC, data: the rest of the dynamically stuffed region.
    let control_and_data = 1 + 4 + 8 * frame.len() as u32;
    let crc = if frame.len() <= FD_CRC17_MAX_BYTES {
        17
    } else {
        21
    };
    let stuff_count: u32 = 4;
    let fixed_stuff = (stuff_count + crc).div_ceil(4);
    let crc_field = stuff_count + crc + fixed_stuff + 1; // + CRC delimiter
    let (stuff_nominal, stuff_data) = match policy {
        StuffingPolicy::None => (0, 0),
        StuffingPolicy::WorstCase => {
            // A stuff bit can follow the 5th bit, then every 4th: after bit 5 + 4k. Those
            // after bits up to `arbitration - 1` are sent before the switch.
            let all = (arbitration + control_and_data - 1) / 4;
            let before = (arbitration - 2) / 4;
            (before, all - before)
        }
        StuffingPolicy::Exact => {
            let bits = unstuffed_bits(frame);
            count_stuff_bits_split(&bits, arbitration as usize)
        }
    };
    let nominal = arbitration + stuff_nominal + FD_TAIL_BITS;
    let data = control_and_data + stuff_data + crc_field;
    if frame.brs() {
        PhaseBits { nominal, data }
    } else {
        PhaseBits {
            nominal: nominal + data,
            data: 0,
        }
    }
}

fn push_bits(bits: &mut Vec<bool>, value: u32, width: u32) {
    for shift in (0..width).rev() {
        bits.push((value >> shift) & 1 == 1);
    }
}

/// The bit sequence the transmitter sends before stuffing (`true` = recessive 1), data frames
/// only. A classic frame: start-of-frame through the CRC (RTR dominant). A CAN FD frame:
/// start-of-frame through the last data bit, the region of dynamic stuffing (the CRC field of a
/// CAN FD frame has fixed stuff bits, and its CRC covers the stuff bits too).
pub fn unstuffed_bits(frame: &CanFrame) -> Vec<bool> {
    let fd = frame.is_fd();
    let mut bits = Vec::with_capacity(stuffable_bits(frame) as usize + 8);
    bits.push(false); // start of frame
    match frame.id() {
        CanId::Standard(id) => {
            push_bits(&mut bits, u32::from(id), 11);
            bits.push(false); // RTR: data frame (RRS in CAN FD, always dominant)
            bits.push(false); // IDE: standard format
        }
        CanId::Extended(id) => {
            push_bits(&mut bits, id >> 18, 11);
            bits.push(true); // SRR, always recessive
            bits.push(true); // IDE: extended format
            push_bits(&mut bits, id & 0x3_FFFF, 18);
            bits.push(false); // RTR: data frame (RRS in CAN FD, always dominant)
            if !fd {
                bits.push(false); // r1
            }
        }
    }
    if fd {
        bits.push(true); // FDF: CAN FD format
        bits.push(false); // res
        bits.push(frame.brs());
        bits.push(frame.esi());
    } else {
        bits.push(false); // r0
    }
    push_bits(&mut bits, u32::from(frame.dlc()), 4);
    for &byte in frame.data() {
        push_bits(&mut bits, u32::from(byte), 8);
    }
    if !fd {
        let crc = crc15(&bits);
        push_bits(&mut bits, u32::from(crc), 15);
    }
    bits
}
/// CAN's 15-bit CRC (generator 0x4599, initial value 0) over a bit sequence.
pub fn crc15(bits: &[bool]) -> u16 {
    let mut crc: u16 = 0;
    for &bit in bits {
        let feedback = bit ^ ((crc >> 14) & 1 == 1);
        crc = (crc << 1) & 0x7FFF;
        if feedback {
            crc ^= 0x4599;
        }
    }
    crc
}

/// How many stuff bits a transmitter inserts into `bits`: after five consecutive equal bits it
/// sends one complementary bit, which itself starts the next run.
pub fn count_stuff_bits(bits: &[bool]) -> u32 {
    let mut stuffed = 0;
    let mut previous: Option<bool> = None;
    let mut run = 0u32;
    for &bit in bits {
        if previous == Some(bit) {
            run += 1;
        } else {
            previous = Some(bit);
            run = 1;
        }
        if run == 5 {
            stuffed += 1;
            previous = Some(!bit);
            run = 1;
        }
    }
    stuffed
}

/// [`count_stuff_bits`], split into the stuff bits that follow one of the first `split` bits
/// but the last of them, and the rest: a stuff bit after bit `split` (the BRS bit of a CAN FD
/// frame) is sent after the switch to the data rate.
fn count_stuff_bits_split(bits: &[bool], split: usize) -> (u32, u32) {
    let mut before = 0;
    let mut after = 0;
    let mut previous: Option<bool> = None;
    let mut run = 0u32;
    for (index, &bit) in bits.iter().enumerate() {
        if previous == Some(bit) {
            run += 1;
        } else {
            previous = Some(bit);
            run = 1;
        }
        if run == 5 {
            if index + 1 < split {
                before += 1;
            } else {
                after += 1;
            }
            previous = Some(!bit);
            run = 1;
        }
    }
    (before, after)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn frame(extended: bool, id: u32, data: &[u8]) -> CanFrame {
        if extended {
            CanFrame::extended(id, data).unwrap()
        } else {
            CanFrame::standard(id as u16, data).unwrap()
        }
    }

    #[test]
    fn lengths_without_and_with_worst_case_stuffing_match_the_textbook_formulas() {
        for n in 0..=8usize {
            let data = vec![0x55; n];
            let sff = frame(false, 0x2A1, &data);
            let eff = frame(true, 0x0200_FD01, &data);
            let n = n as u32;
            assert_eq!(frame_bits(&sff, StuffingPolicy::None), 47 + 8 * n);
            assert_eq!(frame_bits(&sff, StuffingPolicy::WorstCase), 55 + 10 * n);
            assert_eq!(frame_bits(&eff, StuffingPolicy::None), 67 + 8 * n);
            assert_eq!(frame_bits(&eff, StuffingPolicy::WorstCase), 80 + 10 * n);
        }
        let full = frame(false, 0x100, &[0; 8]);
        assert_eq!(frame_bits(&full, StuffingPolicy::None), 111);
        assert_eq!(frame_bits(&full, StuffingPolicy::WorstCase), 135);
    }

    #[test]
    fn crc_residue_of_message_plus_crc_is_zero() {
        let bits = unstuffed_bits(&frame(false, 0x123, &[0xDE, 0xAD, 0xBE, 0xEF]));
        assert_eq!(crc15(&bits), 0);
        let bits = unstuffed_bits(&frame(true, 0x1234_5678, &[1, 2, 3]));
        assert_eq!(crc15(&bits), 0);
    }

    #[test]
    fn stuffing_counts_runs_including_stuff_bits() {
        // Five zeros need one stuff bit; the stuff bit (1) starts a new run.
        assert_eq!(count_stuff_bits(&[false; 5]), 1);
        assert_eq!(count_stuff_bits(&[false; 4]), 0);
        // 00000 (1) 0000 -> the stuffed 1 and the next four zeros make no new run of five.
        assert_eq!(count_stuff_bits(&[false; 9]), 1);
        assert_eq!(count_stuff_bits(&[false; 10]), 2);
        // 00000 (1) 1111 -> the stuff bit and four ones make a run of five ones.
        let mut bits = vec![false; 5];
        bits.extend([true; 4]);
        assert_eq!(count_stuff_bits(&bits), 2);
        let alternating: Vec<bool> = (0..40).map(|i| i % 2 == 0).collect();
        assert_eq!(count_stuff_bits(&alternating), 0);
    }

    #[test]
    fn exact_stuffing_of_an_all_zero_frame() {
        // ID 0, DLC 0: SOF, 11 id bits, RTR, IDE, r0, 4 DLC bits are 19 zeros and the CRC of
        // zeros is zero: 34 zeros, stuffed after every fifth -> 6 stuff bits, 47 + 6 bits.
        let zero = frame(false, 0, &[]);
        assert!(unstuffed_bits(&zero).iter().all(|bit| !bit));
        assert_eq!(frame_bits(&zero, StuffingPolicy::Exact), 53);
    }

    #[test]
    fn exact_stuffing_lies_between_none_and_worst_case() {
        let mut rng = rand::rngs::SmallRng::seed_from_u64(7);
        for _ in 0..2000 {
            let extended = rng.random_bool(0.5);
            let id = if extended {
                rng.random_range(0..=crate::MAX_EXTENDED_ID)
            } else {
                rng.random_range(0..=u32::from(crate::MAX_STANDARD_ID))
            };
            let len = rng.random_range(0..=8usize);
            let data: Vec<u8> = (0..len).map(|_| rng.random()).collect();
            let f = frame(extended, id, &data);
            let exact = frame_bits(&f, StuffingPolicy::Exact);
            assert!(exact >= frame_bits(&f, StuffingPolicy::None));
            assert!(exact <= frame_bits(&f, StuffingPolicy::WorstCase), "{f}");
        }
    }

    #[test]
    fn bit_time_scales_with_bitrate() {
        assert_eq!(bits_duration(111, 1_000_000), Duration::from_micros(111));
        assert_eq!(bits_duration(111, 500_000), Duration::from_micros(222));
        assert_eq!(bits_duration(135, 250_000), Duration::from_micros(540));
    }

    fn fd(extended: bool, id: u32, data: &[u8], brs: bool, esi: bool) -> CanFrame {
        let id = if extended {
            CanId::Extended(id)
        } else {
            CanId::Standard(id as u16)
        };
        CanFrame::fd(id, data, crate::FdFlags { brs, esi }).unwrap()
    }

    /// Field by field, without dynamic stuffing: SOF, identifier, RRS, IDE, FDF, res, BRS (17;
    /// 36 with SRR, IDE and the 18-bit extension) and ACK slot, ACK delimiter, EOF, IFS (12)
    /// at the nominal rate; ESI, DLC, data, stuff count (4), CRC (17 / 21), fixed stuff bits
    /// (one before the stuff count and one after every 4 bits: 6 / 7), CRC delimiter at the
    /// data rate.
    #[test]
    fn fd_lengths_without_stuffing_add_up_field_by_field() {
        for &n in &crate::FD_DATA_LENS {
            let data = vec![0x55; n];
            let crc_field = if n <= 16 {
                4 + 17 + 6 + 1
            } else {
                4 + 21 + 7 + 1
            };
            let data_phase = 1 + 4 + 8 * n as u32 + crc_field;
            let sff = fd(false, 0x2A1, &data, true, false);
            let eff = fd(true, 0x0200_FD01, &data, true, false);
            assert_eq!(
                phase_bits(&sff, StuffingPolicy::None),
                PhaseBits {
                    nominal: 1 + 11 + 1 + 1 + 1 + 1 + 1 + 12,
                    data: data_phase
                },
                "{n} bytes"
            );
            assert_eq!(
                phase_bits(&eff, StuffingPolicy::None),
                PhaseBits {
                    nominal: 1 + 11 + 1 + 1 + 18 + 1 + 1 + 1 + 1 + 12,
                    data: data_phase
                },
                "{n} bytes"
            );
            assert_eq!(frame_bits(&sff, StuffingPolicy::None), 29 + data_phase);
            // Without BRS every bit is sent at the nominal rate.
            let slow = fd(false, 0x2A1, &data, false, false);
            assert_eq!(
                phase_bits(&slow, StuffingPolicy::None),
                PhaseBits {
                    nominal: 29 + data_phase,
                    data: 0
                }
            );
        }
        // Classic frames have no data phase.
        let classic = frame(false, 0x100, &[0; 8]);
        assert_eq!(
            phase_bits(&classic, StuffingPolicy::WorstCase),
            PhaseBits {
                nominal: 135,
                data: 0
            }
        );
    }

    #[test]
    fn exact_stuffing_of_all_zero_fd_frames_by_hand() {
        // Id 0, DLC 0, no BRS: SOF, 11 id bits, RRS and IDE are 14 zeros (stuff bits after the
        // 5th and 10th), FDF is 1, then res, BRS, ESI and the DLC are 7 zeros (a stuff bit
        // after the 5th): 3 stuff bits, all at the nominal rate, on 62 bits.
        let slow = fd(false, 0, &[], false, false);
        assert_eq!(
            phase_bits(&slow, StuffingPolicy::Exact),
            PhaseBits {
                nominal: 65,
                data: 0
            }
        );
        // With BRS (a 1 after res) the last run is ESI and the DLC, five zeros: its stuff bit
        // follows the BRS bit, so it is sent at the data rate.
        let fast = fd(false, 0, &[], true, false);
        assert_eq!(
            phase_bits(&fast, StuffingPolicy::Exact),
            PhaseBits {
                nominal: 29 + 2,
                data: 5 + 28 + 1
            }
        );
    }

    #[test]
    fn exact_fd_stuffing_lies_between_none_and_worst_case_in_each_phase() {
        let mut rng = rand::rngs::SmallRng::seed_from_u64(11);
        for _ in 0..2000 {
            let extended = rng.random_bool(0.5);
            let id = if extended {
                rng.random_range(0..=crate::MAX_EXTENDED_ID)
            } else {
                rng.random_range(0..=u32::from(crate::MAX_STANDARD_ID))
            };
            let len = crate::FD_DATA_LENS[rng.random_range(0..16usize)];
            // Mostly sparse bytes, so long runs (and stuff bits) are common.
            let data: Vec<u8> = (0..len)
                .map(|_| {
                    if rng.random_bool(0.7) {
                        0
                    } else {
                        rng.random()
                    }
                })
                .collect();
            let f = fd(extended, id, &data, true, rng.random_bool(0.5));
            let none = phase_bits(&f, StuffingPolicy::None);
            let exact = phase_bits(&f, StuffingPolicy::Exact);
            let worst = phase_bits(&f, StuffingPolicy::WorstCase);
            assert!(
                none.nominal <= exact.nominal && exact.nominal <= worst.nominal,
                "{f}"
            );
            assert!(none.data <= exact.data && exact.data <= worst.data, "{f}");
        }
    }

    /// 64 bytes at 1 Mbit/s nominal and 5 Mbit/s data, counted by hand: 0x55 bytes after an
    /// id of 0x555 never make five equal bits (the longest run is the DLC's 1111), so the
    /// frame is 29 nominal bits (29 µs) and 5 + 512 + 33 data bits (110 µs at 200 ns).
    /// Zero bytes add a stuff bit per five zeros: 512 / 5 = 102 more data bits, 20.4 µs.
    #[test]
    fn a_64_byte_fd_frame_at_1m_5m_takes_its_time() {
        let sparse = fd(false, 0x555, &[0x55; 64], true, false);
        assert_eq!(
            frame_duration(&sparse, StuffingPolicy::Exact, 1_000_000, 5_000_000),
            Duration::from_micros(29) + Duration::from_nanos(550 * 200)
        );
        let zeros = fd(false, 0x555, &[0; 64], true, false);
        assert_eq!(
            frame_duration(&zeros, StuffingPolicy::Exact, 1_000_000, 5_000_000),
            Duration::from_nanos(29_000 + (550 + 102) * 200)
        );
        // Without BRS all 579 bits take the nominal rate; the data rate is not used.
        let slow = fd(false, 0x555, &[0x55; 64], false, false);
        assert_eq!(
            frame_duration(&slow, StuffingPolicy::Exact, 1_000_000, 5_000_000),
            Duration::from_micros(579)
        );
        // Rates that do not divide a second: rounded once, not per phase.
        assert_eq!(
            phases_duration(
                PhaseBits {
                    nominal: 1,
                    data: 1
                },
                3,
                3
            ),
            Duration::from_nanos(666_666_666)
        );
    }
}
