//! `armhil sim piper`: the Piper firmware emulator in real time on a SocketCAN interface or
//! behind a socketcand server.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::Context;
use armhil::ui::bus_tap::BusTap;
use armhil::ui::piper::PiperLive;
use bus::CanBus;
use sim::piper::{FirmwareProfile, Flash, LinkageRole, PiperConfig, PiperEmulator};

use super::served_bus::{ServeArgs, ServedBus};

/// The Piper's CAN bit rate (for the web view's bus load).
const PIPER_BITRATE_BPS: u32 = 1_000_000;

/// Arguments of `armhil sim piper`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Where the emulator answers.
    #[command(flatten)]
    pub bus: ServeArgs,
    /// Firmware to impersonate: S-V1.5-8, S-V1.6-3, S-V1.8-2 or S-V1.8-8.
    #[arg(long, default_value = "S-V1.8-2")]
    pub firmware: FirmwareProfile,
    /// JSON file keeping the "flash" parameters (limits, zero offsets, collision levels, …)
    /// across runs; created on the first change.
    #[arg(long)]
    pub state_file: Option<PathBuf>,
    /// Leader/follower role in flash at power-on (a leader is a teach-input arm that sends
    /// its joints as commands for a follower on its bus). A state file that exists keeps
    /// the role it holds.
    #[arg(long, value_enum)]
    pub role: Option<Role>,
    /// URDF to simulate instead of the bundled urdf/piper.urdf.
    #[arg(long)]
    pub urdf: Option<PathBuf>,
    /// Joint angles at power-on, degrees, comma-separated J1..J6.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub initial_joints_deg: Option<Vec<f64>>,
    /// Record every frame on the interface until stopped (Ctrl-C or SIGTERM): a pcap when the
    /// name ends in `.pcap`, else a candump log.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Physics steps (1 ms each) per wake-up of the emulator: 5 = one wake-up per 200 Hz
    /// feedback group (less CPU, up to 4 ms extra command latency); 1 = every millisecond.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=25))]
    pub ticks_per_wake: u32,
    /// Most missed milliseconds of physics one wake-up catches up (default 100). On a machine
    /// too slow for real-time physics (an emulated VM) a small value, e.g. 5, lets the
    /// emulator fall behind the wall clock instead of starving its clients.
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub max_catch_up_ms: Option<u64>,
    /// Serve a live web view (the arm in 3D, joint strips, controller state, bus figures and a
    /// fault panel) on HOST:PORT, e.g. `127.0.0.1:8000` (a bare port means 127.0.0.1).
    #[arg(long, value_name = "HOST:PORT")]
    pub ui: Option<String>,
}

/// `--role`: the arm's leader/follower role in flash.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Role {
    /// Teach-input arm.
    Leader,
    /// Motion-output arm (the factory setting).
    Follower,
}

/// `armhil sim piper` (registered in [`super::served_kinds`]).
pub(crate) struct Kind;

impl super::served::ServedKind for Kind {
    const NAME: &'static str = "piper";
    const OUTPUT_KEYS: &'static [&'static str] = &["state_file", "record"];
    type Args = Args;

    fn paths_mut(args: &mut Args) -> Vec<&mut PathBuf> {
        [&mut args.state_file, &mut args.urdf, &mut args.record]
            .into_iter()
            .flatten()
            .collect()
    }

    fn serve(
        args: Args,
        stop: super::StopSource,
    ) -> impl std::future::Future<Output = anyhow::Result<ExitCode>> + Send {
        serve(args, stop)
    }
}

fn initial_joints_rad(args: &Args) -> anyhow::Result<[f64; 6]> {
    let Some(deg) = &args.initial_joints_deg else {
        return Ok([0.0; 6]);
    };
    let arr: [f64; 6] = deg
        .as_slice()
        .try_into()
        .map_err(|_| anyhow::anyhow!("--initial-joints-deg needs 6 values, got {}", deg.len()))?;
    Ok(arr.map(f64::to_radians))
}

/// Serve until `stop` asks (a signal, or the rig this device is part of stopping).
pub(crate) async fn serve(args: Args, mut stop: super::StopSource) -> anyhow::Result<ExitCode> {
    let config = PiperConfig {
        firmware: args.firmware,
        initial_joints_rad: initial_joints_rad(&args)?,
        state_file: args.state_file.clone(),
        urdf_path: args.urdf.clone(),
        ticks_per_wake: args.ticks_per_wake,
        max_catch_up_steps: args.max_catch_up_ms,
        flash: args.role.map(|role| Flash {
            linkage_role: match role {
                Role::Leader => LinkageRole::Leader,
                Role::Follower => LinkageRole::Follower,
            },
            ..Flash::default()
        }),
        ..PiperConfig::default()
    };
    let served = ServedBus::open(&args.bus, stop.rig_buses()).await?;
    let place = served.place();
    let bus = served.node("piper")?;
    let tap = args
        .record
        .as_ref()
        .map(|_| served.node("recorder"))
        .transpose()?;
    let ui_tap = args.ui.as_ref().map(|_| served.node("ui")).transpose()?;
    let recorder = match (&args.record, tap) {
        (Some(path), Some(tap)) => Some(start_recorder(tap, served.channel(), path)?),
        _ => None,
    };
    let urdf = match &args.urdf {
        // Bounded and type-checked like every file a user names (a FIFO or /dev/zero here
        // would otherwise hang or fill memory).
        Some(path) => sim::bounded_read::read_regular_file(path, sim::physics::MAX_URDF_BYTES)
            .map_err(anyhow::Error::from)
            .and_then(|bytes| String::from_utf8(bytes).context("not UTF-8 text"))
            .with_context(|| format!("cannot read URDF {}", path.display()))?,
        None => sim::piper::BUNDLED_URDF.to_owned(),
    };
    let emu = PiperEmulator::spawn(Arc::clone(&bus), config)
        .with_context(|| format!("cannot start the Piper emulator on {place}"))?;
    let ui = match &args.ui {
        Some(addr) => {
            let tap = ui_tap.map(|t| BusTap::spawn(t, PIPER_BITRATE_BPS));
            let title = format!("Piper {} on {place}", args.firmware);
            let live = PiperLive::new(emu.monitor(), tap, &urdf, &title);
            let server = armhil::ui::serve(addr, Arc::new(live)).await?;
            super::announce_ui("piper", &server);
            Some(server)
        }
        None => None,
    };
    tracing::info!(
        on = %place,
        firmware = %args.firmware,
        "Piper emulator running; Ctrl-C to stop"
    );
    eprintln!(
        "armhil sim piper: {} on {place} (Ctrl-C to stop)",
        args.firmware
    );
    let mut death = emu.death_watch();
    let stopped = super::until_stopped(&mut stop, &mut death).await;
    // Frames per ID per second, feedback periods and overruns: whether the emulator kept up.
    if let Some(ui) = ui {
        ui.shutdown().await;
    }
    eprint!("armhil sim piper: timing\n{}", emu.stats());
    emu.shutdown().await;
    bus.close().await;
    if let Some(rec) = recorder {
        rec.stop().await?;
    }
    served.shutdown().await;
    super::outcome("Piper", stopped, &death)
}

/// A task that writes every frame seen on the interface to a candump log or a pcap (by the
/// file's extension).
struct Recorder {
    stop: tokio::sync::watch::Sender<bool>,
    task: tokio::task::JoinHandle<anyhow::Result<()>>,
}

impl Recorder {
    async fn stop(self) -> anyhow::Result<()> {
        let _ = self.stop.send(true);
        self.task.await.context("recorder task failed")?
    }
}

/// Write what `tap` receives (a second socket on the interface, or a silent node on the
/// socketcand bus: both see the emulator's and the clients' frames) to `path`. The file is
/// flushed every second, so even a killed process leaves at most a second unwritten, and
/// finished (flushed and synced) when the recorder stops.
fn start_recorder(
    tap: Arc<dyn CanBus>,
    channel: &str,
    path: &std::path::Path,
) -> anyhow::Result<Recorder> {
    let mut file = bus::recorder::Recorder::create(path, channel)
        .with_context(|| format!("cannot create {}", path.display()))?;
    let (stop, mut stopped) = tokio::sync::watch::channel(false);
    let shown = path.display().to_string();
    let task = tokio::spawn(async move {
        let mut flush = tokio::time::interval(std::time::Duration::from_secs(1));
        let outcome = loop {
            tokio::select! {
                r = tap.recv() => match r {
                    Ok(frame) => {
                        if let Err(e) = file.write(&frame) {
                            break Err(anyhow::Error::new(e).context(format!("cannot write {shown}")));
                        }
                    }
                    Err(bus::BusError::Closed) => break Ok(()),
                    Err(e) => tracing::warn!(error = %e, "recorder receive error"),
                },
                _ = flush.tick() => {
                    if let Err(e) = file.flush() {
                        break Err(anyhow::Error::new(e).context(format!("cannot write {shown}")));
                    }
                }
                _ = stopped.changed() => break Ok(()),
            }
        };
        tap.close().await;
        let frames = file
            .finish()
            .with_context(|| format!("cannot finish {shown}"))?;
        tracing::info!(frames, path = %shown, "recording finished");
        outcome
    });
    Ok(Recorder { stop, task })
}
