//! The Realman driver.

mod client;
mod fixtures;
mod shared_push;
