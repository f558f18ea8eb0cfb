//! robstride_flow (being built).
