//! The RobStride driver.

mod conformance;
mod mit;
mod routing;
