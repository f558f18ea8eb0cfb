//! Scenario model, runner and reports (being built).
