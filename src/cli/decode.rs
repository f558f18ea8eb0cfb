//! `armhil decode`: print every frame of a candump log or pcap capture decoded with units,
//! through the driver's codecs.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use armhil::interop::{decode_piper, decode_robstride, decode_robstride_mit, DecodedFrame};
use bus::{CanFrame, CanId};

/// Which protocol the capture carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Device {
    /// AgileX Piper (11-bit ids).
    Piper,
    /// RobStride actuators (29-bit ids, private protocol).
    Robstride,
    /// RobStride actuators switched to the MIT variant (11-bit ids).
    RobstrideMit,
}

/// Arguments of `armhil decode`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// candump `-L` log (`.log`) or pcap capture (`.pcap`).
    pub file: PathBuf,
    /// Protocol to decode with.
    #[arg(long, value_enum, default_value_t = Device::Piper)]
    pub device: Device,
    /// RobStride: the host id replies are addressed to.
    #[arg(long, default_value_t = 0xFD)]
    pub host_id: u8,
    /// RobStride: the model whose ranges scale status frames (RS00 … RS06, EL05).
    #[arg(long, default_value = "RS03")]
    pub model: String,
}

fn read_frames(path: &Path) -> anyhow::Result<Vec<(Duration, CanFrame)>> {
    let is_pcap = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pcap"));
    if is_pcap {
        let bytes =
            std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        let frames = bus::pcap::parse_capture(&bytes)
            .with_context(|| format!("{} is not a readable pcap", path.display()))?;
        Ok(frames.into_iter().map(|r| (r.timestamp, r.frame)).collect())
    } else {
        let entries = bus::candump::read_log(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        Ok(entries
            .into_iter()
            .map(|e| (e.timestamp, e.frame))
            .collect())
    }
}

/// One output line: `t  id  name  field=value unit …` (`raw=…` when nothing decodes it).
fn line(
    t_s: f64,
    frame: &CanFrame,
    decoded: Option<DecodedFrame>,
    error: Option<String>,
) -> String {
    let id = match frame.id() {
        CanId::Standard(id) => format!("{id:03X}"),
        CanId::Extended(id) => format!("{id:08X}"),
    };
    let mut out = format!("{t_s:.6}  {id}  ");
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

/// Runs `armhil decode`.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let model = driver::robstride::Model::parse(&args.model)
        .with_context(|| format!("unknown RobStride model {:?}", args.model))?;
    let frames = read_frames(&args.file)?;
    let start = frames.first().map_or(Duration::ZERO, |(t, _)| *t);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (t, frame) in frames {
        let t_s = t.saturating_sub(start).as_secs_f64();
        let (decoded, error) = match args.device {
            Device::Piper => match decode_piper(&frame) {
                Ok(d) => (d, None),
                Err(e) => (None, Some(e.to_string())),
            },
            Device::Robstride => (decode_robstride(&frame, args.host_id, model), None),
            Device::RobstrideMit => (decode_robstride_mit(&frame, args.host_id, model), None),
        };
        use std::io::Write as _;
        if let Err(e) = writeln!(out, "{}", line(t_s, &frame, decoded, error)) {
            // A closed pipe (`| head`) ends the listing quietly.
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                return Ok(ExitCode::SUCCESS);
            }
            return Err(e.into());
        }
    }
    Ok(ExitCode::SUCCESS)
}
