//! vcan end-to-end: robstride (being built).
