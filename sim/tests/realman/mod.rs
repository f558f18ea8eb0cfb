//! The Realman controller emulator.

mod controller;
mod fixtures;
mod kinematics;
mod plant;
mod server;
