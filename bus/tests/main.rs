//! Integration tests of the bus layer (`bus`), one test binary for the crate:
//!
//! - `socketcand`: our socketcand client against our socketcand server over real TCP.
//! - `tools`: the recorders' files read by the programs people open them with (can-utils,
//!   tshark); skipped with one line each when those are not installed, failed instead under
//!   `ARMHIL_REQUIRE_TOOLS=1`.

mod socketcand;
mod tools;
