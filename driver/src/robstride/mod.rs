//! RobStride actuator driver (being built).
