//! AgileX Piper firmware emulator (being built).
