//! Creating a vxcan pair: two linked virtual CAN interfaces, each frame sent on one arrives on
//! the other. A vendor SDK on one end and an emulator on the other see each other's frames
//! whatever socket options the SDK sets (on a single vcan, a sender with loopback off reaches
//! nobody).
//!
//! The pair is made by iproute2's `ip`, the tool every Linux distribution ships for this: its
//! netlink request for a vxcan link carries the peer as a nested link message, which no
//! well-kept Rust netlink crate builds today. Errors say what to do in plain words.

use std::io;
use std::path::Path;
use std::process::Command;

use crate::socketcan_bus::CANFD_MTU;

/// Longest interface name Linux accepts (IFNAMSIZ − 1).
const MAX_NAME_LEN: usize = 15;

/// What [`ensure_pair`] found or did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairSetup {
    /// The pair was created and brought up.
    Created,
    /// Both interfaces were already there (they were brought up).
    AlreadyThere,
}

/// Why a vxcan pair could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum VxcanError {
    /// Not a usable interface name.
    #[error("{name:?} is not a valid interface name (1–15 characters, no '/', ':' or spaces)")]
    BadName {
        /// The name given.
        name: String,
    },
    /// One end exists, the other does not: some other interface has that name.
    #[error("{existing} exists but {missing} does not, so they are not a vxcan pair; pick other names or delete {existing} (ip link del {existing})")]
    HalfThere {
        /// The interface that exists.
        existing: String,
        /// The one that does not.
        missing: String,
    },
    /// iproute2's `ip` is not installed.
    #[error("creating the vxcan pair {ours} ↔ {peer} needs iproute2's `ip` command, which was not found: {source}")]
    NoIpTool {
        /// Our end.
        ours: String,
        /// The peer.
        peer: String,
        /// Why running it failed.
        source: io::Error,
    },
    /// The caller lacks CAP_NET_ADMIN.
    #[error("creating the vxcan pair {ours} ↔ {peer} needs root (CAP_NET_ADMIN); run `sudo ip link add {ours} type vxcan peer name {peer}` once, then start without --create-vxcan")]
    NotPermitted {
        /// Our end.
        ours: String,
        /// The peer.
        peer: String,
    },
    /// The kernel has no vxcan driver.
    #[error("the kernel has no vxcan driver (try `sudo modprobe vxcan`; containers and macOS have none: use socketcand instead)")]
    NoDriver,
    /// `ip` failed for another reason.
    #[error("`{command}` failed: {stderr}")]
    IpFailed {
        /// The command line.
        command: String,
        /// What `ip` printed.
        stderr: String,
    },
}

/// Make sure the vxcan pair `ours` ↔ `peer` exists and both ends are up, creating it if
/// neither exists. The MTU of each end is left as it is (16, classic CAN, on a new pair).
pub fn ensure_pair(ours: &str, peer: &str) -> Result<PairSetup, VxcanError> {
    ensure_pair_with(ours, peer, false)
}

/// [`ensure_pair`] for CAN FD: both ends get the CAN FD MTU (72) so that FD frames cross the
/// pair. An end that is up with a classic MTU is taken down for the change (the kernel
/// refuses to change a running interface's MTU) and brought up again.
pub fn ensure_fd_pair(ours: &str, peer: &str) -> Result<PairSetup, VxcanError> {
    ensure_pair_with(ours, peer, true)
}

fn ensure_pair_with(ours: &str, peer: &str, fd: bool) -> Result<PairSetup, VxcanError> {
    for name in [ours, peer] {
        check_name(name)?;
    }
    let setup = match (exists(ours), exists(peer)) {
        (true, true) => PairSetup::AlreadyThere,
        (false, false) => {
            ip(
                ours,
                peer,
                &["link", "add", ours, "type", "vxcan", "peer", "name", peer],
            )?;
            PairSetup::Created
        }
        (true, false) => return Err(half_there(ours, peer)),
        (false, true) => return Err(half_there(peer, ours)),
    };
    if fd {
        for name in [ours, peer] {
            if mtu(name) != Some(CANFD_MTU) {
                ip(ours, peer, &["link", "set", name, "down"])?;
                ip(ours, peer, &["link", "set", name, "mtu", CANFD_MTU_TEXT])?;
            }
        }
    }
    for name in [ours, peer] {
        ip(ours, peer, &["link", "set", name, "up"])?;
    }
    Ok(setup)
}

fn half_there(existing: &str, missing: &str) -> VxcanError {
    VxcanError::HalfThere {
        existing: existing.to_owned(),
        missing: missing.to_owned(),
    }
}

fn check_name(name: &str) -> Result<(), VxcanError> {
    let ok = !name.is_empty()
        && name.len() <= MAX_NAME_LEN
        && name != "."
        && name != ".."
        && !name
            .chars()
            .any(|c| c == '/' || c == ':' || c.is_whitespace() || c.is_control());
    if ok {
        Ok(())
    } else {
        Err(VxcanError::BadName {
            name: name.to_owned(),
        })
    }
}

fn exists(name: &str) -> bool {
    Path::new("/sys/class/net").join(name).exists()
}

/// [`CANFD_MTU`] as `ip` takes it.
const CANFD_MTU_TEXT: &str = "72";

/// The interface's MTU as the kernel reports it, if readable.
fn mtu(name: &str) -> Option<usize> {
    std::fs::read_to_string(Path::new("/sys/class/net").join(name).join("mtu"))
        .ok()?
        .trim()
        .parse()
        .ok()
}

/// Run `ip ARGS`, classifying a failure from what it printed.
fn ip(ours: &str, peer: &str, args: &[&str]) -> Result<(), VxcanError> {
    let output = Command::new("ip")
        .args(args)
        .output()
        .map_err(|source| VxcanError::NoIpTool {
            ours: ours.to_owned(),
            peer: peer.to_owned(),
            source,
        })?;
    if output.status.success() {
        return Ok(());
    }
    let stderr = String::from_utf8_lossy(&output.stderr).trim().to_owned();
    Err(classify(
        ours,
        peer,
        &format!("ip {}", args.join(" ")),
        stderr,
    ))
}

/// The error `ip` meant, from its message.
fn classify(ours: &str, peer: &str, command: &str, stderr: String) -> VxcanError {
    if stderr.contains("Operation not permitted") {
        VxcanError::NotPermitted {
            ours: ours.to_owned(),
            peer: peer.to_owned(),
        }
    } else if stderr.contains("Unknown device type") || stderr.contains("not supported") {
        VxcanError::NoDriver
    } else {
        VxcanError::IpFailed {
            command: command.to_owned(),
            stderr,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mtu_given_to_ip_is_the_fd_frame_size() {
        assert_eq!(CANFD_MTU_TEXT, CANFD_MTU.to_string());
    }

    #[test]
    fn bad_names_are_refused_before_anything_runs() {
        for name in ["", "a/b", "x:1", "with space", "sixteen-chars-xx", ".."] {
            let error = ensure_pair(name, "vxcan0").unwrap_err();
            assert!(
                matches!(error, VxcanError::BadName { .. }),
                "{name:?}: {error}"
            );
            assert!(error.to_string().contains(&format!("{name:?}")), "{error}");
        }
        assert!(check_name("vxcan1").is_ok());
        assert!(check_name("fifteen-chars-x").is_ok());
    }

    #[test]
    fn ip_messages_become_errors_that_say_what_to_do() {
        let denied = classify(
            "vxcan1",
            "vxcan0",
            "ip link add",
            "RTNETLINK answers: Operation not permitted".into(),
        );
        assert!(
            denied
                .to_string()
                .contains("sudo ip link add vxcan1 type vxcan peer name vxcan0"),
            "{denied}"
        );
        let no_driver = classify(
            "a",
            "b",
            "ip link add",
            "Error: Unknown device type.".into(),
        );
        assert!(
            no_driver.to_string().contains("modprobe vxcan"),
            "{no_driver}"
        );
        let other = classify(
            "a",
            "b",
            "ip link set a up",
            "RTNETLINK answers: File exists".into(),
        );
        assert_eq!(
            other.to_string(),
            "`ip link set a up` failed: RTNETLINK answers: File exists"
        );
    }

    #[test]
    fn an_existing_interface_without_its_peer_is_not_taken_for_a_pair() {
        // `lo` exists on every Linux machine; a 15-character name that does not.
        let error = ensure_pair("lo", "armhil-nopeer-0").unwrap_err();
        assert!(
            error
                .to_string()
                .starts_with("lo exists but armhil-nopeer-0 does not"),
            "{error}"
        );
    }
}
