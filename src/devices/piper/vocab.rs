//! Names scenarios use for Piper status values and fault flags (protocol §4.1, §4.4, §4.6).

/// 0x2A1 byte 1 (arm status) values and their scenario names.
pub const ARM_STATUS: [(u8, &str); 16] = [
    (0x00, "normal"),
    (0x01, "estop"),
    (0x02, "no_solution"),
    (0x03, "singularity"),
    (0x04, "angle_limit"),
    (0x05, "joint_comm_error"),
    (0x06, "brake_not_released"),
    (0x07, "collision"),
    (0x08, "drag_over_speed"),
    (0x09, "joint_status_abnormal"),
    (0x0A, "other"),
    (0x0B, "teach_record"),
    (0x0C, "teach_execute"),
    (0x0D, "teach_pause"),
    (0x0E, "main_ntc_over_temp"),
    (0x0F, "brake_ntc_over_temp"),
];

/// 0x2A1 byte 0 (control mode) values and their scenario names.
pub const CTRL_MODE: [(u8, &str); 8] = [
    (0x00, "standby"),
    (0x01, "can"),
    (0x02, "teach"),
    (0x03, "ethernet"),
    (0x04, "wifi"),
    (0x05, "remote"),
    (0x06, "linkage_teach"),
    (0x07, "offline_trajectory"),
];

/// Active MOVE mode names (0x2A1 byte 2; MIT is `m` whatever its firmware code).
pub const MOVE_MODE: [&str; 6] = ["p", "j", "l", "c", "m", "cpv"];

/// Motion status names (0x2A1 byte 4).
pub const MOTION: [&str; 2] = ["reached", "moving"];

/// Feedback liveness as the driver sees it.
pub const FEEDBACK: [&str; 2] = ["alive", "lost"];

/// Joint driver fault flags (0x261‑0x266 byte 5, without the enable bit).
pub const JOINT_FLAGS: [&str; 7] = [
    "under_voltage",
    "motor_over_temp",
    "over_current",
    "driver_over_temp",
    "collision",
    "driver_error",
    "stall",
];

/// Gripper fault flags (0x2A8 byte 6, without the enable and homed bits).
pub const GRIPPER_FLAGS: [&str; 6] = [
    "under_voltage",
    "motor_over_temp",
    "over_current",
    "driver_over_temp",
    "sensor_fault",
    "driver_error",
];

/// The name of a coded value, or `unknown(0xNN)`.
pub fn name_of(table: &[(u8, &'static str)], code: u8) -> String {
    table.iter().find(|(c, _)| *c == code).map_or_else(
        || format!("unknown(0x{code:02X})"),
        |(_, n)| (*n).to_owned(),
    )
}

/// Resolve a name or a number written in a scenario (`angle_limit`, `0x04`, `4`) to the
/// canonical name.
pub fn resolve(table: &[(u8, &'static str)], text: &str) -> Option<&'static str> {
    if let Some((_, name)) = table.iter().find(|(_, n)| *n == text) {
        return Some(name);
    }
    let number = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16).ok()?,
        None => text.parse::<u8>().ok()?,
    };
    table.iter().find(|(c, _)| *c == number).map(|(_, n)| *n)
}
