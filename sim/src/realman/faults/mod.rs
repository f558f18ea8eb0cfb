//! Faults a scenario can schedule on a running Realman emulator, and how each shows on the wire.
//!
//! | Fault (`name()`) | Wire effect | Cleared by |
//! |---|---|---|
//! | `connection_drop` | every TCP connection (or the one from an IP) is closed by the controller | — (one-shot; clients reconnect) |
//! | `reply_delay` | every TCP reply is written `delay_ms` late (events too) | `clear` |
//! | `malformed_reply` | the next `count` replies are cut in half (still CRLF-terminated) | after `count` replies, or `clear` |
//! | `udp_loss` | each push datagram is dropped with probability `permille`/1000 (seeded) | `clear` |
//! | `udp_reorder` | datagrams are sent in swapped pairs | `clear` |
//! | `joint_error` | joint `err_flag`/`joint_err_code` = `code`, error 0x1001 in `err`, that joint disabled, motion aborts with `trajectory_state:false` | `clear_system_err` + `set_joint_clear_err`, or `clear` |
//! | `power_loss` | arm power off: joints disabled, brakes on, motion aborts (`trajectory_state:false`), `power_state` 0 | `set_arm_power` 1, or `clear` |
//! | `collision` | error 0x100D (4109), arm stops on its path, motion aborts | `clear_system_err`, or `clear` |
//! | `estop` | emergency stop: brakes on, joints disabled, error 0x1010, motion aborts; moves refused | `clear` then `clear_system_err` |
//! | `gripper_fault` | gripper `error` bit (default stall), error 0x2001, gripper commands answer `state:false` | `clear` |

mod target;

pub use target::{fault_table, RealmanFaultCommand};

use std::net::IpAddr;

use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};

/// A fault injected into a running emulator. Joints are numbered from 1 as on the wire.
#[derive(Debug, Clone, PartialEq)]
pub enum RealmanFault {
    /// The controller closes TCP connections (all of them, or those from `peer_ip`).
    ConnectionDrop {
        /// Only connections from this IP; `None` = all.
        peer_ip: Option<IpAddr>,
    },
    /// Replies and events are written this late.
    ReplyDelay {
        /// Delay, ms.
        delay_ms: u64,
    },
    /// The next replies are truncated mid-object.
    MalformedReply {
        /// How many replies.
        count: u32,
    },
    /// UDP push datagrams are lost at random (seeded, reproducible).
    UdpLoss {
        /// Loss probability in 1/1000.
        permille: u16,
    },
    /// UDP push datagrams arrive in swapped pairs.
    UdpReorder,
    /// A joint reports an error code (any joint error bit of docs/protocols/realman.md §12).
    JointError {
        /// Joint, 1-based.
        joint: u8,
        /// Joint error bits (e.g. 0x0008 over-temperature).
        code: u16,
    },
    /// Arm power lost.
    PowerLoss,
    /// Collision detected (0x100D).
    Collision,
    /// Emergency stop pressed.
    EStop,
    /// Gripper fault (error bits, 0x2001).
    GripperFault {
        /// Gripper `error` bits (bit0 stall, bit1 over-temp, bit2 over-current, bit3 driver,
        /// bit4 comms).
        bits: u8,
    },
}

/// Which fault to clear: [`RealmanFault`] without its values. Its name (scenario files,
/// traces, the web view, Python) is its variant's in snake_case.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    strum::EnumString,
    strum::IntoStaticStr,
    strum::EnumIter,
)]
#[strum(serialize_all = "snake_case")]
pub enum RealmanFaultKind {
    /// See [`RealmanFault::ConnectionDrop`].
    ConnectionDrop,
    /// See [`RealmanFault::ReplyDelay`].
    ReplyDelay,
    /// See [`RealmanFault::MalformedReply`].
    MalformedReply,
    /// See [`RealmanFault::UdpLoss`].
    UdpLoss,
    /// See [`RealmanFault::UdpReorder`].
    UdpReorder,
    /// See [`RealmanFault::JointError`].
    JointError,
    /// See [`RealmanFault::PowerLoss`].
    PowerLoss,
    /// See [`RealmanFault::Collision`].
    Collision,
    /// See [`RealmanFault::EStop`].
    #[strum(serialize = "estop")]
    EStop,
    /// See [`RealmanFault::GripperFault`].
    GripperFault,
}

impl RealmanFaultKind {
    /// Every kind, in a stable order.
    pub const ALL: [Self; 10] = [
        Self::ConnectionDrop,
        Self::ReplyDelay,
        Self::MalformedReply,
        Self::UdpLoss,
        Self::UdpReorder,
        Self::JointError,
        Self::PowerLoss,
        Self::Collision,
        Self::EStop,
        Self::GripperFault,
    ];

    /// Stable snake_case name (scenario files, traces).
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// One-line description of the wire effect.
    pub fn description(self) -> &'static str {
        match self {
            Self::ConnectionDrop => "the controller closes TCP connections; clients must reconnect",
            Self::ReplyDelay => "every TCP reply and event is written late (e.g. 600 ms, beyond the SDK's 500 ms timeout)",
            Self::MalformedReply => "the next replies are truncated mid-object (CRLF-terminated)",
            Self::UdpLoss => "realtime push datagrams are dropped at random (seeded)",
            Self::UdpReorder => "realtime push datagrams arrive in swapped pairs",
            Self::JointError => "a joint reports an error code; error 0x1001, joint disabled, motion aborted",
            Self::PowerLoss => "arm power lost: joints disabled, brakes on, motion aborted, power_state 0",
            Self::Collision => "collision detected (0x100D): the arm stops, motion aborted",
            Self::EStop => "emergency stop: brakes on, joints disabled, motion aborted, moves refused",
            Self::GripperFault => "gripper error bits set (0x2001); gripper commands answer false",
        }
    }

    /// The kind with this name.
    pub fn from_name(name: &str) -> Option<Self> {
        name.parse().ok()
    }

    /// The kind called `name`, or an error listing the known names.
    pub fn named(name: &str) -> Result<Self, FaultArgError> {
        crate::fault_args::named("Realman", name, &Self::ALL, Self::name)
    }
}

/// One integer parameter of a fault: its name (as in scenario files, the web view and
/// Python) and the values the emulator accepts. The one table every way of building a
/// [`RealmanFault`] checks against ([`RealmanFault::check`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RealmanFaultParam {
    /// Its name.
    pub name: &'static str,
    /// What it sets.
    pub description: &'static str,
    /// Smallest value accepted.
    pub min: u64,
    /// Largest value accepted.
    pub max: u64,
}

impl RealmanFaultParam {
    /// `value` if it is within `min..=max`, else why not.
    pub fn check(&self, value: u64) -> Result<u64, FaultError> {
        if (self.min..=self.max).contains(&value) {
            Ok(value)
        } else {
            Err(FaultError::OutOfRange {
                param: self.name,
                value,
                min: self.min,
                max: self.max,
            })
        }
    }
}

/// A reply delay of at most a minute: 120 times the vendor SDK's 500 ms timeout, so every
/// timeout test fits; a longer one only stalls the run.
const DELAY_MS: RealmanFaultParam = RealmanFaultParam {
    name: "delay_ms",
    description: "reply delay, ms",
    min: 1,
    max: 60_000,
};
/// Truncated replies: a thousand is more than any recovery test sends.
const COUNT: RealmanFaultParam = RealmanFaultParam {
    name: "count",
    description: "replies truncated",
    min: 1,
    max: 1000,
};
/// A probability in 1/1000.
const PERMILLE: RealmanFaultParam = RealmanFaultParam {
    name: "permille",
    description: "loss probability, 1/1000",
    min: 0,
    max: 1000,
};
/// Joints of the largest arm (RM75: 7); the controller checks the arm's own count.
const JOINT: RealmanFaultParam = RealmanFaultParam {
    name: "joint",
    description: "joint, 1-based",
    min: 1,
    max: 7,
};
/// The 16-bit joint error word; 0 is no error.
const CODE: RealmanFaultParam = RealmanFaultParam {
    name: "code",
    description: "joint error bits (e.g. 8 = over-temperature)",
    min: 1,
    max: 0xFFFF,
};
/// The gripper's error byte; 0 is no error.
const BITS: RealmanFaultParam = RealmanFaultParam {
    name: "bits",
    description: "gripper error bits",
    min: 1,
    max: 0xFF,
};

impl RealmanFaultKind {
    /// Its integer parameters, all required, in the order the web view lists them.
    pub fn params(self) -> &'static [RealmanFaultParam] {
        match self {
            Self::ReplyDelay => &[DELAY_MS],
            Self::MalformedReply => &[COUNT],
            Self::UdpLoss => &[PERMILLE],
            Self::JointError => &[JOINT, CODE],
            Self::GripperFault => &[BITS],
            Self::ConnectionDrop
            | Self::UdpReorder
            | Self::PowerLoss
            | Self::Collision
            | Self::EStop => &[],
        }
    }

    /// The parameter called `name`, if this kind takes one.
    pub fn param(self, name: &str) -> Option<&'static RealmanFaultParam> {
        self.params().iter().find(|p| p.name == name)
    }
}

impl RealmanFault {
    /// Its integer values with their parameters' names.
    pub fn values(&self) -> Vec<(&'static str, u64)> {
        match *self {
            Self::ReplyDelay { delay_ms } => vec![("delay_ms", delay_ms)],
            Self::MalformedReply { count } => vec![("count", u64::from(count))],
            Self::UdpLoss { permille } => vec![("permille", u64::from(permille))],
            Self::JointError { joint, code } => {
                vec![("joint", u64::from(joint)), ("code", u64::from(code))]
            }
            Self::GripperFault { bits } => vec![("bits", u64::from(bits))],
            Self::ConnectionDrop { .. }
            | Self::UdpReorder
            | Self::PowerLoss
            | Self::Collision
            | Self::EStop => Vec::new(),
        }
    }

    /// Whether every value is within its parameter's range
    /// ([`RealmanFaultKind::params`]).
    pub fn check(&self) -> Result<(), FaultError> {
        let kind = self.kind();
        for (name, value) in self.values() {
            if let Some(param) = kind.param(name) {
                param.check(value)?;
            }
        }
        Ok(())
    }

    /// This fault's kind.
    pub fn kind(&self) -> RealmanFaultKind {
        match self {
            Self::ConnectionDrop { .. } => RealmanFaultKind::ConnectionDrop,
            Self::ReplyDelay { .. } => RealmanFaultKind::ReplyDelay,
            Self::MalformedReply { .. } => RealmanFaultKind::MalformedReply,
            Self::UdpLoss { .. } => RealmanFaultKind::UdpLoss,
            Self::UdpReorder => RealmanFaultKind::UdpReorder,
            Self::JointError { .. } => RealmanFaultKind::JointError,
            Self::PowerLoss => RealmanFaultKind::PowerLoss,
            Self::Collision => RealmanFaultKind::Collision,
            Self::EStop => RealmanFaultKind::EStop,
            Self::GripperFault { .. } => RealmanFaultKind::GripperFault,
        }
    }

    /// Stable snake_case name of the kind.
    pub fn name(&self) -> &'static str {
        self.kind().name()
    }
}

/// The optional argument of `connection_drop`: only connections from this IP are closed.
const PEER_IP: &str = "peer_ip";

impl RealmanFaultParam {
    /// Its value in `args`, a whole number within `min..=max`, or why not (in the words a
    /// scenario file has always shown).
    fn read(&self, fault: &str, args: &FaultArgs) -> Result<u64, FaultArgError> {
        let name = self.name;
        let value = match args.get(name) {
            None => return Err(FaultArgError::missing(fault, name)),
            Some(FaultArgValue::Text(text)) => {
                return Err(FaultArgError::at(
                    name,
                    format!("`{name}`: expected a whole number, got `{text}`"),
                ))
            }
            Some(FaultArgValue::Number(value)) => *value,
        };
        if value.fract() != 0.0 || !value.is_finite() {
            return Err(FaultArgError::at(
                name,
                format!("`{name}`: expected a whole number, got {value}"),
            ));
        }
        // Both bounds are far below 2^53, so the comparison in f64 is exact.
        if value < self.min as f64 || value > self.max as f64 {
            return Err(FaultArgError::at(
                name,
                format!(
                    "`{name}`: {value} out of range, expected {}..={}",
                    self.min, self.max
                ),
            ));
        }
        Ok(value as u64)
    }
}

impl RealmanFaultKind {
    /// The names of every argument it takes: its table parameters, plus `peer_ip` for
    /// `connection_drop`.
    pub fn arg_names(self) -> Vec<&'static str> {
        let mut names: Vec<&'static str> = self.params().iter().map(|p| p.name).collect();
        if self == Self::ConnectionDrop {
            names.push(PEER_IP);
        }
        names
    }

    /// The one builder of a [`RealmanFault`] from named arguments: the scenario files, the
    /// web view and the Python emulator only convert what they read into [`FaultArgs`] and
    /// show this error. Every parameter of the table is required and must be a whole number
    /// within its range; an argument the fault does not take is refused by name.
    pub fn build(self, args: &FaultArgs) -> Result<RealmanFault, FaultArgError> {
        let fault = self.name();
        args.only(fault, &self.arg_names())?;
        let params = self.params();
        let int = |i: usize| params[i].read(fault, args);
        Ok(match self {
            Self::ConnectionDrop => RealmanFault::ConnectionDrop {
                peer_ip: peer_ip(args)?,
            },
            Self::ReplyDelay => RealmanFault::ReplyDelay { delay_ms: int(0)? },
            // The table's ranges fit each field, so the narrowing casts are lossless.
            Self::MalformedReply => RealmanFault::MalformedReply {
                count: int(0)? as u32,
            },
            Self::UdpLoss => RealmanFault::UdpLoss {
                permille: int(0)? as u16,
            },
            Self::UdpReorder => RealmanFault::UdpReorder,
            Self::JointError => RealmanFault::JointError {
                joint: int(0)? as u8,
                code: int(1)? as u16,
            },
            Self::PowerLoss => RealmanFault::PowerLoss,
            Self::Collision => RealmanFault::Collision,
            Self::EStop => RealmanFault::EStop,
            Self::GripperFault => RealmanFault::GripperFault {
                bits: int(0)? as u8,
            },
        })
    }
}

/// `peer_ip` of `connection_drop`, if given: an IPv4 or IPv6 address.
fn peer_ip(args: &FaultArgs) -> Result<Option<IpAddr>, FaultArgError> {
    match args.get(PEER_IP) {
        None => Ok(None),
        Some(FaultArgValue::Text(text)) => text.trim().parse().map(Some).map_err(|_| {
            FaultArgError::at(
                PEER_IP,
                format!("`{PEER_IP}`: `{text}` is not an IP address"),
            )
        }),
        Some(other) => Err(FaultArgError::at(
            PEER_IP,
            format!("`{PEER_IP}`: {other} is not an IP address"),
        )),
    }
}

/// The Realman fault called `name` built from `args` ([`RealmanFaultKind::build`]); an
/// unknown name is refused with the list of known ones.
pub fn build_fault(name: &str, args: &FaultArgs) -> Result<RealmanFault, FaultArgError> {
    let kind = RealmanFaultKind::named(name)?;
    kind.build(args)
}

/// A fault with values the emulator cannot apply.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FaultError {
    /// Joint number outside 1..=dof.
    #[error("joint {joint} does not exist (this arm has joints 1–{dof})")]
    NoSuchJoint {
        /// The joint given.
        joint: u8,
        /// Joints of the arm.
        dof: usize,
    },
    /// A joint error with no bit set.
    #[error("joint error code 0 is not an error")]
    ZeroCode,
    /// A value outside its parameter's range ([`RealmanFaultKind::params`]).
    #[error("`{param}` must be between {min} and {max}, got {value}")]
    OutOfRange {
        /// The parameter's name.
        param: &'static str,
        /// The value given.
        value: u64,
        /// Smallest value accepted.
        min: u64,
        /// Largest value accepted.
        max: u64,
    },
    /// A loss probability above 1000 ‰.
    #[error("loss probability {permille}‰ is above 1000‰")]
    BadProbability {
        /// The value given.
        permille: u16,
    },
}

/// System / arm error codes (docs/protocols/realman.md §12).
pub mod codes {
    /// Joint communication abnormal.
    pub const JOINT_COMM: u16 = 0x1001;
    /// Target beyond a joint limit.
    pub const BEYOND_JOINT_LIMIT: u16 = 0x1002;
    /// Unreachable / singular.
    pub const UNREACHABLE: u16 = 0x1003;
    /// Collision detected.
    pub const COLLISION: u16 = 0x100D;
    /// No such work frame.
    pub const NO_WORK_FRAME: u16 = 0x100E;
    /// No such tool frame.
    pub const NO_TOOL_FRAME: u16 = 0x100F;
    /// Joint disabled (enable lost).
    pub const JOINT_DISABLED: u16 = 0x1010;
    /// Arc planning error.
    pub const ARC_PLANNING: u16 = 0x1011;
    /// Gripper fault.
    pub const GRIPPER: u16 = 0x2001;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_round_trip() {
        let mut names: Vec<_> = RealmanFaultKind::ALL.iter().map(|k| k.name()).collect();
        for kind in RealmanFaultKind::ALL {
            assert_eq!(RealmanFaultKind::from_name(kind.name()), Some(kind));
            assert!(!kind.description().is_empty());
        }
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), RealmanFaultKind::ALL.len());
    }

    #[test]
    fn all_lists_every_kind_once_in_declaration_order() {
        use strum::IntoEnumIterator;
        assert!(RealmanFaultKind::iter().eq(RealmanFaultKind::ALL));
        assert_eq!(RealmanFaultKind::EStop.name(), "estop");
        assert_eq!(RealmanFaultKind::from_name("e_stop"), None);
    }

    fn num(name: &str, value: f64) -> FaultArgs {
        FaultArgs::new().with(name, FaultArgValue::Number(value))
    }

    #[test]
    fn the_builder_reads_every_fault_from_its_table() {
        let every = ["delay_ms", "count", "permille", "joint", "code", "bits"];
        for kind in RealmanFaultKind::ALL {
            let mut args = FaultArgs::new();
            for name in every.iter().filter(|n| kind.param(n).is_some()) {
                args.push(*name, FaultArgValue::Number(1.0));
            }
            assert_eq!(build_fault(kind.name(), &args).map(|f| f.kind()), Ok(kind));
        }
        let joint = num("joint", 3.0).with("code", FaultArgValue::Number(8.0));
        assert_eq!(
            RealmanFaultKind::JointError.build(&joint),
            Ok(RealmanFault::JointError { joint: 3, code: 8 })
        );
        let ip = FaultArgs::new().with("peer_ip", FaultArgValue::Text("10.0.0.2".into()));
        assert_eq!(
            RealmanFaultKind::ConnectionDrop.build(&ip),
            Ok(RealmanFault::ConnectionDrop {
                peer_ip: Some([10, 0, 0, 2].into())
            })
        );
    }

    #[test]
    fn the_builder_refuses_with_the_scenario_wording() {
        let err = |kind: RealmanFaultKind, args: FaultArgs| kind.build(&args).unwrap_err();
        let e = err(RealmanFaultKind::ReplyDelay, num("delay_ms", -5.0));
        assert_eq!(e.arg.as_deref(), Some("delay_ms"));
        assert_eq!(e.message, "`delay_ms`: -5 out of range, expected 1..=60000");
        let e = err(RealmanFaultKind::UdpLoss, num("permille", 1001.0));
        assert_eq!(
            e.message,
            "`permille`: 1001 out of range, expected 0..=1000"
        );
        let e = err(RealmanFaultKind::JointError, num("joint", 3.0));
        assert_eq!(
            (e.arg, e.message.as_str()),
            (None, "`joint_error` needs `code`")
        );
        let e = err(RealmanFaultKind::MalformedReply, num("count", 1.5));
        assert_eq!(e.message, "`count`: expected a whole number, got 1.5");
        let e = err(
            RealmanFaultKind::GripperFault,
            FaultArgs::new().with("bits", FaultArgValue::Text("stall".into())),
        );
        assert_eq!(e.message, "`bits`: expected a whole number, got `stall`");
        let e = err(
            RealmanFaultKind::ReplyDelay,
            num("delay_ms", 10.0).with("dleay_ms", FaultArgValue::Number(3.0)),
        );
        assert_eq!(e.arg.as_deref(), Some("dleay_ms"));
        assert!(e.message.contains("it takes: delay_ms"), "{}", e.message);
        let e = err(RealmanFaultKind::EStop, num("joint", 1.0));
        assert!(e.message.contains("takes no arguments"), "{}", e.message);
        let e = err(
            RealmanFaultKind::ConnectionDrop,
            FaultArgs::new().with("peer_ip", FaultArgValue::Text("host".into())),
        );
        assert_eq!(e.message, "`peer_ip`: `host` is not an IP address");
        let e = build_fault("comm_loss", &FaultArgs::new()).unwrap_err();
        assert_eq!(e.arg, None);
        assert!(
            e.message
                .starts_with("no Realman fault `comm_loss`; known: connection_drop, reply_delay"),
            "{}",
            e.message
        );
    }

    #[test]
    fn values_are_checked_against_the_table() {
        assert_eq!(RealmanFault::ReplyDelay { delay_ms: 600 }.check(), Ok(()));
        let err = RealmanFault::ReplyDelay { delay_ms: u64::MAX }
            .check()
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            format!("`delay_ms` must be between 1 and 60000, got {}", u64::MAX)
        );
        assert!(RealmanFault::UdpLoss { permille: 1001 }.check().is_err());
        assert!(RealmanFault::JointError { joint: 8, code: 1 }
            .check()
            .is_err());
        assert!(RealmanFault::JointError { joint: 3, code: 0 }
            .check()
            .is_err());
        assert!(RealmanFault::GripperFault { bits: 0 }.check().is_err());
        assert_eq!(RealmanFault::EStop.check(), Ok(()));
        // Every parameter a fault carries is in the table.
        for kind in RealmanFaultKind::ALL {
            for p in kind.params() {
                assert!(p.min <= p.max, "{}", p.name);
            }
        }
        for (name, _) in (RealmanFault::JointError { joint: 1, code: 1 }).values() {
            assert!(RealmanFaultKind::JointError.param(name).is_some());
        }
    }
}
