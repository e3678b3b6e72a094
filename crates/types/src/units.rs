//! Unit conversions, defined once: every crate converts with these.

/// rad/s → rpm: 60 / (2π), written 30 / π (the same double: scaling by 2 is exact).
pub const RAD_S_TO_RPM: f64 = 30.0 / std::f64::consts::PI;
