//! Enumerated wire fields. Every enum keeps values the spec does not define as `Unknown(raw)`
//! instead of failing, so a newer firmware's extra codes never break decoding.

macro_rules! wire_enum {
    ($(#[$meta:meta])* $name:ident { $($(#[$vmeta:meta])* $variant:ident = $value:literal => $label:literal),* $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
        pub enum $name {
            $($(#[$vmeta])* $variant,)*
            /// A value the spec does not define, kept as received.
            Unknown(u8),
        }

        impl From<u8> for $name {
            fn from(raw: u8) -> Self {
                match raw {
                    $($value => Self::$variant,)*
                    other => Self::Unknown(other),
                }
            }
        }

        impl From<$name> for u8 {
            fn from(value: $name) -> u8 {
                match value {
                    $($name::$variant => $value,)*
                    $name::Unknown(raw) => raw,
                }
            }
        }

        impl $name {
            /// Every defined value, in wire order (the one table of names and codes).
            pub const ALL: &'static [Self] = &[$(Self::$variant),*];

            /// True when the value is one the spec defines.
            pub fn is_known(self) -> bool {
                !matches!(self, Self::Unknown(_))
            }

            /// The value's name (`None` for [`Self::Unknown`]).
            pub fn name(self) -> Option<&'static str> {
                match self {
                    $(Self::$variant => Some($label),)*
                    Self::Unknown(_) => None,
                }
            }

            /// The defined value called `name`.
            pub fn from_name(name: &str) -> Option<Self> {
                Self::ALL.iter().copied().find(|v| v.name() == Some(name))
            }
        }

        impl std::fmt::Display for $name {
            /// The name, or `unknown(0xNN)` for a value the spec does not define.
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                match self.name() {
                    Some(name) => f.write_str(name),
                    None => write!(f, "unknown(0x{:02X})", u8::from(*self)),
                }
            }
        }
    };
}

wire_enum! {
    /// Control mode (0x2A1 byte 0, 0x151 byte 0).
    CtrlMode {
        /// Standby.
        Standby = 0x00 => "standby",
        /// CAN command control (the mode open to users).
        CanCommand = 0x01 => "can",
        /// Teach (drag) mode.
        Teach = 0x02 => "teach",
        /// Ethernet control.
        Ethernet = 0x03 => "ethernet",
        /// Wi-Fi control.
        Wifi = 0x04 => "wifi",
        /// Remote controller (feedback only).
        Remote = 0x05 => "remote",
        /// Linkage-teach input: this arm is a leader (feedback only).
        LinkageTeach = 0x06 => "linkage_teach",
        /// Offline trajectory.
        OfflineTrajectory = 0x07 => "offline_trajectory",
    }
}

wire_enum! {
    /// Arm status code (0x2A1 byte 1).
    ArmStatusCode {
        /// Normal.
        Normal = 0x00 => "normal",
        /// Emergency stop.
        EmergencyStop = 0x01 => "estop",
        /// No inverse-kinematics solution.
        NoIkSolution = 0x02 => "no_solution",
        /// Singularity.
        Singularity = 0x03 => "singularity",
        /// Target angle exceeds a joint limit.
        TargetAngleOverLimit = 0x04 => "angle_limit",
        /// Joint communication error.
        JointCommError = 0x05 => "joint_comm_error",
        /// Joint brake not released.
        BrakeNotReleased = 0x06 => "brake_not_released",
        /// Collision.
        Collision = 0x07 => "collision",
        /// Over-speed during drag teach.
        TeachOverSpeed = 0x08 => "drag_over_speed",
        /// Joint status abnormal.
        JointStatusAbnormal = 0x09 => "joint_status_abnormal",
        /// Other error.
        Other = 0x0A => "other",
        /// Teach record.
        TeachRecord = 0x0B => "teach_record",
        /// Teach execute.
        TeachExecute = 0x0C => "teach_execute",
        /// Teach pause.
        TeachPause = 0x0D => "teach_pause",
        /// Main-board NTC over-temperature.
        MainBoardOverTemp = 0x0E => "main_ntc_over_temp",
        /// Brake-resistor NTC over-temperature.
        BrakeResistorOverTemp = 0x0F => "brake_ntc_over_temp",
    }
}

wire_enum! {
    /// MOVE mode (0x151 byte 1, 0x2A1 byte 2). MIT is 0x04 up to S-V1.8-7 and 0x06 from
    /// S-V1.8-8; both decode to a variant so the caller can tell which code the arm used.
    MoveMode {
        /// MOVE P: Cartesian point to point.
        P = 0x00 => "p",
        /// MOVE J: joint space.
        J = 0x01 => "j",
        /// MOVE L: linear.
        L = 0x02 => "l",
        /// MOVE C: circular.
        C = 0x03 => "c",
        /// MOVE M: MIT pass-through (firmware up to S-V1.8-7).
        Mit = 0x04 => "m",
        /// MOVE CPV: continuous position-velocity.
        Cpv = 0x05 => "cpv",
        /// MIT pass-through code of firmware S-V1.8-8 and later.
        MitV188 = 0x06 => "m_v188",
        /// "Leave the move mode unchanged" (only sent, never reported).
        Unchanged = 0xFF => "unchanged",
    }
}

wire_enum! {
    /// Drag-teach status (0x2A1 byte 3) and command (0x150 byte 2).
    TeachStatus {
        /// Off.
        Off = 0x00 => "off",
        /// Start recording.
        StartRecord = 0x01 => "start_record",
        /// Stop recording.
        StopRecord = 0x02 => "stop_record",
        /// Execute.
        Execute = 0x03 => "execute",
        /// Pause.
        Pause = 0x04 => "pause",
        /// Resume.
        Resume = 0x05 => "resume",
        /// Terminate.
        Terminate = 0x06 => "terminate",
        /// Move to the start point.
        MoveToStart = 0x07 => "move_to_start",
    }
}

wire_enum! {
    /// Quick e-stop field of 0x150 byte 0.
    EmergencyStop {
        /// No operation.
        None = 0x00 => "none",
        /// Quick stop (motors go to damping).
        Stop = 0x01 => "stop",
        /// Resume / reset.
        Resume = 0x02 => "resume",
    }
}

wire_enum! {
    /// Offline-trajectory command (0x150 byte 1).
    TrackCommand {
        /// Off.
        Off = 0x00 => "off",
        /// Pause the plan.
        Pause = 0x01 => "pause",
        /// Start or continue.
        Continue = 0x02 => "continue",
        /// Clear the current trajectory.
        ClearCurrent = 0x03 => "clear_current",
        /// Clear all trajectories.
        ClearAll = 0x04 => "clear_all",
        /// Get the current plan.
        GetCurrent = 0x05 => "get_current",
        /// Terminate.
        Terminate = 0x06 => "terminate",
        /// Trajectory transfer.
        Transfer = 0x07 => "transfer",
        /// End of transfer.
        TransferEnd = 0x08 => "transfer_end",
    }
}

wire_enum! {
    /// MIT flag of 0x151 byte 3.
    MitMode {
        /// Position-velocity mode (default).
        PositionVelocity = 0x00 => "position_velocity",
        /// MIT mode.
        Mit = 0xAD => "mit",
        /// Invalid / ignore.
        Ignore = 0xFF => "ignore",
    }
}

wire_enum! {
    /// Installation position (0x151 byte 5, fw >= V1.5-2).
    InstallPosition {
        /// Leave unchanged.
        Unchanged = 0x00 => "unchanged",
        /// Horizontal upright.
        Upright = 0x01 => "upright",
        /// Side mount, left.
        SideLeft = 0x02 => "left",
        /// Side mount, right.
        SideRight = 0x03 => "right",
    }
}

wire_enum! {
    /// MOVE C point index (0x158 byte 0).
    MoveCPoint {
        /// Invalid.
        Invalid = 0x00 => "invalid",
        /// Start point.
        Start = 0x01 => "start",
        /// Middle point.
        Middle = 0x02 => "middle",
        /// End point.
        End = 0x03 => "end",
    }
}

wire_enum! {
    /// Leader/follower linkage setting (0x470 byte 0).
    LinkageConfig {
        /// No operation.
        None = 0x00 => "none",
        /// Become a teach-input (leader) arm.
        Leader = 0xFA => "leader",
        /// Become a motion-output (follower) arm.
        Follower = 0xFC => "follower",
    }
}

wire_enum! {
    /// CAN id offset of a 0x470 field.
    IdOffset {
        /// No offset (restore).
        None = 0x00 => "none",
        /// +0x10.
        Plus10 = 0x10 => "plus_0x10",
        /// +0x20.
        Plus20 = 0x20 => "plus_0x20",
    }
}

wire_enum! {
    /// End-effector payload (0x477 byte 4).
    Payload {
        /// Empty.
        Empty = 0x00 => "empty",
        /// Half load.
        Half = 0x01 => "half",
        /// Full load.
        Full = 0x02 => "full",
        /// Invalid / no-op (SDK default).
        NoChange = 0x03 => "no_change",
    }
}

wire_enum! {
    /// Motion status (0x2A1 byte 4).
    MotionStatus {
        /// The target was reached.
        Reached = 0x00 => "reached",
        /// Moving towards the target.
        Moving = 0x01 => "moving",
    }
}

wire_enum! {
    /// Acknowledged command in 0x476 byte 0 (the low byte of the set command's id).
    AckedCommand {
        /// Offline-trajectory point on 0x150.
        TrajectoryPoint = 0x50 => "trajectory_point",
        /// 0x474 joint limits / max speed.
        SetJointLimits = 0x74 => "set_joint_limits",
        /// 0x475 joint configuration.
        JointConfig = 0x75 => "joint_config",
        /// 0x477 parameter settings.
        ParamSettings = 0x77 => "param_settings",
        /// 0x479 end-effector vel/acc.
        SetEndParams = 0x79 => "set_end_params",
        /// 0x47A collision levels.
        SetCollision = 0x7A => "set_collision",
        /// 0x471 motor enable (the spec's doc hints at such an ack).
        MotorEnable = 0x71 => "motor_enable",
    }
}

macro_rules! bit_flags {
    ($(#[$meta:meta])* $name:ident { $($(#[$bmeta:meta])* $kind:ident $method:ident = $bit:literal),* $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
        pub struct $name(pub u8);

        impl $name {
            /// Every bit: (bit number, name, true for a fault flag), the one table of names.
            pub const BITS: &'static [(u8, &'static str, bool)] =
                &[$(($bit, stringify!($method), bit_flags!(@fault $kind))),*];

            $($(#[$bmeta])* pub fn $method(self) -> bool { self.0 & (1 << $bit) != 0 })*

            /// Names of the set bits, in bit order.
            pub fn names(self) -> Vec<&'static str> {
                Self::BITS
                    .iter()
                    .filter(|(bit, _, _)| self.0 & (1 << bit) != 0)
                    .map(|(_, name, _)| *name)
                    .collect()
            }

            /// Names of the set fault bits (not the state bits such as `enabled`), in bit order.
            pub fn faults(self) -> Vec<&'static str> {
                Self::BITS
                    .iter()
                    .filter(|(bit, _, fault)| *fault && self.0 & (1 << bit) != 0)
                    .map(|(_, name, _)| *name)
                    .collect()
            }

            /// Names of every fault bit, in bit order.
            pub fn fault_names() -> impl Iterator<Item = &'static str> {
                Self::BITS.iter().filter(|(_, _, fault)| *fault).map(|(_, name, _)| *name)
            }
        }
    };
    (@fault fault) => { true };
    (@fault state) => { false };
}

bit_flags! {
    /// Gripper status bits (0x2A8 byte 6).
    GripperStatus {
        /// Supply under-voltage.
        fault under_voltage = 0,
        /// Motor over-temperature.
        fault motor_over_temp = 1,
        /// Driver over-current.
        fault over_current = 2,
        /// Driver over-temperature.
        fault driver_over_temp = 3,
        /// Sensor fault.
        fault sensor_fault = 4,
        /// Driver error.
        fault driver_error = 5,
        /// Driver enabled.
        state enabled = 6,
        /// Homed (has been zeroed).
        state homed = 7,
    }
}

bit_flags! {
    /// Joint driver status bits (0x261-0x266 byte 5).
    DriverStatus {
        /// Supply under-voltage.
        fault under_voltage = 0,
        /// Motor over-temperature.
        fault motor_over_temp = 1,
        /// Driver over-current.
        fault over_current = 2,
        /// Driver over-temperature.
        fault driver_over_temp = 3,
        /// Collision protection triggered.
        fault collision = 4,
        /// Driver error.
        fault driver_error = 5,
        /// Driver enabled.
        state enabled = 6,
        /// Stall protection triggered.
        fault stall = 7,
    }
}

/// One bit per joint (bit 0 = joint 1 … bit 5 = joint 6), as in the 0x2A1 fault bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
pub struct JointMask(pub u8);

impl JointMask {
    /// Mask with joints 1–6 all set.
    pub const ALL: JointMask = JointMask(0b11_1111);

    /// True when joint `joint` (1–6) is set.
    pub fn contains(self, joint: u8) -> bool {
        (1..=6).contains(&joint) && self.0 & (1 << (joint - 1)) != 0
    }

    /// The set joints in ascending order (1–6).
    pub fn joints(self) -> Vec<u8> {
        (1..=6).filter(|joint| self.contains(*joint)).collect()
    }

    /// True when no joint bit is set.
    pub fn is_empty(self) -> bool {
        self.0 & 0b11_1111 == 0
    }
}
