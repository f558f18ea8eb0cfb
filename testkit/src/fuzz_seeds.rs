//! The seed corpus of every fuzz target, built from the repository's test vectors
//! (`fixtures/`) and scenarios (`scenarios/`) in each target's input encoding.
//!
//! Generated at run time (`scripts/fuzz.sh` runs `cargo run -p armhil-testkit --example fuzz_seeds`), never
//! committed: the fixtures stay the single source.

use std::path::{Path, PathBuf};

use bus::candump::parse_log;
use bus::pcap::PcapWriter;
use bus::{CanFrame, ReceivedFrame};

/// Lines per candump seed: libFuzzer mutates small inputs best.
const LINES_PER_SEED: usize = 40;
/// Frames per seed of the frame-sequence targets.
const FRAMES_PER_SEED: usize = 48;

/// One seed: a file name (unique within its target) and its bytes.
pub type Seed = (String, Vec<u8>);

/// Every seed of `target`, read from the repository at `root`. Unknown targets have none.
pub fn seeds(target: &str, root: &Path) -> std::io::Result<Vec<Seed>> {
    let fixtures = root.join("fixtures");
    Ok(match target {
        "candump_reader" => candump_seeds(&fixtures)?,
        "pcap_reader" => per_log(&fixtures, pcap)?,
        "piper_driver_decode" => per_log(&fixtures.join("piper"), piper_decode)?,
        "piper_emulator" => per_log(&fixtures.join("piper"), piper_ops)?,
        "robstride_driver_decode" => per_log(&fixtures.join("robstride"), rs_decode)?,
        "robstride_emulator" => per_log(&fixtures.join("robstride"), rs_ops)?,
        "damiao_driver_decode" => per_log(&fixtures.join("damiao"), dm_decode)?,
        "damiao_emulator" => per_log(&fixtures.join("damiao"), dm_ops)?,
        "scenario_check" => files(&root.join("scenarios"), &["yaml", "yml"])?
            .into_iter()
            .map(|p| Ok((name_of(&p), std::fs::read(&p)?)))
            .collect::<std::io::Result<_>>()?,
        "realman_framing" => transcripts(&fixtures, |req, rep| [&[0u8][..], req, rep].concat())?,
        "realman_command" => transcripts(&fixtures, |req, _| req.to_vec())?,
        "realman_reply" => transcripts(&fixtures, |_, rep| [&[0u8][..], rep].concat())?,
        "urdf_reader" => files(&root.join("urdf"), &["urdf"])?
            .into_iter()
            .map(|p| Ok((name_of(&p), std::fs::read(&p)?)))
            .collect::<std::io::Result<_>>()?,
        _ => Vec::new(),
    })
}

/// `dir/a/b.log` → `a_b.log` (seed names stay unique across folders).
fn name_of(path: &Path) -> String {
    let parent = path
        .parent()
        .and_then(Path::file_name)
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let file = path.file_name().unwrap_or_default().to_string_lossy();
    format!("{parent}_{file}")
}

/// Files under `dir` (recursively) with one of `exts`, sorted.
fn files(dir: &Path, exts: &[&str]) -> std::io::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d)? {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
            } else if path
                .extension()
                .is_some_and(|e| exts.iter().any(|x| e == *x))
            {
                out.push(path);
            }
        }
    }
    out.sort();
    Ok(out)
}

fn candump_seeds(fixtures: &Path) -> std::io::Result<Vec<Seed>> {
    let mut out = Vec::new();
    for path in files(fixtures, &["log"])? {
        let text = std::fs::read_to_string(&path)?;
        let lines: Vec<&str> = text.lines().collect();
        for (i, chunk) in lines.chunks(LINES_PER_SEED).enumerate() {
            let seed = chunk.join("\n") + "\n";
            out.push((format!("{}.{i}", name_of(&path)), seed.into_bytes()));
        }
    }
    Ok(out)
}

/// One seed per `FRAMES_PER_SEED` frames of every candump fixture under `dir`.
fn per_log(dir: &Path, encode: impl Fn(&[ReceivedFrame]) -> Vec<u8>) -> std::io::Result<Vec<Seed>> {
    let mut out = Vec::new();
    for path in files(dir, &["log"])? {
        let text = std::fs::read_to_string(&path)?;
        // A fixture that does not read (the malformed-frame vectors) still seeds line by line.
        let frames: Vec<ReceivedFrame> = match parse_log(&text) {
            Ok(entries) => entries,
            Err(_) => text
                .lines()
                .filter_map(|l| bus::candump::parse_line(l.trim()).ok())
                .collect(),
        }
        .into_iter()
        .map(|e| ReceivedFrame {
            frame: e.frame,
            timestamp: e.timestamp,
        })
        .collect();
        for (i, chunk) in frames.chunks(FRAMES_PER_SEED).enumerate() {
            out.push((format!("{}.{i}", name_of(&path)), encode(chunk)));
        }
    }
    Ok(out)
}

fn pcap(frames: &[ReceivedFrame]) -> Vec<u8> {
    let mut writer = PcapWriter::new(Vec::new()).expect("writing to memory");
    for f in frames {
        writer.write(f).expect("writing to memory");
    }
    writer.finish().expect("writing to memory")
}

/// Length byte and payload as the harness reads them.
fn payload(out: &mut Vec<u8>, frame: &CanFrame) {
    out.push(frame.len() as u8);
    out.extend_from_slice(frame.data());
}

/// `piper_driver_decode`: raw-id selectors (0xC0 + 11-bit id, 0xF0 + 29-bit id).
fn piper_decode(frames: &[ReceivedFrame]) -> Vec<u8> {
    let mut out = Vec::new();
    for f in frames {
        if f.frame.is_extended() {
            out.push(0xF0);
            out.extend_from_slice(&f.frame.raw_id().to_be_bytes());
        } else {
            out.push(0xC0);
            out.extend_from_slice(&(f.frame.raw_id() as u16).to_be_bytes());
        }
        payload(&mut out, &f.frame);
    }
    out
}

/// `piper_emulator`: profile S-V1.8-2, then each frame with a raw 11-bit id (selector 0xE0)
/// followed by 10 ticks.
fn piper_ops(frames: &[ReceivedFrame]) -> Vec<u8> {
    let mut out = vec![2];
    for f in frames.iter().filter(|f| !f.frame.is_extended()) {
        out.extend_from_slice(&[1, 0xE0]);
        out.extend_from_slice(&(f.frame.raw_id() as u16).to_be_bytes());
        payload(&mut out, &f.frame);
        out.extend_from_slice(&[0, 9]);
    }
    out
}

/// `robstride_driver_decode`: host 0xFD, model RS01, each frame by comm type and data area.
fn rs_decode(frames: &[ReceivedFrame]) -> Vec<u8> {
    let mut out = vec![0xFD];
    for f in frames.iter().filter(|f| f.frame.is_extended()) {
        let id = f.frame.raw_id();
        out.extend_from_slice(&[1, ((id >> 24) & 0x1F) as u8]);
        out.extend_from_slice(&(((id >> 8) & 0xFFFF) as u16).to_be_bytes());
        let mut data = f.frame.data().to_vec();
        data.resize(8, 0);
        out.extend_from_slice(&data);
    }
    out
}

/// `robstride_emulator`: model RS01, each frame (motor 0x7F or another destination), then
/// 5 ticks.
fn rs_ops(frames: &[ReceivedFrame]) -> Vec<u8> {
    let mut out = vec![1];
    for f in frames.iter().filter(|f| f.frame.is_extended()) {
        let id = f.frame.raw_id();
        out.extend_from_slice(&[1, ((id >> 24) & 0x1F) as u8]);
        out.extend_from_slice(&(((id >> 8) & 0xFFFF) as u16).to_be_bytes());
        match (id & 0xFF) as u8 {
            0x7F => out.push(0),
            dst => out.extend_from_slice(&[0xF0, dst]),
        }
        if f.frame.len() == 8 {
            out.push(0);
        } else {
            out.extend_from_slice(&[0xF0, f.frame.len() as u8]);
        }
        out.extend_from_slice(f.frame.data());
        out.extend_from_slice(&[0, 4]);
    }
    out
}

/// `damiao_driver_decode`: model DM4310, each standard frame as an 8-byte frame (selector 0),
/// expecting the ESC_ID of the OpenArm convention (MST_ID − 0x10; ESC_ID 1 for the frames
/// below 0x11, the host's commands).
fn dm_decode(frames: &[ReceivedFrame]) -> Vec<u8> {
    let mut out = Vec::new();
    for f in frames.iter().filter(|f| !f.frame.is_extended()) {
        let id = f.frame.raw_id() as u16;
        let esc = if (0x11..0x7FF).contains(&id) {
            id - 0x10
        } else {
            1
        };
        out.push(1);
        out.extend_from_slice(&esc.to_be_bytes());
        out.push(0);
        out.extend_from_slice(&id.to_be_bytes());
        let mut data = f.frame.data().to_vec();
        data.resize(8, 0);
        out.extend_from_slice(&data);
    }
    out
}

/// `damiao_emulator`: model DM4310 (ESC_ID 1), each standard frame on its own identifier
/// (selector 7) with its own length, then 5 ticks.
fn dm_ops(frames: &[ReceivedFrame]) -> Vec<u8> {
    let mut out = vec![1];
    for f in frames.iter().filter(|f| !f.frame.is_extended()) {
        out.extend_from_slice(&[1, 7]);
        out.extend_from_slice(&(f.frame.raw_id() as u16).to_be_bytes());
        if f.frame.len() == 8 {
            out.push(0);
        } else {
            out.extend_from_slice(&[0xF0, f.frame.len() as u8]);
        }
        out.extend_from_slice(f.frame.data());
        out.extend_from_slice(&[0, 4]);
    }
    out
}

/// One seed per Realman transcript file: `make(requests, replies)` over its vectors'
/// wire text (requests and TCP replies, each in file order).
fn transcripts(
    fixtures: &Path,
    make: impl Fn(&[u8], &[u8]) -> Vec<u8>,
) -> std::io::Result<Vec<Seed>> {
    let mut out = Vec::new();
    for path in files(&fixtures.join("realman"), &["jsonl"])? {
        let text = std::fs::read_to_string(&path)?;
        let (mut requests, mut replies) = (Vec::new(), Vec::new());
        for line in text.lines().filter(|l| l.trim_start().starts_with('{')) {
            let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
                continue;
            };
            if let Some(r) = v.get("request").and_then(|r| r.as_str()) {
                requests.extend_from_slice(r.as_bytes());
            }
            for r in v
                .get("replies")
                .and_then(|r| r.as_array())
                .into_iter()
                .flatten()
            {
                replies.extend(r.as_str().unwrap_or_default().bytes());
            }
        }
        out.push((name_of(&path), make(&requests, &replies)));
    }
    Ok(out)
}
