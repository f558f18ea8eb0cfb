//! The Realman controller emulator.

mod controller;
mod fixtures;
mod io;
mod kinematics;
mod plant;
mod server;
