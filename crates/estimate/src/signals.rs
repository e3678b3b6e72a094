//! Window-mean speeds for the voltage-step fit, and small statistics. Speeds
//! are differences of angles over a window, so the same linear operator can
//! be applied to a simulated angle (no differentiation bias between
//! measurement and model). Ticks → angle, the centred difference and the
//! speed resolution are `rig_types::sensor`.

/// Mean speed over consecutive non-overlapping windows of `w` samples:
/// Ω_k = (φ[(k+1)w] − φ[kw]) / (t[(k+1)w] − t[kw]), stamped at the window centre.
/// Returns (time_s, speed_rad_s).
pub fn window_speed(time_s: &[f64], angle_rad: &[f64], w: usize) -> (Vec<f64>, Vec<f64>) {
    let w = w.max(1);
    let n = time_s.len().min(angle_rad.len());
    let mut t = Vec::new();
    let mut v = Vec::new();
    let mut i = 0;
    while i + w < n {
        let dt = time_s[i + w] - time_s[i];
        t.push(0.5 * (time_s[i + w] + time_s[i]));
        v.push((angle_rad[i + w] - angle_rad[i]) / dt);
        i += w;
    }
    (t, v)
}

/// Median of a slice (NaN for an empty one); sorts a copy with total order.
pub fn median(xs: &[f64]) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// Sample mean and sample standard deviation (n − 1).
pub fn mean_sd(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}
