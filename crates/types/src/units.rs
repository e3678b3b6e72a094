//! Unit conversions, defined once: every crate converts with these.

/// rad/s → rpm: 60 / (2π), written 30 / π (the same double: scaling by 2 is exact).
pub const RAD_S_TO_RPM: f64 = 30.0 / std::f64::consts::PI;

/// rpm → rad/s: 2π / 60, written π / 30.
pub const RPM_TO_RAD_S: f64 = std::f64::consts::PI / 30.0;
