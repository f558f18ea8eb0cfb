//! Bench files: several devices served by one `armhil sim bench` process — two Piper arms on
//! two interfaces, Realman controllers on several ports, robots (grammar: `rigs/README.md`).
//!
//! A device entry is its `armhil sim KIND` command written as YAML: `kind:` names the
//! subcommand and every other key is one of its options without the dashes
//! (`state_file: x.json` is `--state-file x.json`), so a bench file takes exactly what the
//! command line takes and the command checks it the same way. [`load_bench_file`] reads the
//! file into one option list per device; the CLI parses each and reports its mistakes at the
//! device's line ([`BenchDevice::error`]).

mod load;

pub use load::{load_bench_file, BenchDevice, BenchFile, BenchFileError, SimKind};

#[cfg(test)]
mod tests;
