//! The Piper driver.

mod client;
mod fixtures;
