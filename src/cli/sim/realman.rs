//! `armhil sim realman`: the Realman arm-controller emulator in real time on TCP (JSON
//! commands) and UDP (realtime push), for the vendor SDK or any other client.

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::process::ExitCode;

use std::sync::Arc;
use std::time::Duration;

use anyhow::Context;
use armhil::ui::realman::RealmanLive;
use sim::realman::model::ArmModel;
use sim::realman::{ControllerConfig, EmulatorConfig, FirmwareProfile, RealmanEmulator, Transport};

/// Arguments of `armhil sim realman`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Address to listen on (TCP commands and the UDP push). Anything but loopback lets other
    /// machines command the arm (the protocol has no authentication); a warning says so.
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: IpAddr,
    /// TCP port of the JSON command server (the controller's is 8080).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Arm model reported as Product_version (RM65-B, RM75-B).
    #[arg(long, default_value = "RM65-B")]
    pub model: String,
    /// Controller firmware to impersonate: V1.7.0 (`err` arrays) or V1.6.5 (`arm_err`/`sys_err`).
    #[arg(long, default_value = "V1.7.0")]
    pub firmware: FirmwareProfile,
    /// JSON file keeping the controller's settings and the arm's pose across runs (written
    /// atomically by `save_device_info_all` and at exit).
    #[arg(long)]
    pub state_file: Option<PathBuf>,
    /// Joint angles at power-on when the state file has none, degrees, comma-separated.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub initial_joints_deg: Option<Vec<f64>>,
    /// Most simultaneous TCP clients; further connections are closed at once.
    #[arg(long, default_value_t = sim::realman::server::DEFAULT_MAX_CONNECTIONS)]
    pub max_connections: usize,
    /// Close a TCP client after this many seconds without a byte either way (0: never). When
    /// every slot is taken, a new client also takes the slot of one idle for 10 s.
    #[arg(long, value_name = "S", default_value_t = sim::realman::server::DEFAULT_IDLE_TIMEOUT.as_secs())]
    pub idle_timeout_s: u64,
    /// Physics steps (1 ms each) per wake-up of the emulator (1 = every millisecond).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=10))]
    pub ticks_per_wake: u32,
    /// Run without a gripper on the flange.
    #[arg(long)]
    pub no_gripper: bool,
    /// Serve a live web view (the arm in 3D, joint strips, controller state, TCP clients, UDP
    /// push targets and a fault panel) on HOST:PORT, e.g. `127.0.0.1:8000` (a bare port means
    /// 127.0.0.1).
    #[arg(long, value_name = "HOST:PORT")]
    pub ui: Option<String>,
}

/// `armhil sim realman` (registered in [`super::served_kinds`]).
pub(crate) struct Kind;

impl super::served::ServedKind for Kind {
    const NAME: &'static str = "realman";
    const OUTPUT_KEYS: &'static [&'static str] = &["state_file"];
    type Args = Args;

    fn paths_mut(args: &mut Args) -> Vec<&mut PathBuf> {
        args.state_file.iter_mut().collect()
    }

    fn serve(
        args: Args,
        stop: super::StopSource,
    ) -> impl std::future::Future<Output = anyhow::Result<ExitCode>> + Send {
        serve(args, stop)
    }
}

/// Serve until `stop` asks (a signal, or the rig this device is part of stopping).
pub(crate) async fn serve(args: Args, mut stop: super::StopSource) -> anyhow::Result<ExitCode> {
    let model = ArmModel::from_product(&args.model)
        .with_context(|| format!("unknown Realman model {:?} (try RM65-B)", args.model))?;
    let urdf = sim::realman::plant::urdf_for(&model);
    let mut controller = ControllerConfig::new(model);
    controller.firmware = args.firmware;
    controller.state_file = args.state_file.clone();
    controller.gripper = !args.no_gripper;
    controller.initial_joints_rad = args
        .initial_joints_deg
        .as_ref()
        .map(|deg| deg.iter().map(|d| d.to_radians()).collect());
    let mut config = EmulatorConfig::new(controller);
    config.max_connections = args.max_connections;
    config.ticks_per_wake = args.ticks_per_wake;
    config.idle_timeout =
        (args.idle_timeout_s > 0).then(|| Duration::from_secs(args.idle_timeout_s));
    let addr = SocketAddr::new(args.bind, args.port);
    let emu = RealmanEmulator::spawn(config, Transport::Tcp(addr))
        .await
        .with_context(|| format!("cannot start the Realman emulator on {addr}"))?;
    let bound = emu.local_addr().unwrap_or(addr);
    if let Some(warning) = super::public_warning(
        "the Realman JSON/TCP port",
        bound,
        "command the emulated arm (power, motion, settings; the protocol has no authentication)",
    ) {
        eprintln!("{warning}");
    }
    tracing::info!(%bound, model = %args.model, firmware = %args.firmware, "Realman emulator running; Ctrl-C to stop");
    eprintln!(
        "armhil sim realman: {} ({}) on tcp://{bound} (Ctrl-C to stop)",
        args.model, args.firmware
    );
    let ui = match (&args.ui, urdf) {
        (Some(ui_addr), Some(urdf)) => {
            let title = format!(
                "Realman {} ({}) on tcp://{bound}",
                args.model, args.firmware
            );
            let live = RealmanLive::new(emu.monitor(), urdf, &title);
            let server = armhil::ui::serve(ui_addr, Arc::new(live)).await?;
            super::announce_ui("realman", &server);
            Some(server)
        }
        (Some(_), None) => anyhow::bail!("no URDF to draw {} in the web view", args.model),
        (None, _) => None,
    };
    let mut death = emu.death_watch();
    let stopped = super::until_stopped(&mut stop, &mut death).await;
    if let Some(ui) = ui {
        ui.shutdown().await;
    }
    let stats = emu.stats();
    // A state file that cannot be written is an error (D19): the settings would be lost.
    let saved = emu.shutdown_and_save().await;
    tracing::info!(
        accepted = stats.accepted,
        refused = stats.refused,
        overruns = stats.overruns,
        datagrams = stats.push.sent,
        "Realman emulator stopped"
    );
    saved.context("the Realman emulator could not keep its settings")?;
    super::outcome("Realman", stopped, &death)
}
