//! `armhil sim robot FILE`: a whole robot from its robot file, every bus served at once — each
//! on the SocketCAN interface of its name (as on the robot), on vxcan pairs it creates, or as
//! one channel per bus of a socketcand server.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::Context;
use armhil::robots::load_robot_file;
use armhil::ui::bus_tap::BusTap;
use armhil::ui::robot::RobotLive;
use bus::socketcand::SocketcandServer;
use bus::CanBus;
use sim::robot::{Base, Gantry, RobotConfig, RobotEmulator};
use sim::robstride::state_file::StateFile;

use super::served_bus::Frames;

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
    /// Serve a live web view (the whole robot in 3D from its URDF, a strip per actuator, each
    /// actuator's state, every bus's load, faults per actuator and per bus) on HOST:PORT,
    /// e.g. `127.0.0.1:8000` (a bare port means 127.0.0.1).
    #[arg(long, value_name = "HOST:PORT")]
    pub ui: Option<String>,
    /// A floating robot's stand: `until_enabled` (the default unless the robot file says: the
    /// robot hangs at its start pose until every actuator is enabled, as on a bring-up
    /// gantry), `until_released` (until the web view's or Python's `gantry_release`) or `off`
    /// (free from power-on: an unpowered humanoid falls before a host connects).
    #[arg(long, value_name = "WHEN", value_parser = parse_gantry)]
    pub gantry: Option<Gantry>,
}

/// `--gantry`'s word (`until_enabled` or `until-enabled`).
fn parse_gantry(word: &str) -> Result<Gantry, String> {
    Gantry::parse(&word.replace('-', "_"))
}

/// The prefix of the emulator's end of a vxcan pair.
const VXCAN_PREFIX: &str = "sim-";
/// Longest Linux interface name (IFNAMSIZ − 1).
const MAX_IFACE_CHARS: usize = 15;

/// `armhil sim robot` (registered in [`super::served_kinds`]).
pub(crate) struct Kind;

impl super::served::ServedKind for Kind {
    const NAME: &'static str = "robot";
    const POSITIONAL_KEYS: &'static [&'static str] = &["file"];
    const OUTPUT_KEYS: &'static [&'static str] = &["state_file"];
    type Args = Args;

    fn paths_mut(args: &mut Args) -> Vec<&mut PathBuf> {
        std::iter::once(&mut args.file)
            .chain(args.state_file.iter_mut())
            .collect()
    }

    fn serve(
        args: Args,
        stop: super::StopSource,
    ) -> impl std::future::Future<Output = anyhow::Result<ExitCode>> + Send {
        serve(args, stop)
    }
}

/// Where the buses are served, and what has to be shut down with them.
struct Served {
    nodes: Vec<Arc<dyn CanBus>>,
    place: String,
    server: Option<SocketcandServer>,
    /// The socketcand channels' buses (empty on SocketCAN).
    channels: Vec<bus::virtual_bus::VirtualBus>,
    /// The SocketCAN interfaces (empty on socketcand), each with the frames its bus carries.
    ifaces: Vec<(String, Frames)>,
}

impl Served {
    /// Another node on bus `k` (a channel's silent node, or a second socket on the
    /// interface): it receives every frame of the bus, the robot's and the clients'.
    fn tap(&self, k: usize) -> anyhow::Result<Arc<dyn CanBus>> {
        match (self.channels.get(k), self.ifaces.get(k)) {
            (Some(bus), _) => Ok(Arc::new(bus.attach("ui"))),
            (None, Some((iface, frames))) => super::served_bus::open_socketcan(iface, *frames),
            (None, None) => anyhow::bail!("no bus {k} to tap"),
        }
    }
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
            channels: buses,
            ifaces: Vec::new(),
        });
    }
    let mut nodes = Vec::with_capacity(names.len());
    let mut ifaces = Vec::with_capacity(names.len());
    for bus in &config.buses {
        let name = &bus.name;
        // A bus the robot file gives a data rate is a CAN FD bus: FD sockets, FD vxcan pairs.
        let frames = if bus.data_bitrate_bps.is_some() {
            Frames::Fd
        } else {
            Frames::Classic
        };
        let iface = if args.create_vxcan {
            let ours = format!("{VXCAN_PREFIX}{name}");
            anyhow::ensure!(
                ours.len() <= MAX_IFACE_CHARS,
                "bus `{name}`: the vxcan end `{ours}` would be longer than {MAX_IFACE_CHARS} characters, the limit for an interface name; shorten the bus name"
            );
            super::create_vxcan(&ours, name, frames == Frames::Fd)?;
            ours
        } else {
            name.clone()
        };
        nodes.push(super::served_bus::open_socketcan(&iface, frames)?);
        ifaces.push((iface, frames));
    }
    Ok(Served {
        nodes,
        place: ifaces
            .iter()
            .map(|(iface, frames)| match frames {
                Frames::Fd => format!("{iface} (CAN FD)"),
                Frames::Classic => iface.clone(),
            })
            .collect::<Vec<_>>()
            .join(", "),
        server: None,
        channels: Vec::new(),
        ifaces,
    })
}

/// Loads the robot file on a thread of its own while listening for `stop`: a large URDF
/// with many meshes takes a while, and Ctrl-C must end the process then too. `None`: a stop
/// came first (the loading thread is left behind; the process is about to exit).
async fn load_until_stopped(
    file: &std::path::Path,
    stop: &mut super::StopSource,
) -> anyhow::Result<Option<sim::robot::file::LoadedRobot>> {
    let (done, loaded) = tokio::sync::oneshot::channel();
    let path = file.to_owned();
    std::thread::Builder::new()
        .name("load-robot".into())
        .spawn(move || {
            // The receiver is gone only when a stop came first: nothing to report to.
            let _ = done.send(load_robot_file(&path));
        })?;
    tokio::select! {
        loaded = loaded => {
            let loaded = loaded.map_err(|_| anyhow::anyhow!("loading {} stopped unexpectedly", file.display()))?;
            Ok(Some(loaded?))
        }
        signal = stop.next() => {
            eprintln!("{signal} while loading {}: stopped", file.display());
            Ok(None)
        }
    }
}

/// Serve until `stop` asks (a signal, or the rig this device is part of stopping).
pub(crate) async fn serve(args: Args, mut stop: super::StopSource) -> anyhow::Result<ExitCode> {
    let Some(loaded) = load_until_stopped(&args.file, &mut stop).await? else {
        return Ok(ExitCode::from(130));
    };
    for warning in &loaded.warnings {
        eprintln!("warning: {warning}");
    }
    let gantry = loaded.serving_gantry(args.gantry);
    let mut config = loaded.config;
    config.host_id = args.host_id;
    config.gantry = gantry;
    if config.gantry != Gantry::Off && matches!(config.base, Base::Floating { .. }) {
        eprintln!(
            "the robot hangs on its gantry ({}): {}",
            config.gantry.word(),
            match config.gantry {
                Gantry::UntilEnabled => "released once every actuator is enabled",
                _ => "released by the web view's or Python's gantry_release",
            }
        );
    }
    config.state_file = args.state_file.clone();
    let kept = match &config.state_file {
        Some(path) => StateFile::load(path)?,
        None => StateFile::default(),
    };
    // Refused before the banner (the robot's spawn checks the same).
    sim::robot::check_kept_ids(&config, &kept)
        .with_context(|| format!("cannot start the robot of {}", args.file.display()))?;
    let summary = summary(&config, &kept);
    let served = open_buses(&args, &config).await?;
    let mut nodes = served.nodes.clone();
    let ui_taps = match &args.ui {
        Some(_) => config
            .buses
            .iter()
            .enumerate()
            .map(|(k, b)| Ok((b.name.clone(), served.tap(k)?, b.bitrate_bps)))
            .collect::<anyhow::Result<Vec<_>>>()?,
        None => Vec::new(),
    };
    nodes.extend(ui_taps.iter().map(|(_, node, _)| Arc::clone(node)));
    let (urdf, urdf_paths) = (config.urdf.clone(), config.urdf_paths.clone());
    let robot = RobotEmulator::spawn(config, served.nodes.clone())
        .with_context(|| format!("cannot start the robot of {}", args.file.display()))?;
    let ui = match &args.ui {
        Some(addr) => {
            let taps = ui_taps
                .into_iter()
                .map(|(name, node, bitrate)| (name, BusTap::spawn(node, bitrate)))
                .collect();
            let title = format!("{summary} on {}", served.place);
            let live = RobotLive::new(robot.monitor(), (&urdf, &urdf_paths), taps, &title);
            let server = armhil::ui::serve(addr, Arc::new(live)).await?;
            super::announce_ui("robot", &server);
            Some(server)
        }
        None => None,
    };
    tracing::info!(on = %served.place, "robot emulator running; Ctrl-C to stop");
    eprintln!(
        "armhil sim robot: {summary} on {} (Ctrl-C to stop)",
        served.place
    );
    let mut death = robot.death_watch();
    let stopped = super::until_stopped(&mut stop, &mut death).await;
    if let Some(ui) = ui {
        ui.shutdown().await;
    }
    robot.shutdown().await;
    for node in nodes {
        node.close().await;
    }
    if let Some(server) = served.server {
        server.shutdown().await;
    }
    super::outcome("robot", stopped, &death)
}

/// `robstride_arm6: can0 ids 1 2 3, can1 ids 4 5 6`, each actuator at the ID it answers on:
/// `3 (was 1 in the robot file)` for one a host moved in an earlier run (`kept` says).
fn summary(config: &RobotConfig, kept: &StateFile) -> String {
    let buses: Vec<String> = config
        .buses
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let ids: Vec<String> = config
                .actuators
                .iter()
                .filter(|a| a.bus == k)
                .map(|a| match a.actuator.power_on_id(&b.name, kept) {
                    id if id == a.actuator.can_id() => id.to_string(),
                    id => format!("{id} (was {} in the robot file)", a.actuator.can_id()),
                })
                .collect();
            format!("{} ids {}", b.name, ids.join(" "))
        })
        .collect();
    format!("{}: {}", config.name, buses.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::robstride::state_file::uid_key;
    use sim::robstride::PersistedMotor;

    fn arm6() -> RobotConfig {
        let file =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/robstride_arm6.yaml");
        load_robot_file(&file)
            .expect("robots/robstride_arm6.yaml loads")
            .config
    }

    /// A state file in which a host moved the first actuator of the first bus to `to`.
    fn moved_first(config: &RobotConfig, to: u8) -> StateFile {
        let mut kept = StateFile::default();
        let motor = config.actuators[0]
            .actuator
            .downcast_ref::<sim::robstride::MotorConfig>()
            .unwrap();
        kept.motors.insert(
            uid_key(motor.effective_uid()),
            PersistedMotor {
                can_id: to,
                master_id: sim::robstride::DEFAULT_HOST_ID,
                zero_offset_rad: 0.0,
                params: Default::default(),
                baud_code: 1,
                protocol: 0,
            },
        );
        kept
    }

    #[test]
    fn a_state_file_putting_two_actuators_of_one_bus_on_one_id_is_refused() {
        let mut config = arm6();
        config.state_file = Some("arm.json".into());
        let first = config.actuators[0].clone();
        let second = config
            .actuators
            .iter()
            .find(|a| a.bus == first.bus && a.joint != first.joint)
            .unwrap()
            .clone();
        let kept = moved_first(&config, second.actuator.can_id() as u8);
        let error = format!(
            "{:#}",
            sim::robot::check_kept_ids(&config, &kept).unwrap_err()
        );
        let bus = &config.buses[first.bus].name;
        for part in [
            format!("bus `{bus}`"),
            format!("joint `{}`", first.joint),
            format!("joint `{}`", second.joint),
            format!("CAN ID {}", second.actuator.can_id()),
            "arm.json".to_owned(),
        ] {
            assert!(error.contains(&part), "{part:?} missing from: {error}");
        }
        // Moved to a free ID: served there, and the summary says so.
        let kept = moved_first(&config, 100);
        sim::robot::check_kept_ids(&config, &kept).unwrap();
        let text = summary(&config, &kept);
        assert!(
            text.contains(&format!(
                "{bus} ids 100 (was {} in the robot file) ",
                first.actuator.can_id()
            )),
            "{text}"
        );
    }
}
