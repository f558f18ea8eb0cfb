//! Integration tests of the `armhil` crate, one test binary so a 2-core machine links it once
//! (`cargo test --test integration dbc` runs one module):
//!
//! - the drivers against the emulators on the virtual bus (`*_flow`, `arm_api`, `socketcand`);
//! - the `armhil` binary itself (`cli_errors`, `signals`, `long_run`) and the crate graph
//!   (`deps`), `decode_cli`;
//! - the two independent codecs against each other (`codec_cross_props`), the generated DBC
//!   (`dbc`), broken scenarios (`scenario_errors`) and every kept fuzz input
//!   (`fuzz_regressions`).

mod abuse;
mod arm_api;
mod cli_errors;
mod codec_cross_props;
mod corpus_robots;
mod dbc;
mod decode_cli;
mod deps;
mod fuzz_regressions;
mod long_run;
mod openarm;
mod piper_flow;
mod realman_flow;
mod robot_flow;
mod robstride_flow;
mod robstride_mit;
mod scenario_errors;
mod signals;
mod socketcand;
mod support;
