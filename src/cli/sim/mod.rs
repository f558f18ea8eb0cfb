//! `armhil sim <device>`: a firmware emulator in real time on a real interface.

use std::process::ExitCode;

use clap::Subcommand;

pub mod piper;
pub mod realman;
pub mod robstride;

/// Arguments of `armhil sim`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    device: Device,
}

#[derive(Debug, Subcommand)]
enum Device {
    /// AgileX Piper 6-DoF arm (CAN, 11-bit IDs).
    Piper(piper::Args),
    /// Realman arm controller (JSON over TCP, realtime push over UDP).
    Realman(realman::Args),
    /// RobStride actuators (CAN, 29-bit IDs), any number on one bus.
    Robstride(robstride::Args),
}

/// Run the chosen emulator until Ctrl-C.
pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    match args.device {
        Device::Piper(args) => piper::run(args),
        Device::Realman(args) => realman::run(args),
        Device::Robstride(args) => robstride::run(args),
    }
}
