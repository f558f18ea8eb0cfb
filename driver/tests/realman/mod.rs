//! The Realman driver.

mod client;
mod fixtures;
