//! The Piper emulator.

mod dynamics;
mod faults;
mod fixtures;
mod mit_friction;
mod motion;
mod on_bus;
mod physics;
mod protocol;
mod vectors;
