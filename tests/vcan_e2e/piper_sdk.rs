//! vcan end-to-end: piper_sdk (being built).
