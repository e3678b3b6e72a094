//! The chapter's closed-form characterisation equations (Eqs. 4-1 to 4-5) and
//! the per-trial ratios of Tables 4.3 and 4.6, as pure functions in SI units.

use std::f64::consts::PI;

/// G = E / (2(1 + ν)) (text under Eq. 4-1), Pa.
pub fn shear_modulus_pa(youngs_modulus_pa: f64, poisson_ratio: f64) -> f64 {
    youngs_modulus_pa / (2.0 * (1.0 + poisson_ratio))
}

/// I_s = π D⁴ / 32 (text under Eq. 4-1): the polar second moment of area of a
/// solid round shaft, m⁴. (The chapter calls it "moment of inertia (geometric)".)
pub fn polar_moment_m4(diameter_m: f64) -> f64 {
    PI / 32.0 * diameter_m.powi(4)
}

/// K_sA = G I_s / L_s (Eq. 4-1), N·m/rad.
pub fn shaft_stiffness_nm_rad(shear_modulus_pa: f64, polar_moment_m4: f64, length_m: f64) -> f64 {
    shear_modulus_pa * polar_moment_m4 / length_m
}

/// δ = ln(x1 / x2) (Eq. 4-2a) for two successive amplitudes of the same sign.
pub fn log_decrement(x1: f64, x2: f64) -> f64 {
    (x1 / x2).ln()
}

/// ξ = δ / √((2π)² + δ²) (Eq. 4-2b).
pub fn damping_ratio(log_decrement: f64) -> f64 {
    log_decrement / ((2.0 * PI).powi(2) + log_decrement * log_decrement).sqrt()
}

/// ω_n = ω_d / √(1 − ξ²) (Eq. 4-3); any frequency unit, returned in the same unit.
pub fn natural_from_damped(damped: f64, damping_ratio: f64) -> f64 {
    damped / (1.0 - damping_ratio * damping_ratio).sqrt()
}

/// J = K / ω_n² (Eq. 4-4), kg·m²; ω_n must be in rad/s.
pub fn inertia_from_frequency_kgm2(stiffness_nm_rad: f64, natural_rad_s: f64) -> f64 {
    stiffness_nm_rad / (natural_rad_s * natural_rad_s)
}

/// J_1A = ½ M R² (Eq. 4-5): a uniform solid disc, kg·m².
pub fn disc_inertia_kgm2(mass_kg: f64, radius_m: f64) -> f64 {
    0.5 * mass_kg * radius_m * radius_m
}

/// |a − b| / b in percent (the chapter's "relative error", reference b).
pub fn relative_error_pct(value: f64, reference: f64) -> f64 {
    100.0 * (value - reference).abs() / reference.abs()
}

/// K_SE = T / φ for one static trial (Table 4.3), N·m/rad.
pub fn static_stiffness_nm_rad(torque_nm: f64, angle_rad: f64) -> f64 {
    torque_nm / angle_rad
}

/// Sensor factor = voltage / load for one trial (Table 4.6), mV/N.
pub fn force_factor_mv_per_n(voltage_mv: f64, load_n: f64) -> f64 {
    voltage_mv / load_n
}

/// Hz → rad/s (ω = 2π f).
pub fn hz_to_rad_s(f_hz: f64) -> f64 {
    2.0 * PI * f_hz
}

/// rpm → rad/s (`rig_types::units`, the one home of the factor).
pub use rig_types::units::rpm_to_rad_s;

/// Steady no-load speed of a DC motor under constant voltage, from Eq. 4-6 with
/// di/dt = 0 and Ω̇ = 0 and no load: V = R i + k_e Ω and k_T i = C_m Ω + T_f,
/// so Ω = (V − R T_f / k_T) / (k_e + R C_m / k_T), rad/s at the armature.
pub fn no_load_speed_rad_s(
    voltage_v: f64,
    resistance_ohm: f64,
    torque_constant_nm_a: f64,
    voltage_constant_v_s_rad: f64,
    friction_torque_nm: f64,
    speed_regulation_nm_s_rad: f64,
) -> f64 {
    let r_over_kt = resistance_ohm / torque_constant_nm_a;
    (voltage_v - r_over_kt * friction_torque_nm) / (voltage_constant_v_s_rad + r_over_kt * speed_regulation_nm_s_rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand computation with Table 4.1's constants: G = 210e9/2.6 = 80.769 GPa,
    /// I_s = π·0.003⁴/32 = 7.9522e-12 m⁴, K = G I_s / 2.4 = 0.26763 N·m/rad.
    #[test]
    fn eq_4_1_by_hand() {
        let g = shear_modulus_pa(210e9, 0.30);
        assert!((g - 80.769_230_769e9).abs() < 1e3);
        let i = polar_moment_m4(0.003);
        assert!((i - 7.952_156_8e-12).abs() < 1e-18);
        assert!((shaft_stiffness_nm_rad(g, i, 2.4) - 0.267_63).abs() < 1e-5);
    }

    #[test]
    fn damping_round_trip() {
        // ξ = 0.1 ⇔ δ = 2πξ/√(1−ξ²) = 0.631484.
        let d = 2.0 * PI * 0.1 / (1.0f64 - 0.01).sqrt();
        assert!((damping_ratio(d) - 0.1).abs() < 1e-14);
        assert!((log_decrement(1.0, (-d).exp()) - d).abs() < 1e-14);
        assert!((natural_from_damped(0.99f64.sqrt(), 0.1) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn eq_4_5_by_hand() {
        // ½·6.40·0.188² = 0.1131008
        assert!((disc_inertia_kgm2(6.40, 0.188) - 0.113_100_8).abs() < 1e-12);
    }

    #[test]
    fn no_load_speed_without_losses_is_v_over_ke() {
        assert!((no_load_speed_rad_s(8.0, 0.5, 0.1, 0.05, 0.0, 0.0) - 160.0).abs() < 1e-12);
    }
}
