//! The RobStride actuator emulator.

mod canopen;
mod conformance;
mod host_params;
mod mit;
mod on_bus;
mod physics;
