//! Which clock a run keeps and which CAN link it reaches a separate emulator on.

use std::sync::Arc;

/// Which clock and bus a run uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Clock {
    /// In-process emulator and virtual bus on tokio's paused clock (deterministic, fast).
    Virtual,
    /// In-process emulator and virtual bus on the real clock.
    Realtime,
    /// Real time on a CAN link (a SocketCAN interface or a socketcand server), against a
    /// separate emulator process (`armhil sim <kind> --iface IF` or `--socketcand ADDR`). Bus
    /// and emulator faults are unavailable.
    Iface(Link),
}

/// The CAN link of a [`Clock::Iface`] run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Link {
    /// A SocketCAN interface, e.g. `vcan0`.
    SocketCan(String),
    /// A socketcand server at `HOST:PORT`.
    Socketcand(String),
}

impl Link {
    /// The command-line option that names this kind of link, the same for every command
    /// (`armhil run`, `armhil record`, `armhil sim`): `--iface` or `--socketcand`.
    pub fn flag(&self) -> &'static str {
        match self {
            Self::SocketCan(_) => "--iface",
            Self::Socketcand(_) => "--socketcand",
        }
    }

    /// The `armhil sim` option that serves an emulator on this link.
    pub fn sim_option(&self) -> String {
        match self {
            Self::SocketCan(iface) | Self::Socketcand(iface) => format!("{} {iface}", self.flag()),
        }
    }

    /// Connect to the bus as a node; `what` names it in errors (the recorder, or the driver
    /// of a CAN device kind). On a SocketCAN interface a second socket sees every frame, the
    /// driver's and the emulator's; on a socketcand server so does a second connection.
    pub async fn open(&self, what: &str) -> Result<Arc<dyn bus::CanBus>, String> {
        self.open_for(what, false).await
    }

    /// [`Link::open`] for a node that must see CAN FD frames too, such as a recorder: on
    /// SocketCAN a CAN FD socket (classic and FD frames alike; a classic socket never receives
    /// an FD frame). socketcand carries classic frames only.
    pub async fn open_fd(&self, what: &str) -> Result<Arc<dyn bus::CanBus>, String> {
        self.open_for(what, true).await
    }

    async fn open_for(&self, what: &str, fd: bool) -> Result<Arc<dyn bus::CanBus>, String> {
        match self {
            Self::SocketCan(iface) => super::open_iface(iface, what, fd),
            Self::Socketcand(addr) => bus::socketcand::SocketcandBus::connect(addr, "can0")
                .await
                .map(|b| Arc::new(b) as Arc<dyn bus::CanBus>)
                .map_err(|e| format!("cannot reach the socketcand server for the {what}: {e}")),
        }
    }

    /// One word for a candump log's interface column: the interface, or `socketcand`.
    pub fn channel(&self) -> &str {
        match self {
            Self::SocketCan(iface) => iface,
            Self::Socketcand(_) => "socketcand",
        }
    }
}

impl std::fmt::Display for Link {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::SocketCan(iface) => write!(f, "{iface}"),
            Self::Socketcand(addr) => write!(f, "socketcand {addr}"),
        }
    }
}

impl Clock {
    /// The clock in one phrase for results and logs (`virtual`, `iface vcan0`).
    pub(crate) fn describe(&self) -> String {
        match self {
            Self::Virtual => "virtual".to_owned(),
            Self::Realtime => "realtime".to_owned(),
            Self::Iface(Link::SocketCan(iface)) => format!("iface {iface}"),
            Self::Iface(link @ Link::Socketcand(_)) => link.to_string(),
        }
    }
}
