//! The RobStride actuator emulator.

mod conformance;
mod on_bus;
mod physics;
