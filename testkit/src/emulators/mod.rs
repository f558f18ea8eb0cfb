//! Emulators started the way tests need them: on a fresh in-process virtual bus (Piper) or on
//! in-memory streams under the paused clock (Realman), with a client beside each.

pub mod piper;
pub mod realman;
