//! vcan end-to-end: piper_driver (being built).
