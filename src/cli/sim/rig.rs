//! `armhil sim rig FILE`: several devices in one process from a rig file — two Piper arms
//! on two interfaces, Realman controllers on several ports, robots — each served as its own
//! `armhil sim KIND` would serve it, all stopped together.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use armhil::rigs::{load_rig_file, RigDevice, RigFile, SimKind};
use tokio::sync::watch;
use tokio::task::JoinSet;

use super::served::RigEntry;
use super::served_bus::RigBuses;
use super::StopSource;

/// Arguments of `armhil sim rig`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The rig file (`rigs/bimanual_piper.yaml`, grammar in `rigs/README.md`).
    pub file: PathBuf,
}

/// clap's message without its usage block, with its `--option` words as the file's keys
/// (`'--ifac'` → `ifac:`).
fn clap_message(error: &clap::Error) -> String {
    let rendered = error.render().to_string();
    let message: Vec<&str> = rendered
        .lines()
        .take_while(|line| !line.starts_with("Usage:") && !line.starts_with("For more information"))
        .map(str::trim)
        .filter(|line| !line.is_empty())
        .collect();
    // A line ending in ':' introduces the next ("not provided:" <FILE>).
    let mut text = String::new();
    for line in message {
        if !text.is_empty() {
            text.push_str(if text.ends_with(':') { " " } else { "; " });
        }
        text.push_str(line);
    }
    let text = text.strip_prefix("error: ").unwrap_or(&text);
    as_keys(text)
}

/// `'--state-file <STATE_FILE>'` → `state_file:` wherever clap names an option, and a
/// missing positional (`<FILE>`) → `file:`.
fn as_keys(text: &str) -> String {
    let text = positional_as_key(text);
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(start) = rest.find("'--") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 3..];
        let end = after.find('\'').unwrap_or(after.len());
        let option = after[..end].split([' ', '=']).next().unwrap_or("");
        out.push_str(&format!("`{}:`", option.replace('-', "_")));
        rest = after.get(end + 1..).unwrap_or("");
    }
    out.push_str(rest);
    out
}

/// clap names a missing positional argument `<FILE>` on a line of its own.
fn positional_as_key(text: &str) -> String {
    match text.rsplit_once(' ') {
        Some((head, last)) if last.starts_with('<') && last.ends_with('>') => {
            format!("{head} `{}:`", last[1..last.len() - 1].to_lowercase())
        }
        _ => text.to_owned(),
    }
}

/// Parse a device's options with its kind's own parser and resolve its paths against the
/// rig file's folder.
fn parse(device: &RigDevice, dir: &Path) -> anyhow::Result<Box<dyn RigEntry>> {
    let (_, parse_entry) = super::SERVED
        .iter()
        .find(|(kind, _)| *kind == device.kind)
        .ok_or_else(|| anyhow::anyhow!("{}", device.error("no such kind is served")))?;
    let mut args =
        parse_entry(device).map_err(|e| anyhow::anyhow!("{}", device.error(clap_message(&e))))?;
    for path in args.paths_mut() {
        if path.is_relative() {
            *path = dir.join(&*path);
        }
    }
    Ok(args)
}

/// Serve every device of the rig file until Ctrl-C, or until one of them stops on its own
/// (it could not start, or it died), which stops the others.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let kinds: Vec<SimKind> = super::SERVED.iter().map(|(kind, _)| *kind).collect();
    let rig = load_rig_file(&args.file, &kinds)?;
    let devices = rig
        .devices
        .iter()
        .map(|d| Ok((d.name.clone(), d.kind, parse(d, rig.dir())?)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    super::real_time_runtime()?.block_on(serve(&rig, devices))
}

async fn serve(
    rig: &RigFile,
    devices: Vec<(String, SimKind, Box<dyn RigEntry>)>,
) -> anyhow::Result<ExitCode> {
    let mut signals = StopSource::signals()?;
    let (stop, stop_request) = watch::channel(None);
    let mut running = JoinSet::new();
    let count = devices.len();
    let buses = std::sync::Arc::new(RigBuses::default());
    for (name, kind, args) in devices {
        let stop = StopSource::Rig {
            request: stop_request.clone(),
            buses: std::sync::Arc::clone(&buses),
        };
        running.spawn(async move { (name, kind, args.serve(stop).await) });
    }
    eprintln!(
        "armhil sim rig: {count} devices from {} (Ctrl-C to stop them all)",
        rig.file.display()
    );
    let mut failures = Vec::new();
    let mut record = |joined: Result<(String, SimKind, anyhow::Result<ExitCode>), _>| match joined {
        Ok((_, _, Ok(_))) => {}
        Ok((name, kind, Err(e))) => failures.push(format!(
            "device `{name}` ({}): {}",
            kind.name(),
            super::super::error_text(&e)
        )),
        Err(e) => failures.push(format!("a device's task failed: {e}")),
    };
    // The first of: a stop signal, or a device ending by itself (which nothing asked for).
    tokio::select! {
        signal = signals.next() => {
            let _ = stop.send(Some(signal));
        }
        Some(joined) = running.join_next() => {
            record(joined);
            let _ = stop.send(Some("a device stopped"));
        }
    }
    while let Some(joined) = running.join_next().await {
        record(joined);
    }
    if failures.is_empty() {
        return Ok(ExitCode::SUCCESS);
    }
    Err(anyhow::anyhow!(
        "{} of {count} devices of {} failed:\n  {}",
        failures.len(),
        rig.file.display(),
        failures.join("\n  ")
    ))
    .context("the rig stopped")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_rig_file_loads_and_each_device_takes_its_options() {
        let kinds: Vec<SimKind> = super::super::SERVED.iter().map(|(kind, _)| *kind).collect();
        let rigs = Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs");
        let mut files = 0;
        for entry in std::fs::read_dir(&rigs).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().and_then(|e| e.to_str()) != Some("yaml") {
                continue;
            }
            let rig =
                load_rig_file(&path, &kinds).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for device in &rig.devices {
                parse(device, rig.dir()).unwrap_or_else(|e| panic!("{e:#}"));
            }
            files += 1;
        }
        assert!(files >= 4, "only {files} rig files in {}", rigs.display());
    }

    /// Two devices of a rig writing one file (a recording, a state file) are refused when
    /// the file loads, at the later one's line, naming both devices and the file, whatever
    /// the spelling of the path.
    #[test]
    fn two_devices_writing_one_file_are_refused_at_load() {
        let kinds: Vec<SimKind> = super::super::SERVED.iter().map(|(kind, _)| *kind).collect();
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("rig.yaml");
        let shared = |name: &str| dir.path().join(name).display().to_string();
        let cases = [
            (
                "devices:\n  a: {kind: piper, iface: can0, record: both.log}\n  b: {kind: piper, iface: can1, record: ./both.log}\n",
                ":3:",
                "both.log",
            ),
            (
                "devices:\n  arm: {kind: realman, state_file: s.json}\n  motors: {kind: robstride, state-file: sub/../s.json}\n",
                ":3:",
                "s.json",
            ),
            (
                "devices:\n  z: {kind: robstride, state_file: x.json}\n  a: {kind: piper, record: x.json}\n",
                ":3:",
                "x.json",
            ),
        ];
        for (text, line, name) in cases {
            let text = text.to_owned();
            std::fs::write(&file, &text).unwrap();
            let error = match load_rig_file(&file, &kinds) {
                Ok(_) => panic!("accepted:\n{text}"),
                Err(e) => e.to_string(),
            };
            let devices: Vec<&str> = text
                .lines()
                .skip(1)
                .map(|l| l.trim().split(':').next().unwrap())
                .collect();
            let at = format!("{}{line}", file.display());
            for part in [at.as_str(), devices[0], devices[1], &shared(name)] {
                assert!(error.contains(part), "{part:?} missing from: {error}");
            }
        }
        // The same name in two folders is two files.
        std::fs::write(
            &file,
            "devices:\n  a: {kind: piper, iface: can0, record: l/x.log}\n  b: {kind: piper, iface: can1, record: r/x.log}\n",
        )
        .unwrap();
        load_rig_file(&file, &kinds).unwrap();
    }

    /// Every file a device writes is resolved against the rig file's folder, as the load
    /// compares them.
    #[test]
    fn every_output_is_resolved_against_the_rig_file() {
        let kinds: Vec<SimKind> = super::super::SERVED.iter().map(|(kind, _)| *kind).collect();
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("rig.yaml");
        let mut text = "devices:\n".to_owned();
        for kind in &kinds {
            let outputs: Vec<String> = kind
                .output_keys
                .iter()
                .map(|key| format!(", {key}: out/{}-{key}", kind.name))
                .collect();
            let file_key = if kind.positional_keys.contains(&"file") {
                ", file: robot.yaml"
            } else {
                ""
            };
            text.push_str(&format!(
                "  {0}: {{kind: {0}{1}{file_key}}}\n",
                kind.name,
                outputs.concat()
            ));
        }
        std::fs::write(&file, text).unwrap();
        let rig = load_rig_file(&file, &kinds).unwrap();
        for device in &rig.devices {
            let mut args = parse(device, rig.dir()).unwrap_or_else(|e| panic!("{e:#}"));
            let resolved: Vec<PathBuf> = args.paths_mut().into_iter().map(|p| p.clone()).collect();
            for key in device.kind.output_keys {
                let want = dir.path().join(format!("out/{}-{key}", device.kind.name));
                assert!(
                    resolved.contains(&want),
                    "{}: {want:?} not in {resolved:?}",
                    device.name
                );
            }
        }
    }

    #[test]
    fn clap_words_become_the_file_s_keys() {
        assert_eq!(
            as_keys(
                "unexpected argument '--ifac' found; tip: a similar argument exists: '--iface'"
            ),
            "unexpected argument `ifac:` found; tip: a similar argument exists: `iface:`"
        );
        assert_eq!(
            as_keys("invalid value 'x' for '--state-file <STATE_FILE>'"),
            "invalid value 'x' for `state_file:`"
        );
        assert_eq!(
            as_keys("the following required arguments were not provided: <FILE>"),
            "the following required arguments were not provided: `file:`"
        );
    }
}
