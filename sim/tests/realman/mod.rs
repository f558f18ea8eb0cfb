//! The Realman controller emulator.

mod firmware;
mod fixtures;
mod io;
mod kinematics;
mod plant;
mod server;
