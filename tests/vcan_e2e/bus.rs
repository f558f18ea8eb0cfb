//! vcan end-to-end: bus (being built).
