//! vcan end-to-end: scenarios (being built).
