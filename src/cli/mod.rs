//! One module per subcommand; each exposes clap `Args` and a `run` that builds its own runtime.

pub mod check;
pub mod decode;
pub mod logging;
pub mod record;
pub mod replay;
pub mod run;
pub mod sim;
