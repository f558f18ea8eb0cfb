//! Rig files: several devices served by one `armhil sim rig` process — two Piper arms on
//! two interfaces, Realman controllers on several ports, robots (grammar: `rigs/README.md`).
//!
//! A device entry is its `armhil sim KIND` command written as YAML: `kind:` names the
//! subcommand and every other key is one of its options without the dashes
//! (`state_file: x.json` is `--state-file x.json`), so a rig file takes exactly what the
//! command line takes and the command checks it the same way. [`load_rig_file`] reads the
//! file into one option list per device; the CLI parses each and reports its mistakes at the
//! device's line ([`RigDevice::error`]).

mod load;

pub use load::{load_rig_file, RigDevice, RigFile, RigFileError, SimKind};

#[cfg(test)]
mod tests;
