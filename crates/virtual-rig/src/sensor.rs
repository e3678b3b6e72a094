//! Sensor dynamics of the virtual rig's sensor chain: the response of a
//! second-order sensor (mass–spring–damper) to a sampled input.

/// Sub-steps of the classical Runge–Kutta integration per sample: at 500 Hz
/// and f_n ≤ 30 Hz, ω h ≤ 0.019 per sub-step, so the local error
/// (ω h)⁵/120 ≈ 2·10⁻¹¹ is far below the encoder's tick and the force noise.
const SUBSTEPS: usize = 20;

/// The output y of a second-order sensor driven by the sampled input u:
/// ÿ + 2ζω ẏ + ω² y = ω² u (+ 2ζω u̇ when `rate` gives u̇), ω = 2π f_n.
/// Without `rate` it is a base-excited load cell (a mass on a spring and
/// damper pulled by the force u); with it, a disc of inertia J on a coupling
/// of stiffness k and damping c to a shaft at angle u and speed u̇
/// (J φ̈ = k(u − φ) + c(u̇ − φ̇), ω² = k/J, 2ζω = c/J). The input is taken
/// linear between samples (u̇ too), integrated by RK4 with [`SUBSTEPS`] steps
/// per sample, from rest at the first sample (y = u[0], ẏ = u̇[0]).
pub fn second_order_response(
    u: &[f64],
    rate: Option<&[f64]>,
    rate_hz: f64,
    natural_frequency_hz: f64,
    damping_ratio: f64,
) -> Vec<f64> {
    let n = u.len();
    if n == 0 {
        return Vec::new();
    }
    let w = 2.0 * std::f64::consts::PI * natural_frequency_hz;
    let (w2, c) = (w * w, 2.0 * damping_ratio * w);
    let du = |k: usize| rate.map_or(0.0, |r| r[k]);
    let h = 1.0 / (rate_hz * SUBSTEPS as f64);
    let mut out = Vec::with_capacity(n);
    let (mut y, mut v) = (u[0], du(0));
    out.push(y);
    for k in 1..n {
        let (u0, u1, r0, r1) = (u[k - 1], u[k], du(k - 1), du(k));
        // Input at fraction s ∈ [0, 1] of the sample interval.
        let input = |s: f64| (u0 + s * (u1 - u0), r0 + s * (r1 - r0));
        let f = |s: f64, y: f64, v: f64| {
            let (uu, rr) = input(s);
            (v, w2 * (uu - y) + c * (rr - v))
        };
        let ds = 1.0 / SUBSTEPS as f64;
        for j in 0..SUBSTEPS {
            let s = j as f64 * ds;
            let (k1y, k1v) = f(s, y, v);
            let (k2y, k2v) = f(s + 0.5 * ds, y + 0.5 * h * k1y, v + 0.5 * h * k1v);
            let (k3y, k3v) = f(s + 0.5 * ds, y + 0.5 * h * k2y, v + 0.5 * h * k2v);
            let (k4y, k4v) = f(s + ds, y + h * k3y, v + h * k3v);
            y += h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        out.push(y);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::second_order_response;
    use std::f64::consts::PI;

    /// A sine in, after the transient: the amplitude of the frequency response
    /// |H(iΩ)|, H = ω²/(ω² − Ω² + 2iζωΩ) for the load cell and
    /// (ω² + 2iζωΩ)/(ω² − Ω² + 2iζωΩ) for the coupling.
    #[test]
    fn sine_response_has_the_frequency_response_amplitude() {
        let (rate, f_n, zeta) = (500.0, 5.0, 0.2);
        let w = 2.0 * PI * f_n;
        for f_in in [1.0, 4.0, 9.0] {
            let wi = 2.0 * PI * f_in;
            let t: Vec<f64> = (0..5000).map(|k| k as f64 / rate).collect();
            let u: Vec<f64> = t.iter().map(|&t| (wi * t).sin()).collect();
            let du: Vec<f64> = t.iter().map(|&t| wi * (wi * t).cos()).collect();
            let den = ((w * w - wi * wi).powi(2) + (2.0 * zeta * w * wi).powi(2)).sqrt();
            for (rate_in, num) in [(None, w * w), (Some(&du[..]), (w.powi(4) + (2.0 * zeta * w * wi).powi(2)).sqrt())] {
                let y = second_order_response(&u, rate_in, rate, f_n, zeta);
                let amp = y[4000..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let expect = num / den;
                // The sampled peak misses the true one by ≤ 1 − cos(Ω h/2).
                assert!((amp - expect).abs() < 2e-3 * expect, "{f_in} Hz: {amp} vs {expect}");
            }
        }
    }

    /// From rest at a constant input it stays there (no start transient).
    #[test]
    fn rest_stays_at_rest() {
        let y = second_order_response(&[2.5; 100], None, 500.0, 8.0, 0.1);
        assert!(y.iter().all(|&v| (v - 2.5).abs() < 1e-12));
    }
}
