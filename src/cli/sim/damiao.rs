//! `armhil sim damiao`: Damiao (DM) joint motors in real time on a SocketCAN interface or
//! behind a socketcand server.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::str::FromStr;
use std::sync::Arc;

use anyhow::Context;
use armhil::ui::bus_tap::BusTap;
use armhil::ui::damiao::DamiaoLive;
use sim::damiao::{DamiaoBus, DamiaoConfig, Model, MotorConfig, MAX_ID, OPENARM_MST_OFFSET};

use super::robstride::LoadSpec;
use super::served_bus::{Frames, ServeArgs, ServedBus};

/// Highest ESC_ID a motor may be given here: its force-position command goes to 0x300 +
/// ESC_ID, which must stay below the register identifier 0x7FF (as in robot files).
const MAX_ESC_ID: u16 = 0x4FE;

/// The identifiers the Damiao motors' command frames use besides ESC_ID itself: the
/// position-velocity, velocity and force-position commands (docs/protocols/damiao.md §2).
const COMMAND_OFFSETS: [u16; 4] = [0, 0x100, 0x200, 0x300];

/// The register and refresh identifier every motor listens on.
const REGISTER_ID: u16 = 0x7FF;

/// Arguments of `armhil sim damiao`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Where the motors answer.
    #[command(flatten)]
    pub bus: ServeArgs,
    /// A motor as ESC_ID:MODEL, e.g. `1:DM4310`, answering on ESC_ID + 0x10 (the OpenArm's
    /// convention), or ESC_ID:MODEL:FEEDBACK_ID to give its MST_ID, e.g. `0x01:DM4310:0x11`
    /// (repeat for more motors; default `1:DM4310`).
    #[arg(long = "motor", value_name = "ID:MODEL[:FEEDBACK_ID]")]
    pub motors: Vec<MotorSpec>,
    /// Load on every motor: `disc:MASS_KG:RADIUS_M`, `pendulum:MASS_KG:LENGTH_M` or `none`.
    #[arg(long, default_value = "disc:1.0:0.1")]
    pub load: LoadSpec,
    /// JSON file keeping each motor's saved registers (ids, CTRL_MODE, TIMEOUT, …) and zero
    /// across runs (the motors' flash).
    #[arg(long)]
    pub state_file: Option<PathBuf>,
    /// Serve a live web view (each motor's dial and strips, state, faults, bus figures) on
    /// HOST:PORT, e.g. `127.0.0.1:8000` (a bare port means 127.0.0.1).
    #[arg(long, value_name = "HOST:PORT")]
    pub ui: Option<String>,
}

/// `ID:MODEL[:FEEDBACK_ID]` from the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MotorSpec {
    /// Command identifier (ESC_ID).
    pub esc_id: u16,
    /// Model.
    pub model: Model,
    /// Feedback identifier (MST_ID).
    pub mst_id: u16,
}

impl FromStr for MotorSpec {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = text.split(':').collect();
        let (esc, model, mst) = match parts.as_slice() {
            [esc, model] => (esc, model, None),
            [esc, model, mst] => (esc, model, Some(mst)),
            _ => {
                return Err(format!(
                    "expected ID:MODEL or ID:MODEL:FEEDBACK_ID (e.g. 1:DM4310 or 0x01:DM4310:0x11), got {text:?}"
                ))
            }
        };
        let esc_id = parse_id(esc, "ESC_ID", 1, MAX_ESC_ID)?;
        let model = Model::named(model)?;
        let mst_id = match mst {
            Some(mst) => parse_id(mst, "feedback id", 0, MAX_ID)?,
            None => esc_id + OPENARM_MST_OFFSET,
        };
        Ok(Self {
            esc_id,
            model,
            mst_id,
        })
    }
}

/// A decimal or `0x` hexadecimal identifier within `min..=max`.
fn parse_id(text: &str, what: &str, min: u16, max: u16) -> Result<u16, String> {
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u16::from_str_radix(hex, 16),
        None => text.parse(),
    };
    match parsed {
        Ok(id) if (min..=max).contains(&id) => Ok(id),
        _ => Err(format!(
            "{what} {text:?} must be {min}..={max} (0x{min:X}..=0x{max:X})"
        )),
    }
}

/// `armhil sim damiao` (registered in [`super::served_kinds`]).
pub(crate) struct Kind;

impl super::served::ServedKind for Kind {
    const NAME: &'static str = "damiao";
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

/// The motors of `args` (default `1:DM4310`), refused when one would answer on an
/// identifier another motor takes commands on: that motor would read each reply as a command.
fn config(args: &Args) -> anyhow::Result<DamiaoConfig> {
    let specs = if args.motors.is_empty() {
        vec![MotorSpec {
            esc_id: 1,
            model: Model::DM4310,
            mst_id: 1 + OPENARM_MST_OFFSET,
        }]
    } else {
        args.motors.clone()
    };
    check_ids(&specs)?;
    let motors = specs
        .iter()
        .map(|spec| {
            MotorConfig::new(spec.esc_id, spec.model)
                .with_mst_id(spec.mst_id)
                .with_load(args.load.0)
        })
        .collect();
    let mut config = DamiaoConfig::new(motors);
    config.state_file = args.state_file.clone();
    Ok(config)
}

/// Two motors on one ESC_ID, or a motor answering on an identifier some motor takes commands
/// on (its ESC_ID, 0x100/0x200/0x300 + ESC_ID, or 0x7FF), named with both.
fn check_ids(specs: &[MotorSpec]) -> anyhow::Result<()> {
    for (k, a) in specs.iter().enumerate() {
        if let Some(b) = specs[..k].iter().find(|b| b.esc_id == a.esc_id) {
            anyhow::bail!(
                "--motor {} and --motor {}: two motors on ESC_ID {} would answer every frame together",
                shown(b),
                shown(a),
                a.esc_id
            );
        }
    }
    for a in specs {
        if a.mst_id == REGISTER_ID {
            anyhow::bail!(
                "--motor {}: its feedback id 0x7FF is the register identifier every motor listens on",
                shown(a)
            );
        }
        for b in specs {
            if let Some(offset) = COMMAND_OFFSETS.iter().find(|&&o| b.esc_id + o == a.mst_id) {
                let whose = if a == b {
                    "its own".to_owned()
                } else {
                    format!("motor {}'s", b.esc_id)
                };
                let which = match offset {
                    0 => "MIT and special commands",
                    0x100 => "position-velocity commands",
                    0x200 => "velocity commands",
                    _ => "force-position commands",
                };
                anyhow::bail!(
                    "--motor {}: it would answer on 0x{:03X}, the identifier of {whose} {which}; \
                     give it another feedback id (ID:MODEL:FEEDBACK_ID)",
                    shown(a),
                    a.mst_id
                );
            }
        }
    }
    Ok(())
}

/// A motor as the command line gives it, its feedback id in full.
fn shown(spec: &MotorSpec) -> String {
    format!(
        "{}:{}:0x{:02X}",
        spec.esc_id,
        spec.model.name(),
        spec.mst_id
    )
}

/// Serve until `stop` asks (a signal, or the rig this device is part of stopping).
pub(crate) async fn serve(args: Args, mut stop: super::StopSource) -> anyhow::Result<ExitCode> {
    let config = config(&args)?;
    // Damiao motors answer CAN FD as well as classic frames: FD sockets on SocketCAN.
    let served = ServedBus::open_for(&args.bus, stop.rig_buses(), Frames::Fd).await?;
    let place = served.place();
    let bus = served.node("damiao")?;
    let ui_tap = args.ui.as_ref().map(|_| served.node("ui")).transpose()?;
    let configured = config.motors.clone();
    let emulator = DamiaoBus::spawn(config, Arc::clone(&bus))
        .with_context(|| format!("cannot start the Damiao emulator on {place}"))?;
    // The ids the motors answer on: a state file keeps the ones a host gave them.
    let powered: Vec<(u16, u16)> = emulator
        .power_on_ids()
        .iter()
        .copied()
        .zip(emulator.power_on_mst_ids().iter().copied())
        .collect();
    let motors: Vec<String> = configured
        .iter()
        .zip(&powered)
        .map(|(m, (esc, _))| format!("{esc}:{}", m.model.name()))
        .collect();
    let ui = match &args.ui {
        Some(addr) => {
            let tap = ui_tap.map(|t| BusTap::spawn(t, 1_000_000));
            let title = format!("Damiao {} on {place}", motors.join(", "));
            let live = DamiaoLive::new(emulator.monitor(), tap, &title);
            let server = armhil::ui::serve(addr, Arc::new(live)).await?;
            super::announce_ui("damiao", &server);
            Some(server)
        }
        None => None,
    };
    tracing::info!(on = %place, motors = ?motors, "Damiao emulator running; Ctrl-C to stop");
    eprintln!(
        "{}",
        banner(&configured, &powered, &place, args.state_file.as_deref())
    );
    let mut death = emulator.death_watch();
    let stopped = super::until_stopped(&mut stop, &mut death).await;
    if let Some(ui) = ui {
        ui.shutdown().await;
    }
    emulator.shutdown().await;
    bus.close().await;
    served.shutdown().await;
    super::outcome("Damiao", stopped, &death)
}

/// What `armhil sim damiao` says once it serves: each motor at the ESC_ID it takes commands on
/// and the feedback id it answers on (`powered`, in the order of `motors`, as configured).
/// When a state file moved any (a host's write of ESC_ID or MST_ID and a save in an earlier
/// run), one line per motor says what the command line gave it, so that nobody addresses a
/// motor where it no longer is.
fn banner(
    motors: &[MotorConfig],
    powered: &[(u16, u16)],
    place: &str,
    state_file: Option<&Path>,
) -> String {
    let moved = motors
        .iter()
        .zip(powered)
        .any(|(m, &(esc, mst))| (m.esc_id, m.mst_id) != (esc, mst));
    if !moved {
        let motors: Vec<String> = motors
            .iter()
            .map(|m| {
                format!(
                    "{}:{} (feedback 0x{:03X})",
                    m.esc_id,
                    m.model.name(),
                    m.mst_id
                )
            })
            .collect();
        return format!(
            "armhil sim damiao: {} on {place} (Ctrl-C to stop)",
            motors.join(", ")
        );
    }
    let file = state_file.map_or(String::new(), |f| format!(" {}", f.display()));
    let mut text = format!(
        "armhil sim damiao: {} motors on {place} (Ctrl-C to stop), at the ids the state \
         file{file} keeps:",
        motors.len()
    );
    for (m, &(esc, mst)) in motors.iter().zip(powered) {
        let was = if (m.esc_id, m.mst_id) == (esc, mst) {
            String::new()
        } else {
            format!(
                " (was {} with feedback 0x{:03X} on the command line)",
                m.esc_id, m.mst_id
            )
        };
        text.push_str(&format!(
            "\n  motor {esc}{was}: {}, feedback 0x{mst:03X}",
            m.model.name()
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> Result<MotorSpec, String> {
        text.parse()
    }

    #[test]
    fn motor_arguments_parse_with_an_optional_feedback_id() {
        assert_eq!(
            spec("1:DM4310"),
            Ok(MotorSpec {
                esc_id: 1,
                model: Model::DM4310,
                mst_id: 0x11
            })
        );
        assert_eq!(
            spec("0x02:dm4340:0x21"),
            Ok(MotorSpec {
                esc_id: 2,
                model: Model::DM4340,
                mst_id: 0x21
            })
        );
        assert_eq!(spec("3:DM-J4310-2EC").map(|s| s.model), Ok(Model::DM4310));
        for bad in [
            "0:DM4310",
            "0x4FF:DM4310",
            "1:DM9999",
            "1",
            "1:DM4310:0x800",
            "1:DM4310:2:3",
        ] {
            assert!(spec(bad).is_err(), "{bad}");
        }
        assert!(spec("1:DM9999")
            .unwrap_err()
            .contains("unknown Damiao model `DM9999`"));
    }

    #[test]
    fn a_feedback_id_on_a_command_identifier_is_refused_naming_both_motors() {
        let specs = |texts: &[&str]| -> Vec<MotorSpec> {
            texts.iter().map(|t| t.parse().unwrap()).collect()
        };
        assert!(check_ids(&specs(&["1:DM4310", "2:DM4340", "8:DM4310"])).is_ok());
        let error = check_ids(&specs(&["1:DM4310", "0x11:DM4310"]))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains(
                "--motor 1:DM4310:0x11: it would answer on 0x011, the identifier of motor 17's MIT"
            ),
            "{error}"
        );
        let own = check_ids(&specs(&["1:DM4310:0x101"]))
            .unwrap_err()
            .to_string();
        assert!(own.contains("its own position-velocity commands"), "{own}");
        let twice = check_ids(&specs(&["1:DM4310", "1:DM4340:0x21"]))
            .unwrap_err()
            .to_string();
        assert!(twice.contains("two motors on ESC_ID 1"), "{twice}");
        assert!(check_ids(&specs(&["1:DM4310:0x7FF"])).is_err());
    }

    #[test]
    fn the_banner_lists_each_motor_with_its_feedback_id_and_says_what_a_state_file_moved() {
        let motors = [
            MotorConfig::new(1, Model::DM8009),
            MotorConfig::new(2, Model::DM4340),
        ];
        assert_eq!(
            banner(&motors, &[(1, 0x11), (2, 0x12)], "vcan0", None),
            "armhil sim damiao: 1:DM8009 (feedback 0x011), 2:DM4340 (feedback 0x012) on vcan0 \
             (Ctrl-C to stop)"
        );
        assert_eq!(
            banner(
                &motors,
                &[(5, 0x25), (2, 0x12)],
                "vcan0",
                Some(Path::new("dm.json"))
            ),
            "armhil sim damiao: 2 motors on vcan0 (Ctrl-C to stop), at the ids the state file \
             dm.json keeps:\n  motor 5 (was 1 with feedback 0x011 on the command line): \
             DM8009, feedback 0x025\n  motor 2: DM4340, feedback 0x012"
        );
    }
}
