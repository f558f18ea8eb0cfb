//! Enumerated wire fields. Every enum keeps values the spec does not define as `Unknown(raw)`
//! instead of failing, so a newer firmware's extra codes never break decoding.

macro_rules! wire_enum {
    ($(#[$meta:meta])* $name:ident { $($(#[$vmeta:meta])* $variant:ident = $value:literal),* $(,)? }) => {
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
            /// True when the value is one the spec defines.
            pub fn is_known(self) -> bool {
                !matches!(self, Self::Unknown(_))
            }
        }
    };
}

wire_enum! {
    /// Control mode (0x2A1 byte 0, 0x151 byte 0).
    CtrlMode {
        /// Standby.
        Standby = 0x00,
        /// CAN command control (the mode open to users).
        CanCommand = 0x01,
        /// Teach (drag) mode.
        Teach = 0x02,
        /// Ethernet control.
        Ethernet = 0x03,
        /// Wi-Fi control.
        Wifi = 0x04,
        /// Remote controller (feedback only).
        Remote = 0x05,
        /// Linkage-teach input: this arm is a leader (feedback only).
        LinkageTeach = 0x06,
        /// Offline trajectory.
        OfflineTrajectory = 0x07,
    }
}

wire_enum! {
    /// Arm status code (0x2A1 byte 1).
    ArmStatusCode {
        /// Normal.
        Normal = 0x00,
        /// Emergency stop.
        EmergencyStop = 0x01,
        /// No inverse-kinematics solution.
        NoIkSolution = 0x02,
        /// Singularity.
        Singularity = 0x03,
        /// Target angle exceeds a joint limit.
        TargetAngleOverLimit = 0x04,
        /// Joint communication error.
        JointCommError = 0x05,
        /// Joint brake not released.
        BrakeNotReleased = 0x06,
        /// Collision.
        Collision = 0x07,
        /// Over-speed during drag teach.
        TeachOverSpeed = 0x08,
        /// Joint status abnormal.
        JointStatusAbnormal = 0x09,
        /// Other error.
        Other = 0x0A,
        /// Teach record.
        TeachRecord = 0x0B,
        /// Teach execute.
        TeachExecute = 0x0C,
        /// Teach pause.
        TeachPause = 0x0D,
        /// Main-board NTC over-temperature.
        MainBoardOverTemp = 0x0E,
        /// Brake-resistor NTC over-temperature.
        BrakeResistorOverTemp = 0x0F,
    }
}

wire_enum! {
    /// MOVE mode (0x151 byte 1, 0x2A1 byte 2). MIT is 0x04 up to S-V1.8-7 and 0x06 from
    /// S-V1.8-8; both decode to a variant so the caller can tell which code the arm used.
    MoveMode {
        /// MOVE P: Cartesian point to point.
        P = 0x00,
        /// MOVE J: joint space.
        J = 0x01,
        /// MOVE L: linear.
        L = 0x02,
        /// MOVE C: circular.
        C = 0x03,
        /// MOVE M: MIT pass-through (firmware up to S-V1.8-7).
        Mit = 0x04,
        /// MOVE CPV: continuous position-velocity.
        Cpv = 0x05,
        /// MIT pass-through code of firmware S-V1.8-8 and later.
        MitV188 = 0x06,
        /// "Leave the move mode unchanged" (only sent, never reported).
        Unchanged = 0xFF,
    }
}

wire_enum! {
    /// Drag-teach status (0x2A1 byte 3) and command (0x150 byte 2).
    TeachStatus {
        /// Off.
        Off = 0x00,
        /// Start recording.
        StartRecord = 0x01,
        /// Stop recording.
        StopRecord = 0x02,
        /// Execute.
        Execute = 0x03,
        /// Pause.
        Pause = 0x04,
        /// Resume.
        Resume = 0x05,
        /// Terminate.
        Terminate = 0x06,
        /// Move to the start point.
        MoveToStart = 0x07,
    }
}

wire_enum! {
    /// Quick e-stop field of 0x150 byte 0.
    EmergencyStop {
        /// No operation.
        None = 0x00,
        /// Quick stop (motors go to damping).
        Stop = 0x01,
        /// Resume / reset.
        Resume = 0x02,
    }
}

wire_enum! {
    /// Offline-trajectory command (0x150 byte 1).
    TrackCommand {
        /// Off.
        Off = 0x00,
        /// Pause the plan.
        Pause = 0x01,
        /// Start or continue.
        Continue = 0x02,
        /// Clear the current trajectory.
        ClearCurrent = 0x03,
        /// Clear all trajectories.
        ClearAll = 0x04,
        /// Get the current plan.
        GetCurrent = 0x05,
        /// Terminate.
        Terminate = 0x06,
        /// Trajectory transfer.
        Transfer = 0x07,
        /// End of transfer.
        TransferEnd = 0x08,
    }
}

wire_enum! {
    /// MIT flag of 0x151 byte 3.
    MitMode {
        /// Position-velocity mode (default).
        PositionVelocity = 0x00,
        /// MIT mode.
        Mit = 0xAD,
        /// Invalid / ignore.
        Ignore = 0xFF,
    }
}

wire_enum! {
    /// Installation position (0x151 byte 5, fw >= V1.5-2).
    InstallPosition {
        /// Leave unchanged.
        Unchanged = 0x00,
        /// Horizontal upright.
        Upright = 0x01,
        /// Side mount, left.
        SideLeft = 0x02,
        /// Side mount, right.
        SideRight = 0x03,
    }
}

wire_enum! {
    /// MOVE C point index (0x158 byte 0).
    MoveCPoint {
        /// Invalid.
        Invalid = 0x00,
        /// Start point.
        Start = 0x01,
        /// Middle point.
        Middle = 0x02,
        /// End point.
        End = 0x03,
    }
}

wire_enum! {
    /// Leader/follower linkage setting (0x470 byte 0).
    LinkageConfig {
        /// No operation.
        None = 0x00,
        /// Become a teach-input (leader) arm.
        Leader = 0xFA,
        /// Become a motion-output (follower) arm.
        Follower = 0xFC,
    }
}

wire_enum! {
    /// CAN id offset of a 0x470 field.
    IdOffset {
        /// No offset (restore).
        None = 0x00,
        /// +0x10.
        Plus10 = 0x10,
        /// +0x20.
        Plus20 = 0x20,
    }
}

wire_enum! {
    /// End-effector payload (0x477 byte 4).
    Payload {
        /// Empty.
        Empty = 0x00,
        /// Half load.
        Half = 0x01,
        /// Full load.
        Full = 0x02,
        /// Invalid / no-op (SDK default).
        NoChange = 0x03,
    }
}

wire_enum! {
    /// Motion status (0x2A1 byte 4).
    MotionStatus {
        /// The target was reached.
        Reached = 0x00,
        /// Moving towards the target.
        Moving = 0x01,
    }
}

wire_enum! {
    /// Acknowledged command in 0x476 byte 0 (the low byte of the set command's id).
    AckedCommand {
        /// Offline-trajectory point on 0x150.
        TrajectoryPoint = 0x50,
        /// 0x474 joint limits / max speed.
        SetJointLimits = 0x74,
        /// 0x475 joint configuration.
        JointConfig = 0x75,
        /// 0x477 parameter settings.
        ParamSettings = 0x77,
        /// 0x479 end-effector vel/acc.
        SetEndParams = 0x79,
        /// 0x47A collision levels.
        SetCollision = 0x7A,
        /// 0x471 motor enable (the spec's doc hints at such an ack).
        MotorEnable = 0x71,
    }
}

macro_rules! bit_flags {
    ($(#[$meta:meta])* $name:ident { $($(#[$bmeta:meta])* $method:ident = $bit:literal),* $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
        pub struct $name(pub u8);

        impl $name {
            $($(#[$bmeta])* pub fn $method(self) -> bool { self.0 & (1 << $bit) != 0 })*
        }
    };
}

bit_flags! {
    /// Gripper status bits (0x2A8 byte 6).
    GripperStatus {
        /// Supply under-voltage.
        under_voltage = 0,
        /// Motor over-temperature.
        motor_over_temp = 1,
        /// Driver over-current.
        over_current = 2,
        /// Driver over-temperature.
        driver_over_temp = 3,
        /// Sensor fault.
        sensor_fault = 4,
        /// Driver error.
        driver_error = 5,
        /// Driver enabled.
        enabled = 6,
        /// Homed (has been zeroed).
        homed = 7,
    }
}

bit_flags! {
    /// Joint driver status bits (0x261-0x266 byte 5).
    DriverStatus {
        /// Supply under-voltage.
        under_voltage = 0,
        /// Motor over-temperature.
        motor_over_temp = 1,
        /// Driver over-current.
        over_current = 2,
        /// Driver over-temperature.
        driver_over_temp = 3,
        /// Collision protection triggered.
        collision = 4,
        /// Driver error.
        driver_error = 5,
        /// Driver enabled.
        enabled = 6,
        /// Stall protection triggered.
        stall = 7,
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
