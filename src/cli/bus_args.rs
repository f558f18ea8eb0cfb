//! Which bus a client command (`armhil record`, `armhil run`) connects to: one set of options
//! for every such command, turned into the harness's [`Link`] (opened with [`Link::open`]),
//! the way python-can has one `Bus(interface=…)`. The emulators' side of the same choice is
//! `sim::served_bus`.

use armhil::harness::Link;

/// A SocketCAN interface or a socketcand server (flattened into each command's arguments).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct BusArgs {
    /// SocketCAN interface, e.g. `vcan0` (an emulator there: `armhil sim piper --iface vcan0`).
    #[arg(long, value_name = "IF")]
    pub iface: Option<String>,
    /// A socketcand server (CAN over TCP) at HOST:PORT instead, e.g. one served by `armhil sim
    /// piper --socketcand 29536`; works without kernel CAN.
    #[arg(long, value_name = "HOST:PORT", conflicts_with = "iface")]
    pub socketcand: Option<String>,
}

impl BusArgs {
    /// The link these options name, if any.
    pub fn link(&self) -> Option<Link> {
        match (&self.socketcand, &self.iface) {
            (Some(addr), _) => Some(Link::Socketcand(addr.clone())),
            (None, Some(iface)) => Some(Link::SocketCan(iface.clone())),
            (None, None) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        bus: BusArgs,
    }

    fn link(args: &[&str]) -> Result<Option<Link>, clap::Error> {
        let all = std::iter::once("x").chain(args.iter().copied());
        Cli::try_parse_from(all).map(|cli| cli.bus.link())
    }

    #[test]
    fn each_option_names_its_link_and_both_at_once_are_refused() {
        assert_eq!(link(&[]).unwrap(), None);
        assert_eq!(
            link(&["--iface", "can1"]).unwrap(),
            Some(Link::SocketCan("can1".into()))
        );
        assert_eq!(
            link(&["--socketcand", "127.0.0.1:29536"]).unwrap(),
            Some(Link::Socketcand("127.0.0.1:29536".into()))
        );
        let both = link(&["--iface", "can1", "--socketcand", "1"]).unwrap_err();
        assert_eq!(both.kind(), clap::error::ErrorKind::ArgumentConflict);
    }
}
