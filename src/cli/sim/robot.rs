//! `armhil sim robot FILE`: a whole robot from its robot file, every bus served at once — each
//! on the SocketCAN interface of its name (as on the robot), on vxcan pairs it creates, or as
//! one channel per bus of a socketcand server.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::Context;
use armhil::robots::load_robot_file;
use bus::socketcand::SocketcandServer;
use bus::CanBus;
use sim::robot::{RobotConfig, RobotEmulator};

/// Arguments of `armhil sim robot`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The robot file (`robots/humanoid.yaml`, grammar in `robots/README.md`).
    pub file: PathBuf,
    /// Serve every bus over one socketcand server on HOST:PORT (a bare port means
    /// 127.0.0.1), one channel per bus: a client's `< open can2 >` reaches bus `can2` only.
    #[arg(long, value_name = "HOST:PORT")]
    pub socketcand: Option<String>,
    /// Create a vxcan pair per bus first (needs root; kept after exit): the emulator takes
    /// `sim-NAME` and the client keeps the bus's own name (`can0` …), so a stack written for
    /// the robot runs unchanged.
    #[arg(long, conflicts_with = "socketcand")]
    pub create_vxcan: bool,
    /// Host ID the motors answer to until a host speaks.
    #[arg(long, default_value_t = 0xFD)]
    pub host_id: u8,
    /// JSON file keeping every actuator's saved parameters, CAN id and zero across runs.
    #[arg(long)]
    pub state_file: Option<PathBuf>,
}

/// The prefix of the emulator's end of a vxcan pair.
const VXCAN_PREFIX: &str = "sim-";
/// Longest Linux interface name (IFNAMSIZ − 1).
const MAX_IFACE_CHARS: usize = 15;

/// Run the robot until Ctrl-C.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    super::real_time_runtime()?.block_on(async { serve(args, super::StopSource::signals()?).await })
}

/// Where the buses are served, and what has to be shut down with them.
struct Served {
    nodes: Vec<Arc<dyn CanBus>>,
    place: String,
    server: Option<SocketcandServer>,
}

async fn open_buses(args: &Args, config: &RobotConfig) -> anyhow::Result<Served> {
    let names: Vec<String> = config.buses.iter().map(|b| b.name.clone()).collect();
    if let Some(addr) = &args.socketcand {
        let addr = super::socketcand_addr(addr);
        let (buses, server) = SocketcandServer::bind_realtime_channels(&addr, &names)
            .await
            .with_context(|| format!("cannot serve socketcand on {addr}"))?;
        if let Some(warning) = super::public_warning(
            "the socketcand server",
            server.local_addr(),
            "put any frame on the robot's buses (the protocol has no authentication)",
        ) {
            eprintln!("{warning}");
        }
        let nodes = buses
            .iter()
            .map(|b| Arc::new(b.attach("robot")) as Arc<dyn CanBus>)
            .collect();
        return Ok(Served {
            nodes,
            place: format!(
                "socketcand {} (channels {})",
                server.local_addr(),
                names.join(", ")
            ),
            server: Some(server),
        });
    }
    let mut nodes = Vec::with_capacity(names.len());
    let mut ifaces = Vec::with_capacity(names.len());
    for name in &names {
        let iface = if args.create_vxcan {
            let ours = format!("{VXCAN_PREFIX}{name}");
            anyhow::ensure!(
                ours.len() <= MAX_IFACE_CHARS,
                "bus `{name}`: the vxcan end `{ours}` would be longer than {MAX_IFACE_CHARS} characters, the limit for an interface name; shorten the bus name"
            );
            super::create_vxcan(&ours, name)?;
            ours
        } else {
            name.clone()
        };
        nodes.push(super::served_bus::open_socketcan(&iface)?);
        ifaces.push(iface);
    }
    Ok(Served {
        nodes,
        place: ifaces.join(", "),
        server: None,
    })
}

/// Serve until `stop` asks (a signal, or the bench this device is part of stopping).
pub(crate) async fn serve(args: Args, mut stop: super::StopSource) -> anyhow::Result<ExitCode> {
    let loaded = load_robot_file(&args.file)?;
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    let mut config = loaded.config;
    config.host_id = args.host_id;
    config.state_file = args.state_file.clone();
    let summary = summary(&config);
    let served = open_buses(&args, &config).await?;
    let nodes = served.nodes.clone();
    let robot = RobotEmulator::spawn(config, served.nodes)
        .with_context(|| format!("cannot start the robot of {}", args.file.display()))?;
    tracing::info!(on = %served.place, "robot emulator running; Ctrl-C to stop");
    eprintln!(
        "armhil sim robot: {summary} on {} (Ctrl-C to stop)",
        served.place
    );
    let mut death = robot.death_watch();
    let stopped = super::until_stopped(&mut stop, &mut death).await;
    robot.shutdown().await;
    for node in nodes {
        node.close().await;
    }
    if let Some(server) = served.server {
        server.shutdown().await;
    }
    super::outcome("robot", stopped, &death)
}

/// `robstride_arm6: can0 ids 1 2 3, can1 ids 4 5 6`.
fn summary(config: &RobotConfig) -> String {
    let buses: Vec<String> = config
        .buses
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let ids: Vec<String> = config
                .actuators
                .iter()
                .filter(|a| a.bus == k)
                .map(|a| a.motor.can_id.to_string())
                .collect();
            format!("{} ids {}", b.name, ids.join(" "))
        })
        .collect();
    format!("{}: {}", config.name, buses.join(", "))
}
