//! The RobStride actuator emulator.

mod conformance;
mod host_params;
mod mit;
mod on_bus;
mod physics;
