//! Unit conversions, defined once: every crate converts with these (a tidy
//! test refuses an rpm factor written anywhere else).

use std::f64::consts::PI;

/// rad/s → rpm: 60 / (2π), written 30 / π (the same double: scaling by 2 is exact).
pub const RAD_S_TO_RPM: f64 = 30.0 / PI;

/// rpm → rad/s: 2π / 60, written π / 30.
pub const RPM_TO_RAD_S: f64 = PI / 30.0;

/// rpm → rad/s as rpm · 2π / 60, rounded in that order (the simulator's set-point
/// and every caller that compares with it get the same double; `rpm · RPM_TO_RAD_S`
/// may differ from it in the last bit).
pub fn rpm_to_rad_s(rpm: f64) -> f64 {
    rpm * 2.0 * PI / 60.0
}

/// rad/s → rpm as ω · 60 / (2π), rounded in that order (the inverse of
/// [`rpm_to_rad_s`] as the diagnosis and the simulator's stick test write it).
pub fn rad_s_to_rpm(omega_rad_s: f64) -> f64 {
    omega_rad_s * 60.0 / (2.0 * PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_agree_with_the_functions_to_the_last_bits() {
        for rpm in [0.0, 1.0, 20.0, 54.5, 122.0, 130.0] {
            let w = rpm_to_rad_s(rpm);
            assert!((w - rpm * RPM_TO_RAD_S).abs() <= 2.0 * f64::EPSILON * w.abs());
            assert!((rad_s_to_rpm(w) - rpm).abs() <= 4.0 * f64::EPSILON * rpm.max(1.0));
            assert!((w * RAD_S_TO_RPM - rpm).abs() <= 4.0 * f64::EPSILON * rpm.max(1.0));
        }
        assert_eq!(RAD_S_TO_RPM, 60.0 / (2.0 * PI));
        assert!((rpm_to_rad_s(60.0) - 2.0 * PI).abs() < 1e-15);
    }
}
