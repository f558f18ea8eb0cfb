//! Integration tests that run the drivers against the emulators on the virtual bus.

mod arm_api;
mod deps;
mod piper_flow;
mod realman_flow;
mod robstride_flow;
mod socketcand;
