//! How many bit times a classic CAN data frame occupies on the wire.
//!
//! Frame lengths count every bit from start-of-frame through the 3-bit intermission that must
//! follow before the next frame may start, so back-to-back frames are spaced by exactly their
//! length. Without stuffing a standard (11-bit) frame is `47 + 8n` bits and an extended (29-bit)
//! frame `67 + 8n` bits for `n` data bytes. Bit stuffing (a complementary bit after five equal
//! bits) applies from start-of-frame through the CRC: `34 + 8n` bits for standard frames and
//! `54 + 8n` for extended, adding at most `(stuffable - 1) / 4` bits, hence the worst cases
//! `55 + 10n` and `80 + 10n`.

use std::time::Duration;

use crate::CanFrame;

/// Which stuff bits the wire model adds to a frame's length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StuffingPolicy {
    /// No stuff bits: the shortest possible frame (`47 + 8n` / `67 + 8n` bits).
    None,
    /// The maximum number of stuff bits any frame of that format and length can need
    /// (`55 + 10n` / `80 + 10n` bits), the figure bus-load budgets use.
    WorstCase,
    /// The stuff bits this exact frame needs, computed from its bit sequence including the
    /// CRC. Deterministic and the most faithful choice, hence the default.
    #[default]
    Exact,
}

/// Frame bits outside the stuffed region: CRC delimiter, ACK slot and delimiter, 7-bit end of
/// frame and the 3-bit intermission.
const UNSTUFFED_TAIL_BITS: u32 = 1 + 1 + 1 + 7 + 3;

/// The number of bits from start-of-frame through the CRC, before stuffing.
fn stuffable_bits(frame: &CanFrame) -> u32 {
    let data_bits = 8 * frame.len() as u32;
    if frame.is_extended() {
        54 + data_bits
    } else {
        34 + data_bits
    }
}

/// The frame's length in bit times under the given stuffing policy.
pub fn frame_bits(frame: &CanFrame, policy: StuffingPolicy) -> u32 {
    let stuffable = stuffable_bits(frame);
    let stuff = match policy {
        StuffingPolicy::None => 0,
        StuffingPolicy::WorstCase => (stuffable - 1) / 4,
        StuffingPolicy::Exact => count_stuff_bits(&unstuffed_bits(frame)),
    };
    stuffable + stuff + UNSTUFFED_TAIL_BITS
}

/// The time `bits` bit times take at `bitrate_bps` (a zero bitrate is treated as 1 bit/s).
pub fn bits_duration(bits: u32, bitrate_bps: u32) -> Duration {
    let nanos = u64::from(bits) * 1_000_000_000 / u64::from(bitrate_bps.max(1));
    Duration::from_nanos(nanos)
}

fn push_bits(bits: &mut Vec<bool>, value: u32, width: u32) {
    for shift in (0..width).rev() {
        bits.push((value >> shift) & 1 == 1);
    }
}

/// The bit sequence from start-of-frame through the CRC as the transmitter sends it before
/// stuffing (`true` = recessive 1). Data frames only: RTR is dominant.
pub fn unstuffed_bits(frame: &CanFrame) -> Vec<bool> {
    let mut bits = Vec::with_capacity(stuffable_bits(frame) as usize);
    bits.push(false); // start of frame
    match frame.id() {
        crate::CanId::Standard(id) => {
            push_bits(&mut bits, u32::from(id), 11);
            bits.push(false); // RTR: data frame
            bits.push(false); // IDE: standard format
            bits.push(false); // r0
        }
        crate::CanId::Extended(id) => {
            push_bits(&mut bits, id >> 18, 11);
            bits.push(true); // SRR, always recessive
            bits.push(true); // IDE: extended format
            push_bits(&mut bits, id & 0x3_FFFF, 18);
            bits.push(false); // RTR: data frame
            bits.push(false); // r1
            bits.push(false); // r0
        }
    }
    push_bits(&mut bits, frame.len() as u32, 4);
    for &byte in frame.data() {
        push_bits(&mut bits, u32::from(byte), 8);
    }
    let crc = crc15(&bits);
    push_bits(&mut bits, u32::from(crc), 15);
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
}
