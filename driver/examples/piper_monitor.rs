//! Live Piper state monitor over SocketCAN.
//!
//! `cargo run -p armhil-driver --example piper_monitor -- vcan0` (default `can0`). Against the
//! emulator: `armhil sim piper --iface vcan0` in another terminal. Ctrl-C stops.

use std::time::Duration;

#[cfg(target_os = "linux")]
#[tokio::main(flavor = "current_thread")]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    use driver::piper::{PiperBuilder, Timeouts};

    let iface = std::env::args().nth(1).unwrap_or_else(|| "can0".to_owned());
    let timeouts = Timeouts {
        first_feedback: Some(Duration::from_secs(3)),
        ..Timeouts::default()
    };
    let piper = PiperBuilder::interface(&iface)
        .timeouts(timeouts)
        .connect()
        .await?;
    match piper.state().firmware {
        Some(info) => println!(
            "{iface}: {} {} ({})",
            info.node_type, info.software, info.hardware
        ),
        None => println!("{iface}: firmware version unknown"),
    }
    let mut ticker = tokio::time::interval(Duration::from_millis(500));
    loop {
        tokio::select! {
            _ = tokio::signal::ctrl_c() => break,
            _ = ticker.tick() => {}
        }
        let state = piper.state();
        let status = state.arm_status.map(|s| s.value);
        let joints_deg = state.joints_rad().map(|q| q.map(f64::to_degrees));
        let gripper_mm = state.gripper_stroke_m().map(|m| m * 1000.0);
        println!(
            "ok={} {:.0} frames/s | mode={} status={} move={} motion={} | joints(deg)={:?} | gripper(mm)={:?} | enabled={:?}",
            piper.is_ok(),
            state.link.frames_per_s,
            name(status.map(|s| s.ctrl_mode)),
            name(status.map(|s| s.status)),
            name(status.map(|s| s.move_mode)),
            name(status.map(|s| s.motion)),
            joints_deg,
            gripper_mm,
            state.enabled_mask().joints(),
        );
        if let Some(status) = status {
            if !status.angle_limit_exceeded.is_empty() || !status.comm_error.is_empty() {
                println!(
                    "  faults: angle limit {:?}, comm error {:?}",
                    status.angle_limit_exceeded.joints(),
                    status.comm_error.joints()
                );
            }
        }
    }
    piper.disconnect().await;
    Ok(())
}

/// A status value's name from the driver's table, `-` before the first 0x2A1 frame.
#[cfg(target_os = "linux")]
fn name<T: std::fmt::Display>(value: Option<T>) -> String {
    value.map_or_else(|| "-".to_owned(), |v| v.to_string())
}

#[cfg(not(target_os = "linux"))]
fn main() {
    eprintln!("piper_monitor needs SocketCAN (Linux)");
}
