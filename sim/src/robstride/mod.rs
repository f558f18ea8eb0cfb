//! RobStride actuator emulator (being built).
