//! Names scenarios use for Piper status values and fault flags. Every name comes from the
//! driver's typed enums (one table, in the driver); only `feedback` is the harness's own.

use driver::piper::{
    ActiveMove, ArmStatusCode, CtrlMode, DriverStatus, GripperStatus, MotionStatus,
};

/// Feedback liveness as the driver sees it.
pub const FEEDBACK: [&str; 2] = ["alive", "lost"];

/// Arm status names (0x2A1 byte 1), in code order.
pub fn arm_status_names() -> Vec<&'static str> {
    ArmStatusCode::ALL.iter().filter_map(|c| c.name()).collect()
}

/// Control mode names (0x2A1 byte 0), in code order.
pub fn ctrl_mode_names() -> Vec<&'static str> {
    CtrlMode::ALL.iter().filter_map(|c| c.name()).collect()
}

/// Active MOVE mode names (MIT is `m` whatever its firmware code).
pub fn move_mode_names() -> Vec<&'static str> {
    ActiveMove::ALL.iter().filter_map(|m| m.name()).collect()
}

/// Motion status names.
pub fn motion_names() -> Vec<&'static str> {
    MotionStatus::ALL.iter().filter_map(|m| m.name()).collect()
}

/// Joint driver fault flags (without the enable bit).
pub fn joint_flags() -> Vec<&'static str> {
    DriverStatus::fault_names().collect()
}

/// Gripper fault flags (without the enable and homed bits).
pub fn gripper_flags() -> Vec<&'static str> {
    GripperStatus::fault_names().collect()
}

/// A number written in a scenario (`0x04` or `4`).
fn number(text: &str) -> Option<u8> {
    match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16).ok(),
        None => text.parse::<u8>().ok(),
    }
}

/// Resolve an arm status written as a name or a code (`angle_limit`, `0x04`, `4`) to its
/// canonical name.
pub fn resolve_arm_status(text: &str) -> Option<&'static str> {
    ArmStatusCode::from_name(text)
        .or_else(|| number(text).map(ArmStatusCode::from))
        .and_then(ArmStatusCode::name)
}

/// Resolve a control mode written as a name or a code to its canonical name.
pub fn resolve_ctrl_mode(text: &str) -> Option<&'static str> {
    CtrlMode::from_name(text)
        .or_else(|| number(text).map(CtrlMode::from))
        .and_then(CtrlMode::name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_codes_resolve_through_the_driver_tables() {
        assert_eq!(resolve_arm_status("angle_limit"), Some("angle_limit"));
        assert_eq!(resolve_arm_status("0x04"), Some("angle_limit"));
        assert_eq!(resolve_arm_status("7"), Some("collision"));
        assert_eq!(resolve_arm_status("0x2A"), None);
        assert_eq!(resolve_ctrl_mode("1"), Some("can"));
        assert_eq!(arm_status_names().len(), 16);
        assert_eq!(move_mode_names(), ["p", "j", "l", "c", "m", "cpv"]);
        assert_eq!(motion_names(), ["reached", "moving"]);
        assert!(joint_flags().contains(&"stall") && !joint_flags().contains(&"enabled"));
        assert_eq!(gripper_flags().len(), 6);
    }
}
