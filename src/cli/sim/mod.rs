//! `armhil sim <device>`: a firmware emulator in real time on a real interface.

use std::net::SocketAddr;
use std::process::ExitCode;

use clap::Subcommand;
use sim::supervise::{DeathWatch, EmulatorDied};

use super::signals::StopSignals;

pub mod damiao;
pub mod piper;
pub mod realman;
pub mod rig;
pub mod robot;
pub mod robstride;
pub mod served;
pub mod served_bus;

use served::ServedKind;

/// Arguments of `armhil sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    device: Device,
}

/// Register the served kinds: `"name" => Variant(module)`, each module holding a `Kind`
/// that implements [`ServedKind`]. The subcommands, the kinds a rig file may hold and the
/// rig's dispatch are generated from this list; nothing else in the CLI lists them.
macro_rules! served_kinds {
    ($( $(#[$doc:meta])* $name:literal => $variant:ident($module:ident) ),* $(,)?) => {
        // Each registration line's name is its kind's `ServedKind::NAME`.
        $( const _: () = assert!(
            armhil::devices::same_text($name, <$module::Kind as ServedKind>::NAME),
            concat!("`", $name, "` is registered under another name than its ServedKind::NAME")
        ); )*

        #[derive(Debug, Subcommand)]
        enum Device {
            $( $(#[$doc])* #[command(name = $name)] $variant(<$module::Kind as ServedKind>::Args), )*
            /// Several devices in one process from a rig file (`rigs/`): two Piper arms on two
            /// interfaces, Realman controllers on several ports, robots; stopped together.
            // `bench`: its name while rig files were called bench files; kept as a hidden
            // alias so the commands people wrote then still run.
            #[command(alias = "bench")]
            Rig(rig::Args),
        }

        /// Every kind a rig file may hold, with the parser of its options.
        pub(crate) const SERVED: &[(armhil::rigs::SimKind, served::EntryParser)] = &[
            $( (served::sim_kind::<$module::Kind>(), served::parse_entry::<$module::Kind>), )*
        ];

        /// Run the chosen emulator until Ctrl-C.
        pub fn run(args: Args) -> anyhow::Result<ExitCode> {
            raise_open_file_limit();
            match args.device {
                $( Device::$variant(args) => served::run_alone::<$module::Kind>(args), )*
                Device::Rig(args) => rig::run(args),
            }
        }
    };
}

served_kinds! {
    /// AgileX Piper 6-DoF arm (CAN, 11-bit IDs).
    "piper" => Piper(piper),
    /// Realman arm controller (JSON over TCP, realtime push over UDP).
    "realman" => Realman(realman),
    /// RobStride actuators (CAN, 29-bit IDs), any number on one bus.
    "robstride" => Robstride(robstride),
    /// Damiao (DM) joint motors (CAN, 11-bit IDs), any number on one bus.
    "damiao" => Damiao(damiao),
    /// A whole robot from its robot file: one physics world, every bus served at once.
    "robot" => Robot(robot),
}

/// The runtime every emulator of `armhil sim` runs on: `sim::pacer::real_time_runtime`, one
/// punctual worker (why one: `sim::pacer::REAL_TIME_WORKERS`).
fn real_time_runtime() -> anyhow::Result<tokio::runtime::Runtime> {
    use anyhow::Context as _;
    sim::pacer::real_time_runtime().context("cannot start the tokio runtime")
}

/// `--socketcand` takes `HOST:PORT`; a bare port means loopback.
pub(crate) fn socketcand_addr(text: &str) -> String {
    match text.parse::<u16>() {
        Ok(port) => format!("127.0.0.1:{port}"),
        Err(_) => text.to_owned(),
    }
}

/// A socketcand server on `addr` with the real-time virtual bus the emulator attaches to.
/// Timestamps are Unix time, as a SocketCAN socket reports them.
pub(crate) async fn socketcand_server(
    addr: &str,
) -> anyhow::Result<(
    bus::virtual_bus::VirtualBus,
    bus::socketcand::SocketcandServer,
)> {
    use anyhow::Context as _;

    let addr = socketcand_addr(addr);
    let (bus, server) = bus::socketcand::SocketcandServer::bind_realtime_bus(&addr)
        .await
        .with_context(|| format!("cannot serve socketcand on {addr}"))?;
    if let Some(warning) = public_warning(
        "the socketcand server",
        server.local_addr(),
        "put any frame on the emulator's bus (the protocol has no authentication)",
    ) {
        eprintln!("{warning}");
    }
    Ok((bus, server))
}

/// The warning for a server bound to `addr` if other machines can reach it: who can, and
/// what they can do. `None` on loopback.
pub(crate) fn public_warning(what: &str, addr: SocketAddr, can: &str) -> Option<String> {
    if addr.ip().is_loopback() {
        return None;
    }
    let who = if addr.ip().is_unspecified() {
        "every interface of this machine: anyone who can reach it over any network (LAN, \
         Wi-Fi, VPN, containers and VMs on it)"
    } else {
        "a non-loopback address: anyone who can reach that address over the network"
    };
    tracing::warn!(%addr, "{what} is reachable from other machines");
    Some(format!(
        "WARNING: {what} listens on {addr}, {who}, can connect and {can}. \
         Bind 127.0.0.1 unless other machines must connect."
    ))
}

/// Print where the web view is, with its token, and warn if other machines can reach it.
pub(crate) fn announce_ui(device: &str, server: &armhil::ui::UiServer) {
    if let Some(warning) = public_warning(
        "the web view",
        server.local_addr(),
        "inject faults into the emulator if they have the token in this URL (share it only \
         with those who should)",
    ) {
        eprintln!("{warning}");
    }
    eprintln!("armhil sim {device}: web view on {}", server.url());
}

/// `--create-vxcan PEER`: make sure the vxcan pair `iface` ↔ `peer` exists and is up (with the
/// CAN FD MTU when `fd`, for devices that speak CAN FD), and tell the user which end their
/// client takes.
fn create_vxcan(iface: &str, peer: &str, fd: bool) -> anyhow::Result<()> {
    #[cfg(target_os = "linux")]
    {
        use bus::vxcan::{ensure_fd_pair, ensure_pair, PairSetup};
        let setup = if fd {
            ensure_fd_pair(iface, peer)?
        } else {
            ensure_pair(iface, peer)?
        };
        let done = match setup {
            PairSetup::Created => "created",
            PairSetup::AlreadyThere => "using the existing",
        };
        let frames = if fd { " (CAN FD, MTU 72)" } else { "" };
        eprintln!("{done} vxcan pair {iface} ↔ {peer}{frames}: the emulator is on {iface}, point your client at {peer}");
        Ok(())
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (iface, fd);
        anyhow::bail!("--create-vxcan {peer}: vxcan pairs exist only on Linux (use --socketcand)")
    }
}

/// How `armhil sim` came to stop.
#[derive(Debug)]
pub(crate) enum Stopped {
    /// Ctrl-C or SIGTERM (or the rig's stop request).
    Signal(&'static str),
    /// The emulator stopped serving on its own.
    Died(EmulatorDied),
}

/// What tells a served device to stop: the process's own signals when it runs alone, or the
/// rig it is part of (`armhil sim rig`), which listens for the signals once and stops
/// every device together.
pub(crate) enum StopSource {
    /// SIGINT / SIGTERM. Listened for before the emulator starts: a signal that arrived
    /// earlier would kill the process with its recording or state file unfinished.
    Signals(StopSignals),
    /// The rig's stop request: the name of the signal (or reason) once it is sent; and the
    /// socketcand buses the rig's devices share.
    Rig {
        /// The stop request.
        request: tokio::sync::watch::Receiver<Option<&'static str>>,
        /// The shared socketcand servers.
        buses: std::sync::Arc<served_bus::RigBuses>,
    },
}

impl StopSource {
    /// Listen for the process's signals (needs the runtime).
    pub(crate) fn signals() -> anyhow::Result<Self> {
        Ok(Self::Signals(StopSignals::listen()?))
    }

    /// The socketcand buses shared with the other devices of the rig, if on one.
    pub(crate) fn rig_buses(&self) -> Option<&std::sync::Arc<served_bus::RigBuses>> {
        match self {
            Self::Signals(_) => None,
            Self::Rig { buses, .. } => Some(buses),
        }
    }

    /// Wait for the stop request and name it.
    pub(crate) async fn next(&mut self) -> &'static str {
        match self {
            Self::Signals(signals) => signals.next().await,
            Self::Rig { request, .. } => match request.wait_for(Option::is_some).await {
                Ok(reason) => reason.unwrap_or("stop"),
                // The rig is gone: nobody is left to serve.
                Err(_) => "stop",
            },
        }
    }
}

/// Wait for a stop request (Ctrl-C / SIGTERM, or the rig's), or for the emulator to die on
/// its own (a task panicked, its state file could not be written), whichever comes first.
/// Waiting for the signal alone kept the port open on a dead bus and exited 0 (D4).
pub(crate) async fn until_stopped(stop: &mut StopSource, death: &mut DeathWatch) -> Stopped {
    let stopped = tokio::select! {
        signal = stop.next() => Stopped::Signal(signal),
        died = death.died() => Stopped::Died(died),
    };
    match &stopped {
        Stopped::Signal(signal) => tracing::info!(signal, "stopping"),
        Stopped::Died(died) => tracing::error!(%died, "the emulator died; stopping"),
    }
    stopped
}

/// The outcome of `armhil sim <device>` once everything is shut down: success after a stop
/// signal, an error saying why if the emulator died (during the run, or while it shut down).
pub(crate) fn outcome(
    device: &str,
    stopped: Stopped,
    death: &DeathWatch,
) -> anyhow::Result<ExitCode> {
    let died = match stopped {
        Stopped::Died(died) => Some(died),
        Stopped::Signal(_) => death.now(),
    };
    match died {
        Some(died) => {
            Err(anyhow::Error::new(died).context(format!("the {device} emulator stopped serving")))
        }
        None => Ok(ExitCode::SUCCESS),
    }
}

/// Open files the servers ask for: every connection cap together (Realman 64, socketcand
/// 128, web view 64) plus the recordings and state files, with room to spare. Many systems
/// start processes at a soft limit of 1,024, which a storm of unfinished connections used up
/// before the caps existed; the hard limit is left alone.
const WANTED_OPEN_FILES: u64 = 8192;

/// Raise the soft open-file limit towards [`WANTED_OPEN_FILES`] (never above the hard limit);
/// the limit in force afterwards. A failure only costs headroom, so it is logged, not fatal.
fn raise_open_file_limit() -> Option<u64> {
    match rlimit::increase_nofile_limit(WANTED_OPEN_FILES) {
        Ok(limit) => {
            tracing::debug!(limit, "open-file soft limit");
            Some(limit)
        }
        Err(e) => {
            tracing::warn!("cannot raise the open-file limit: {e}");
            None
        }
    }
}

#[cfg(test)]
mod tests {
    /// Every path option of every kind is a file it reads (listed here) or a file it writes
    /// (its `OUTPUT_KEYS`, which a rig checks for files two devices would write): a new
    /// option naming a file fails here until it is one or the other.
    #[test]
    fn every_path_option_is_an_input_or_an_output_key() {
        let read: &[(&str, &[&str])] = &[("piper", &["urdf"]), ("robot", &["file"])];
        let command = <super::Args as clap::Args>::augment_args(clap::Command::new("sim"));
        for (kind, _) in super::SERVED {
            let sub = command
                .find_subcommand(kind.name)
                .expect("a subcommand per kind");
            let paths: Vec<String> = sub
                .get_arguments()
                .filter(|a| {
                    a.get_value_parser().type_id() == std::any::TypeId::of::<std::path::PathBuf>()
                })
                .map(|a| match a.get_long() {
                    Some(long) => long.replace('-', "_"),
                    None => a.get_id().as_str().to_owned(),
                })
                .collect();
            let inputs = read
                .iter()
                .find(|(name, _)| *name == kind.name)
                .map_or(&[][..], |(_, keys)| keys);
            for input in inputs {
                assert!(
                    paths.iter().any(|p| p == input),
                    "{}: no `{input}`",
                    kind.name
                );
            }
            let mut written: Vec<&str> = paths
                .iter()
                .map(String::as_str)
                .filter(|p| !inputs.contains(p))
                .collect();
            let mut declared = kind.output_keys.to_vec();
            written.sort_unstable();
            declared.sort_unstable();
            assert_eq!(written, declared, "{}: files it writes", kind.name);
        }
    }

    #[test]
    fn a_bare_port_means_loopback() {
        assert_eq!(super::socketcand_addr("29536"), "127.0.0.1:29536");
        assert_eq!(super::socketcand_addr("0.0.0.0:1"), "0.0.0.0:1");
    }

    #[test]
    fn a_public_bind_is_warned_about_and_loopback_is_not() {
        let warn = |a: &str| super::public_warning("X", a.parse().unwrap(), "do Y");
        assert_eq!(warn("127.0.0.1:8080"), None);
        assert_eq!(warn("[::1]:8080"), None);
        let all = warn("0.0.0.0:8080").expect("a warning");
        assert!(
            all.contains("every interface") && all.contains("do Y"),
            "{all}"
        );
        let lan = warn("192.168.1.5:8080").expect("a warning");
        assert!(
            lan.contains("192.168.1.5:8080") && lan.contains("anyone"),
            "{lan}"
        );
    }
}
