//! `armhil sim robstride`: RobStride actuators in real time on a SocketCAN interface or behind
//! a socketcand server.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::str::FromStr;
use std::sync::Arc;

use anyhow::Context;
use armhil::ui::bus_tap::BusTap;
use armhil::ui::robstride::RobstrideLive;
use sim::robstride::{
    Load, Model, MotorConfig, PlantKind, RangeTable, RobstrideBus, RobstrideConfig,
};

use super::served_bus::{ServeArgs, ServedBus};

/// Arguments of `armhil sim robstride`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Where the motors answer.
    #[command(flatten)]
    pub bus: ServeArgs,
    /// A motor as ID:MODEL, e.g. `1:RS03` (repeat for more motors; default `127:RS03`).
    #[arg(long = "motor", value_name = "ID:MODEL")]
    pub motors: Vec<MotorSpec>,
    /// Load on every motor: `disc:MASS_KG:RADIUS_M`, `pendulum:MASS_KG:LENGTH_M` or `none`.
    #[arg(long, default_value = "disc:1.0:0.1")]
    pub load: LoadSpec,
    /// Scaling table: `manual` (default) or `sdk`.
    #[arg(long, default_value = "manual")]
    pub ranges: String,
    /// Move the rigs in the rapier3d physics world (the rig's URDF) instead of the built-in
    /// one-joint integrator.
    #[arg(long)]
    pub world_physics: bool,
    /// Host ID the motors answer to until a host speaks.
    #[arg(long, default_value_t = 0xFD)]
    pub host_id: u8,
    /// JSON file keeping saved parameters, CAN IDs, zeros and baud/protocol switches across
    /// runs (the motors' flash).
    #[arg(long)]
    pub state_file: Option<PathBuf>,
    /// Serve a live web view (each motor's dial and strips, faults, bus figures) on
    /// HOST:PORT, e.g. `127.0.0.1:8000` (a bare port means 127.0.0.1).
    #[arg(long, value_name = "HOST:PORT")]
    pub ui: Option<String>,
}

/// `ID:MODEL` from the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MotorSpec {
    /// CAN ID.
    pub can_id: u8,
    /// Model.
    pub model: Model,
}

impl FromStr for MotorSpec {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let (id, model) = text
            .split_once(':')
            .ok_or_else(|| format!("expected ID:MODEL (e.g. 1:RS03), got {text:?}"))?;
        let can_id = parse_id(id)?;
        let model = Model::named(model)?;
        Ok(Self { can_id, model })
    }
}

fn parse_id(text: &str) -> Result<u8, String> {
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => text.parse(),
    };
    match parsed {
        Ok(id) if (1..=0x7F).contains(&id) => Ok(id),
        _ => Err(format!("CAN ID {text:?} must be 1..=127")),
    }
}

/// `--load` from the command line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadSpec(pub Load);

impl FromStr for LoadSpec {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = text.split(':').collect();
        let number = |s: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("{s:?} is not a positive number"))
        };
        match parts.as_slice() {
            ["none"] => Ok(Self(Load::None)),
            ["disc", mass, radius] => Ok(Self(Load::Disc {
                mass_kg: number(mass)?,
                radius_m: number(radius)?,
            })),
            ["pendulum", mass, length] => Ok(Self(Load::Pendulum {
                mass_kg: number(mass)?,
                length_m: number(length)?,
            })),
            _ => Err(format!(
                "expected none, disc:MASS:RADIUS or pendulum:MASS:LENGTH, got {text:?}"
            )),
        }
    }
}

/// `armhil sim robstride` (registered in [`super::served_kinds`]).
pub(crate) struct Kind;

impl super::served::ServedKind for Kind {
    const NAME: &'static str = "robstride";
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

fn config(args: &Args) -> anyhow::Result<RobstrideConfig> {
    let table = match args.ranges.to_ascii_lowercase().as_str() {
        "manual" => RangeTable::Manual,
        "sdk" => RangeTable::Sdk,
        other => anyhow::bail!("--ranges must be manual or sdk, got {other:?}"),
    };
    let specs = if args.motors.is_empty() {
        vec![MotorSpec {
            can_id: 0x7F,
            model: Model::RS03,
        }]
    } else {
        args.motors.clone()
    };
    let motors = specs
        .iter()
        .map(|spec| {
            let mut motor = MotorConfig::new(spec.can_id, spec.model).with_load(args.load.0);
            motor.range_table = table;
            if args.world_physics {
                motor.plant = PlantKind::World;
            }
            motor
        })
        .collect();
    let mut config = RobstrideConfig::new(motors);
    config.host_id = args.host_id;
    config.state_file = args.state_file.clone();
    Ok(config)
}

/// Serve until `stop` asks (a signal, or the rig this device is part of stopping).
pub(crate) async fn serve(args: Args, mut stop: super::StopSource) -> anyhow::Result<ExitCode> {
    let config = config(&args)?;
    let served = ServedBus::open(&args.bus, stop.rig_buses()).await?;
    let place = served.place();
    let bus = served.node("robstride")?;
    let ui_tap = args.ui.as_ref().map(|_| served.node("ui")).transpose()?;
    let bitrate_bps = config.bus_bitrate_bps;
    let configured = config.motors.clone();
    let emulator = RobstrideBus::spawn(Arc::clone(&bus), config)
        .with_context(|| format!("cannot start the RobStride emulator on {place}"))?;
    // The IDs the motors answer on: a state file keeps the ones a host gave them.
    let ids = emulator.power_on_ids().to_vec();
    let motors: Vec<String> = configured
        .iter()
        .zip(&ids)
        .map(|(m, id)| format!("{id}:{}", m.model.name()))
        .collect();
    let ui = match &args.ui {
        Some(addr) => {
            let tap = ui_tap.map(|t| BusTap::spawn(t, bitrate_bps));
            let title = format!("RobStride {} on {place}", motors.join(", "));
            let live = RobstrideLive::new(emulator.monitor(), tap, &ids, &title);
            let server = armhil::ui::serve(addr, Arc::new(live)).await?;
            super::announce_ui("robstride", &server);
            Some(server)
        }
        None => None,
    };
    tracing::info!(on = %place, motors = ?motors, "RobStride emulator running; Ctrl-C to stop");
    eprintln!(
        "{}",
        banner(&configured, &ids, &place, args.state_file.as_deref())
    );
    let mut death = emulator.death_watch();
    let stopped = super::until_stopped(&mut stop, &mut death).await;
    if let Some(ui) = ui {
        ui.shutdown().await;
    }
    emulator.shutdown().await;
    bus.close().await;
    served.shutdown().await;
    super::outcome("RobStride", stopped, &death)
}

/// What `armhil sim robstride` says once it serves: the motors at the CAN IDs they answer on
/// (`ids`, in the order of `motors`, as configured). When a state file moved any (a host's
/// "set CAN ID" in an earlier run), one line per motor says which ID it had on the command
/// line, so that nobody addresses a motor where it no longer is.
fn banner(motors: &[MotorConfig], ids: &[u8], place: &str, state_file: Option<&Path>) -> String {
    let moved = motors.iter().zip(ids).any(|(m, id)| m.can_id != *id);
    if !moved {
        let motors: Vec<String> = motors
            .iter()
            .map(|m| format!("{}:{}", m.can_id, m.model.name()))
            .collect();
        return format!(
            "armhil sim robstride: {} on {place} (Ctrl-C to stop)",
            motors.join(", ")
        );
    }
    let file = state_file.map_or(String::new(), |f| format!(" {}", f.display()));
    let mut text = format!(
        "armhil sim robstride: {} motors on {place} (Ctrl-C to stop), at the CAN IDs the \
         state file{file} keeps:",
        motors.len()
    );
    for (m, id) in motors.iter().zip(ids) {
        let was = if m.can_id == *id {
            String::new()
        } else {
            format!(" (was {} on the command line)", m.can_id)
        };
        text.push_str(&format!("\n  motor {id}{was}: {}", m.model.name()));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_banner_lists_each_motor_at_the_id_it_answers_on() {
        let motors = [
            MotorConfig::new(1, Model::RS03),
            MotorConfig::new(2, Model::RS02),
        ];
        assert_eq!(
            banner(&motors, &[1, 2], "vcan0", Some(Path::new("rs.json"))),
            "armhil sim robstride: 1:RS03, 2:RS02 on vcan0 (Ctrl-C to stop)"
        );
        assert_eq!(
            banner(&motors, &[3, 2], "vcan0", Some(Path::new("rs.json"))),
            "armhil sim robstride: 2 motors on vcan0 (Ctrl-C to stop), at the CAN IDs the \
             state file rs.json keeps:\n  motor 3 (was 1 on the command line): RS03\n  motor 2: RS02"
        );
    }

    #[test]
    fn motor_and_load_arguments_parse() {
        assert_eq!(
            "1:RS03".parse::<MotorSpec>(),
            Ok(MotorSpec {
                can_id: 1,
                model: Model::RS03
            })
        );
        assert_eq!("0x7f:rs00".parse::<MotorSpec>().map(|s| s.can_id), Ok(0x7F));
        assert!("0:RS03".parse::<MotorSpec>().is_err());
        assert!("200:RS03".parse::<MotorSpec>().is_err());
        assert!("1:RS09".parse::<MotorSpec>().is_err());
        assert!("1".parse::<MotorSpec>().is_err());
        assert_eq!(
            "pendulum:1.5:0.3".parse::<LoadSpec>(),
            Ok(LoadSpec(Load::Pendulum {
                mass_kg: 1.5,
                length_m: 0.3
            }))
        );
        assert!("disc:-1:0.1".parse::<LoadSpec>().is_err());
    }
}
