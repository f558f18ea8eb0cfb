//! Where a CAN emulator answers: one set of options (`--iface`, `--socketcand`,
//! `--create-vxcan`) for every CAN device of `armhil sim`, and the bus they open. A new CAN
//! device flattens [`ServeArgs`] into its arguments and asks [`ServedBus`] for its nodes.
//! The devices of one rig that name the same socketcand address share its server and its
//! bus ([`RigBuses`]), as devices that name the same SocketCAN interface share that.

use std::collections::HashMap;
use std::sync::Arc;

use bus::socketcand::SocketcandServer;
use bus::virtual_bus::VirtualBus;
use bus::CanBus;

use armhil::harness::Link;

/// Where the emulator answers (flattened into each CAN device's arguments).
#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// SocketCAN interface to answer on.
    #[arg(long, default_value = "vcan0")]
    pub iface: String,
    /// Serve over socketcand (CAN over TCP) on HOST:PORT instead of a SocketCAN interface,
    /// e.g. `127.0.0.1:29536` (a bare port means 127.0.0.1). Any bus name a client opens
    /// reaches the emulator; several clients may connect at once.
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "iface")]
    pub socketcand: Option<String>,
    /// Create the vxcan pair `--iface` ↔ PEER first (needs root; kept after exit), so a client
    /// on PEER, such as a vendor SDK, reaches the emulator whatever its socket options.
    #[arg(long, value_name = "PEER", conflicts_with = "socketcand")]
    pub create_vxcan: Option<String>,
}

impl ServeArgs {
    /// The link these options name, the type `armhil run` and `armhil record` connect with:
    /// here the socketcand address is where the server listens.
    pub fn link(&self) -> Link {
        match &self.socketcand {
            Some(addr) => Link::Socketcand(addr.clone()),
            None => Link::SocketCan(self.iface.clone()),
        }
    }
}

/// The socketcand servers the devices of one rig (`armhil sim rig`) share: devices that
/// name the same address are on one bus behind one server (a leader arm and its follower),
/// as devices that name the same SocketCAN interface are. An address with port 0 (any free
/// port) is never shared. The server stops when the last device on it does.
#[derive(Default)]
pub(crate) struct RigBuses {
    /// By address as given (a bare port is 127.0.0.1): the bus, its server, how many devices
    /// use it.
    servers: tokio::sync::Mutex<HashMap<String, (VirtualBus, SocketcandServer, usize)>>,
}

impl RigBuses {
    /// The bus behind the server on `addr`, started by the first device that names it.
    async fn join(&self, addr: &str) -> anyhow::Result<(VirtualBus, std::net::SocketAddr)> {
        let mut servers = self.servers.lock().await;
        if let Some((bus, server, users)) = servers.get_mut(addr) {
            *users += 1;
            return Ok((bus.clone(), server.local_addr()));
        }
        let (bus, server) = super::socketcand_server(addr).await?;
        let local = server.local_addr();
        servers.insert(addr.to_owned(), (bus.clone(), server, 1));
        Ok((bus, local))
    }

    /// One device fewer on `addr`; the last one stops the server.
    async fn leave(&self, addr: &str) {
        let mut servers = self.servers.lock().await;
        let last = match servers.get_mut(addr) {
            Some((_, _, users)) => {
                *users -= 1;
                *users == 0
            }
            None => false,
        };
        if last {
            if let Some((_, server, _)) = servers.remove(addr) {
                server.shutdown().await;
            }
        }
    }
}

/// The frames a served device speaks, which decides the sockets it is given.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Frames {
    /// Classic CAN only (RobStride, the Piper): classic sockets, which never see an FD frame,
    /// as a classic controller ignores them.
    Classic,
    /// Classic CAN and CAN FD (Damiao): CAN FD sockets.
    Fd,
}

/// The bus an emulator serves, opened from [`ServeArgs`].
pub(crate) struct ServedBus {
    medium: Medium,
}

enum Medium {
    /// A real-time virtual bus behind a socketcand server: every node attaches to it.
    Socketcand {
        bus: VirtualBus,
        server: SocketcandServer,
    },
    /// The same, behind a server other devices of the rig use too.
    SharedSocketcand {
        bus: VirtualBus,
        addr: String,
        local: std::net::SocketAddr,
        rig: Arc<RigBuses>,
    },
    /// A SocketCAN interface: every node is a socket of its own on it, of the frames the device speaks.
    SocketCan { iface: String, frames: Frames },
}

impl ServedBus {
    /// Open the bus `args` names for a classic CAN device: start the socketcand server
    /// (warning if other machines can reach it) or, on a rig, join the one the rig's devices
    /// share on that address; or create the vxcan pair when asked and take the interface.
    pub async fn open(args: &ServeArgs, rig: Option<&Arc<RigBuses>>) -> anyhow::Result<Self> {
        Self::open_for(args, rig, Frames::Classic).await
    }

    /// [`ServedBus::open`] for a device that speaks `frames`: with [`Frames::Fd`] every
    /// SocketCAN node is a CAN FD socket and a vxcan pair it creates gets the CAN FD MTU.
    /// (socketcand carries classic frames only, whatever the device speaks.)
    pub async fn open_for(
        args: &ServeArgs,
        rig: Option<&Arc<RigBuses>>,
        frames: Frames,
    ) -> anyhow::Result<Self> {
        match args.link() {
            Link::Socketcand(addr) => {
                let addr = super::socketcand_addr(&addr);
                let any_port = addr.ends_with(":0");
                if let (Some(rig), false) = (rig, any_port) {
                    let (bus, local) = rig.join(&addr).await?;
                    return Ok(Self {
                        medium: Medium::SharedSocketcand {
                            bus,
                            addr,
                            local,
                            rig: Arc::clone(rig),
                        },
                    });
                }
                let (bus, server) = super::socketcand_server(&addr).await?;
                Ok(Self {
                    medium: Medium::Socketcand { bus, server },
                })
            }
            Link::SocketCan(iface) => {
                if let Some(peer) = &args.create_vxcan {
                    super::create_vxcan(&iface, peer, frames == Frames::Fd)?;
                }
                Ok(Self {
                    medium: Medium::SocketCan { iface, frames },
                })
            }
        }
    }

    /// A node on the bus called `name` (the emulator, a recorder, the web view's tap). A node
    /// that never sends receives every frame, the emulator's and the clients'.
    pub fn node(&self, name: &str) -> anyhow::Result<Arc<dyn CanBus>> {
        match &self.medium {
            Medium::Socketcand { bus, .. } | Medium::SharedSocketcand { bus, .. } => {
                Ok(Arc::new(bus.attach(name)))
            }
            Medium::SocketCan { iface, frames } => open_socketcan(iface, *frames),
        }
    }

    /// Where the emulator answers, for people: `vcan0` or `socketcand 127.0.0.1:29536`.
    pub fn place(&self) -> String {
        match &self.medium {
            Medium::Socketcand { server, .. } => format!("socketcand {}", server.local_addr()),
            Medium::SharedSocketcand { local, .. } => format!("socketcand {local}"),
            Medium::SocketCan { iface, .. } => iface.clone(),
        }
    }

    /// One word for a candump log's interface column: the interface, or `socketcand`.
    pub fn channel(&self) -> &str {
        match &self.medium {
            Medium::Socketcand { .. } | Medium::SharedSocketcand { .. } => "socketcand",
            Medium::SocketCan { iface, .. } => iface,
        }
    }

    /// Stop serving: the socketcand server's clients are disconnected (a shared server's
    /// when its last device stops; nothing to do on a SocketCAN interface, whose sockets
    /// close with their nodes).
    pub async fn shutdown(self) {
        match self.medium {
            Medium::Socketcand { server, .. } => server.shutdown().await,
            Medium::SharedSocketcand { addr, rig, .. } => rig.leave(&addr).await,
            Medium::SocketCan { .. } => {}
        }
    }
}

/// A node on the SocketCAN interface `iface`, a CAN FD socket for [`Frames::Fd`]; the error is
/// the bus crate's, which names the interface and says what to do.
pub(crate) fn open_socketcan(iface: &str, frames: Frames) -> anyhow::Result<Arc<dyn CanBus>> {
    Ok(bus::open_socketcan_for(iface, frames == Frames::Fd)?)
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        bus: ServeArgs,
    }

    fn link(args: &[&str]) -> Link {
        let all = std::iter::once("x").chain(args.iter().copied());
        Cli::try_parse_from(all).expect("valid options").bus.link()
    }

    #[test]
    fn the_served_link_is_the_one_a_client_names_with_the_same_option() {
        let vcan0 = link(&[]);
        assert_eq!(vcan0, Link::SocketCan("vcan0".into()));
        let served = link(&["--socketcand", "127.0.0.1:29536"]);
        assert_eq!(served, Link::Socketcand("127.0.0.1:29536".into()));
        // The option a client passes to reach it is the one the emulator was given.
        assert_eq!(served.sim_option(), "--socketcand 127.0.0.1:29536");
        assert_eq!(link(&["--iface", "can1"]).sim_option(), "--iface can1");
    }
}
