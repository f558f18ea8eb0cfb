//! AgileX Piper driver (being built).
