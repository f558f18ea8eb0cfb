//! Command handling: the MOVE C arc geometry and the timing of the 0x4AF reply.

use bus::CanFrame;
use nalgebra::Isometry3;

use super::path::arc_samples;
use super::settings::FIRMWARE_REPLY_DELAY_MS;
use crate::piper::firmware::Firmware;
use crate::piper::ids;

#[test]
fn arc_passes_through_the_middle_point() {
    let a = Isometry3::translation(0.3, 0.0, 0.2);
    let b = Isometry3::translation(0.2, 0.1, 0.2);
    let c = Isometry3::translation(0.1, 0.0, 0.2);
    let arc = arc_samples(&a, &b, &c).unwrap();
    let near_b = arc
        .iter()
        .map(|p| (p.translation.vector - b.translation.vector).norm())
        .fold(f64::INFINITY, f64::min);
    assert!(near_b < 0.002, "{near_b}");
    assert!((arc.last().unwrap().translation.vector - c.translation.vector).norm() < 1e-9);
    assert!(arc_samples(&a, &Isometry3::translation(0.2, 0.0, 0.2), &c).is_none());
}

/// Ticks until the first 0x4AF reply frame leaves after a query, for a given batching.
fn firmware_reply_ticks(ticks_per_wake: u32) -> (u64, usize) {
    let mut fw = Firmware::new(crate::piper::PiperConfig {
        ticks_per_wake,
        ..crate::piper::PiperConfig::default()
    })
    .unwrap();
    let mut out = Vec::new();
    fw.tick();
    fw.drain_output_into(&mut out);
    let query = CanFrame::standard(ids::FIRMWARE, &[1, 0, 0, 0, 0, 0, 0, 0]).unwrap();
    fw.handle_frame(&query);
    for tick in 1..=100u64 {
        fw.tick();
        out.clear();
        fw.drain_output_into(&mut out);
        let replies = out.iter().filter(|f| f.raw_id() == 0x4AF).count();
        if replies > 0 {
            return (tick, replies);
        }
    }
    panic!("no 0x4AF reply within 100 ticks");
}

#[test]
fn firmware_reply_leaves_a_wake_up_after_the_query_at_the_earliest() {
    // One tick per wake-up: the reply needs FIRMWARE_REPLY_DELAY_MS ticks after the batch
    // of the wake-up that handled the query.
    assert_eq!(firmware_reply_ticks(1), (1 + FIRMWARE_REPLY_DELAY_MS, 11));
    // Five ticks per wake-up (armhil sim piper): the five ticks after the query run at
    // once, in the same wake-up, so the reply must wait past them to be late in real time.
    let (ticks, frames) = firmware_reply_ticks(5);
    assert_eq!(frames, 11);
    assert!(ticks >= 5 + FIRMWARE_REPLY_DELAY_MS, "{ticks}");
}
