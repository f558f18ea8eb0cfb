//! piper_flow (being built).
