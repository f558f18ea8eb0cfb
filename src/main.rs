//! `armhil`: emulate robot arms on CAN and TCP, drive them from scenarios, record the bus.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cli;

/// Hardware-in-the-loop simulator and driver test harness for robot arms.
#[derive(Debug, Parser)]
#[command(name = "armhil", version, about, long_about = None)]
struct Cli {
    /// More log output (-v debug, -vv trace). `RUST_LOG` overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,

    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Record a CAN interface to a candump log (.log) or pcap (.pcap) until Ctrl-C.
    Record(cli::record::Args),
    /// Replay a candump log onto a CAN interface with its original timing.
    Replay(cli::replay::Args),
    /// Run a firmware emulator in real time on a CAN interface.
    Sim(cli::sim::Args),
    /// Run scenario files or folders against the emulators and report a verdict.
    Run(cli::run::Args),
    /// Validate scenario files without running them.
    Check(cli::check::Args),
    /// Print every frame of a candump log or pcap decoded with units (driver codecs).
    Decode(cli::decode::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // `run` and `check` print their own verdicts; the emulator's and driver's progress logs
    // would drown them, so those two start at `warn`.
    let base_level = match cli.command {
        Command::Run(_) | Command::Check(_) | Command::Decode(_) => "warn",
        _ => "info",
    };
    cli::logging::init(cli.verbose, base_level);
    let outcome = match cli.command {
        Command::Record(args) => cli::record::run(args),
        Command::Replay(args) => cli::replay::run(args),
        Command::Sim(args) => cli::sim::run(args),
        Command::Run(args) => cli::run::run(args),
        Command::Check(args) => cli::check::run(args),
        Command::Decode(args) => cli::decode::run(args),
    };
    match outcome {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {}", cli::error_text(&error));
            ExitCode::FAILURE
        }
    }
}
