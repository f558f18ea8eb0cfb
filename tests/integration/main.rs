//! Integration tests that run the drivers against the emulators on the virtual bus.

mod arm_api;
mod cli_errors;
mod deps;
mod long_run;
mod piper_flow;
mod realman_flow;
mod robstride_flow;
mod signals;
mod socketcand;
mod support;
