//! The RobStride driver.

mod conformance;
mod routing;
