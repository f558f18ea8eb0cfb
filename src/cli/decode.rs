//! `armhil decode`: print every frame of a candump log or pcap/pcapng capture decoded with
//! units (the Piper's and RobStride's through the driver's codecs, Damiao's by a decoder of
//! its own, `armhil::devices::damiao::decode_damiao`): by one protocol (`--device`, one of the
//! protocols the registered device kinds own, [`armhil::devices::wire_decoders`]), or by the
//! devices of a scenario's bench (`--scenario`), each frame named by the device that owns it,
//! as the report names them. The options (`--host-id`, `--model`, `--motor`) are handed to the
//! protocol as written; it resolves them through its own tables and names a flag that does
//! not fit it.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use armhil::devices::{wire_decoders, WireDecode, WireMotor, WireOptions};
use armhil::interop::DecodedFrame;
use bus::{CanFrame, CanId};

/// The protocol decoded with when neither `--device` nor `--scenario` says.
const DEFAULT_DEVICE: &str = "piper";

/// `--device`'s values: the protocols of the registered device kinds, each with its help line
/// (listed by `armhil decode --help`, suggested from when mistyped).
fn device_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        wire_decoders().map(|d| clap::builder::PossibleValue::new(d.name).help(d.help)),
    )
}

/// Arguments of `armhil decode`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// candump `-L` log (`.log`), pcap (`.pcap`) or pcapng capture (`.pcapng`, one interface
    /// per bus, as `armhil run` records a bench of several buses).
    pub file: PathBuf,
    /// Protocol to decode with (default: piper).
    #[arg(long, value_parser = device_names(), conflicts_with = "scenario")]
    pub device: Option<String>,
    /// Decode with the devices of this scenario's bench: each frame by the device that owns
    /// it (a robot's actuators, a Piper and a RobStride bus side by side), as its report does.
    #[arg(long, value_name = "SCENARIO")]
    pub scenario: Option<PathBuf>,
    /// RobStride: the host id replies are addressed to (default 253, 0xFD).
    #[arg(long, conflicts_with = "scenario")]
    pub host_id: Option<u8>,
    /// RobStride: the model whose ranges scale every frame (RS00 … RS06, EL05; default RS03).
    #[arg(long, conflicts_with = "scenario")]
    pub model: Option<String>,
    /// A motor on the bus: the id it is commanded on, its model and, for a Damiao motor, the id
    /// it answers on (ESC_ID + 0x10 unless given), e.g. `1:DM8009`, `0x01:DM4310:0x11` or
    /// `3:RS00`; its model's ranges scale its frames (repeat for more motors). Damiao: default
    /// `1:DM4310`; RobStride: only the listed motors' frames, each by its own model.
    #[arg(
        long = "motor",
        value_name = "ID:MODEL[:FEEDBACK_ID]",
        conflicts_with = "scenario"
    )]
    pub motors: Vec<WireMotor>,
}

/// The largest capture read (whole, into memory, so bounded by what a laptop holds): 4 GiB,
/// sixty-four times a recording at `armhil run`'s default limit.
const MAX_CAPTURE_BYTES: u64 = 4 * 1024 * 1024 * 1024;

/// One frame of the capture: when, on which bus (pcapng and candump name their interfaces;
/// a pcap does not), and the frame.
struct Captured {
    at: Duration,
    bus: Option<String>,
    frame: CanFrame,
}

/// The frames of a capture, and whether its lines name their bus (a pcapng, or a candump log
/// of several interfaces; a log of one reads as it always has).
struct Capture {
    frames: Vec<Captured>,
    names_buses: bool,
}

/// The capture's bytes: a regular file (not a FIFO or `/dev/zero`) of at most
/// [`MAX_CAPTURE_BYTES`].
fn read_capture_bytes(path: &Path) -> anyhow::Result<Vec<u8>> {
    sim::bounded_read::read_regular_file(path, MAX_CAPTURE_BYTES).map_err(|e| {
        anyhow::anyhow!(
            "cannot read {}: {}",
            path.display(),
            match e {
                sim::bounded_read::BoundedReadError::TooLarge { limit_bytes } => format!(
                    "larger than the {} GiB this command reads (record with a smaller --max-recording-mib)",
                    limit_bytes / (1024 * 1024 * 1024)
                ),
                other => other.to_string(),
            }
        )
    })
}

fn read_frames(path: &Path) -> anyhow::Result<Capture> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("pcap") => {
            let frames = bus::pcap::parse_capture(&read_capture_bytes(path)?)
                .with_context(|| format!("{} is not a readable pcap", path.display()))?;
            Ok(Capture {
                frames: frames
                    .into_iter()
                    .map(|r| Captured {
                        at: r.timestamp,
                        bus: None,
                        frame: r.frame,
                    })
                    .collect(),
                names_buses: false,
            })
        }
        Some("pcapng") => {
            let capture = bus::pcapng::parse_capture(&read_capture_bytes(path)?)
                .with_context(|| format!("{} is not a readable pcapng", path.display()))?;
            let names = capture.interfaces;
            Ok(Capture {
                frames: capture
                    .frames
                    .into_iter()
                    .map(|(interface, r)| Captured {
                        at: r.timestamp,
                        bus: Some(
                            names
                                .get(interface as usize)
                                .filter(|n| !n.is_empty())
                                .cloned()
                                .unwrap_or_else(|| format!("if{interface}")),
                        ),
                        frame: r.frame,
                    })
                    .collect(),
                names_buses: true,
            })
        }
        _ => {
            let bytes = read_capture_bytes(path)?;
            let text = String::from_utf8(bytes).map_err(|_| {
                anyhow::anyhow!("{} is not a candump log (not text)", path.display())
            })?;
            let entries = bus::candump::parse_log(&text)
                .with_context(|| format!("{} is not a readable candump log", path.display()))?;
            // A log of several interfaces (a bench of several buses) names each line's bus,
            // as a pcapng does; a log of one reads as it always has.
            let several = entries.iter().any(|e| e.iface != entries[0].iface);
            Ok(Capture {
                frames: entries
                    .into_iter()
                    .map(|e| Captured {
                        at: e.timestamp,
                        bus: Some(e.iface),
                        frame: e.frame,
                    })
                    .collect(),
                names_buses: several,
            })
        }
    }
}

/// How frames are named: one protocol, or the devices of a bench.
enum Decoder {
    Protocol(WireDecode),
    Bench(Box<armhil::harness::result::BenchInfo>),
}

/// The decoder of the protocol named `name` with `options`, or an error naming the known
/// ones or the option the protocol refuses.
fn protocol(name: &str, options: &WireOptions) -> anyhow::Result<WireDecode> {
    match wire_decoders().find(|d| d.name == name) {
        Some(wire) => (wire.decoder)(options).map_err(|e| anyhow::anyhow!("{e}")),
        None => {
            let known: Vec<&str> = wire_decoders().map(|d| d.name).collect();
            anyhow::bail!(
                "unknown device `{name}`; known: {}{}",
                known.join(", "),
                sim::yaml_words::suggestion(name, &known)
            )
        }
    }
}

impl Decoder {
    fn of(args: &Args) -> anyhow::Result<Self> {
        if let Some(path) = &args.scenario {
            let scenario =
                armhil::harness::load_scenario(path).map_err(|e| anyhow::anyhow!("{e}"))?;
            // The devices the scenario's report names frames with, in the same order.
            let bench = armhil::harness::report::bench_info(&scenario);
            anyhow::ensure!(
                !bench.frame_decoders.is_empty(),
                "{}: no device on its bench speaks CAN",
                path.display()
            );
            return Ok(Self::Bench(Box::new(bench)));
        }
        let options = WireOptions {
            host_id: args.host_id,
            model: args.model.clone(),
            motors: args.motors.clone(),
        };
        Ok(Self::Protocol(protocol(
            args.device.as_deref().unwrap_or(DEFAULT_DEVICE),
            &options,
        )?))
    }

    /// The frame's name and fields, or why it does not decode; `bus` is the bus the capture
    /// says it was on.
    fn decode(
        &self,
        bus: Option<&str>,
        frame: &CanFrame,
    ) -> (Option<DecodedFrame>, Option<String>) {
        match self {
            Self::Protocol(decode) => match decode(frame) {
                Ok(d) => (d, None),
                Err(e) => (None, Some(e)),
            },
            Self::Bench(bench) => (bench.decode(bus, frame), None),
        }
    }
}

/// One output line: `t  id  name  field=value unit …` (`raw=…` when nothing decodes it).
/// A pcapng capture's lines name the bus after the time: `t  can2  id  name …`.
fn line(
    t_s: f64,
    bus: Option<&str>,
    frame: &CanFrame,
    decoded: Option<DecodedFrame>,
    error: Option<String>,
) -> String {
    let id = match frame.id() {
        CanId::Standard(id) => format!("{id:03X}"),
        CanId::Extended(id) => format!("{id:08X}"),
    };
    let mut out = format!("{t_s:.6}  ");
    if let Some(bus) = bus {
        out.push_str(&printable(bus));
        out.push_str("  ");
    }
    out.push_str(&id);
    out.push_str("  ");
    match (decoded, error) {
        (Some(d), _) => {
            out.push_str(&d.name);
            for f in d.fields {
                out.push_str("  ");
                out.push_str(&f.name);
                out.push('=');
                out.push_str(&f.value);
                if !f.unit.is_empty() {
                    out.push(' ');
                    out.push_str(f.unit);
                }
            }
        }
        (None, error) => {
            let raw: String = frame.data().iter().map(|b| format!("{b:02X}")).collect();
            out.push_str("?  raw=");
            out.push_str(&raw);
            if let Some(e) = error {
                out.push_str("  error=\"");
                out.push_str(&e);
                out.push('"');
            }
        }
    }
    out
}

/// `name` with its control characters escaped (`\u{1b}`): an interface name comes from the
/// capture, and a terminal must not act on what a file says.
fn printable(name: &str) -> std::borrow::Cow<'_, str> {
    if !name.chars().any(char::is_control) {
        return name.into();
    }
    name.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_unicode().to_string()
            } else {
                c.to_string()
            }
        })
        .collect::<String>()
        .into()
}

/// Runs `armhil decode`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let decoder = Decoder::of(&args)?;
    let capture = read_frames(&args.file)?;
    let start = capture.frames.first().map_or(Duration::ZERO, |c| c.at);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for captured in capture.frames {
        let t_s = captured.at.saturating_sub(start).as_secs_f64();
        let bus = captured.bus.as_deref();
        let (decoded, error) = decoder.decode(bus, &captured.frame);
        let text = line(
            t_s,
            bus.filter(|_| capture.names_buses),
            &captured.frame,
            decoded,
            error,
        );
        use std::io::Write as _;
        if let Err(e) = writeln!(out, "{text}") {
            // A closed pipe (`| head`) ends the listing quietly.
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                return Ok(ExitCode::SUCCESS);
            }
            return Err(e.into());
        }
    }
    Ok(ExitCode::SUCCESS)
}
