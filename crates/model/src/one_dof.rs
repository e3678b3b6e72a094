//! A 1-DOF torsional model driven by a measured top speed (the UFRJ LAVI rig):
//!
//! J θ̈ = k (θ_top − θ) + c (Ω_top − Ω) − T_fric(Ω),
//!
//! with the bit friction T_fric(Ω) = sign(Ω) (a + b·exp(−(|Ω|/vs)^δ)) in slip and a
//! stick phase (Ω = 0) while |k φ + c Ω_top| ≤ a + b, where φ = θ_top − θ is the
//! twist. This is the lumped model of Real et al. (2018) for a rig whose drive
//! is not stiff: the measured top speed is the input, so the drive needs no model.
//!
//! Two pure functions: [`fit_one_dof`] identifies J, k, c by linear least
//! squares from a recording (the friction torque is measured, so J is
//! identifiable, not only k/J and c/J), and [`simulate_one_dof`] integrates
//! the model under a measured top speed.

use crate::ModelError;

/// Bit friction law T(Ω) = sign(Ω) (a + b e^{−(|Ω|/vs)^δ}) in slip; break-away at a + b.
/// δ = 1 is an exponential decay, δ = 2 the Gaussian Stribeck curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneDofFriction {
    /// a: the kinetic level reached at high speed, N m.
    pub kinetic_nm: f64,
    /// b: the extra torque at Ω → 0⁺, N m (b > 0 is velocity weakening).
    pub weakening_nm: f64,
    pub stribeck_speed_rad_s: f64,
    pub shape_exponent: f64,
}

impl OneDofFriction {
    /// Slip torque at speed Ω (odd in Ω).
    pub fn slip_torque_nm(&self, omega_rad_s: f64) -> f64 {
        let x = (omega_rad_s.abs() / self.stribeck_speed_rad_s).powf(self.shape_exponent);
        let mag = self.kinetic_nm + self.weakening_nm * (-x).exp();
        omega_rad_s.signum() * mag
    }

    /// Largest torque the contact holds while stuck.
    pub fn static_nm(&self) -> f64 {
        self.kinetic_nm + self.weakening_nm
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneDofParams {
    pub inertia_kgm2: f64,
    pub stiffness_nm_rad: f64,
    pub damping_nm_s_rad: f64,
    pub friction: OneDofFriction,
}

/// Result of the least-squares identification.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneDofFit {
    pub inertia_kgm2: f64,
    pub stiffness_nm_rad: f64,
    pub damping_nm_s_rad: f64,
    /// Twist at the first sample, rad (the regression's constant term / k).
    pub initial_twist_rad: f64,
    /// Standard errors from the residual variance and (XᵀX)⁻¹ (white-residual assumption).
    pub inertia_stderr: f64,
    pub stiffness_stderr: f64,
    pub damping_stderr: f64,
    /// 1 − SSE/SST of the acceleration regression.
    pub r_squared: f64,
    pub points: usize,
}

fn check_lengths(n: usize, others: &[(&'static str, usize)]) -> Result<(), ModelError> {
    for (name, len) in others {
        if *len != n {
            return Err(ModelError::InvalidParameter {
                name,
                value: *len as f64,
                rule: "length must equal time_s.len()",
            });
        }
    }
    Ok(())
}

fn check_times(time_s: &[f64]) -> Result<(), ModelError> {
    for i in 0..time_s.len() {
        if !time_s[i].is_finite() || (i > 0 && time_s[i] <= time_s[i - 1]) {
            return Err(ModelError::BadSampleTimes { index: i });
        }
    }
    Ok(())
}

/// Twist φ(t) − φ(t0) = ∫ (Ω_top − Ω) dt by the trapezoid rule (rad, for speeds in rad/s):
/// the angle a model driven by `top` is wound by; one home for every caller.
pub fn integrated_twist_rad(time_s: &[f64], top: &[f64], bit: &[f64]) -> Vec<f64> {
    let mut phi = vec![0.0; time_s.len()];
    for i in 1..time_s.len() {
        let dt = time_s[i] - time_s[i - 1];
        phi[i] = phi[i - 1] + 0.5 * dt * ((top[i] - bit[i]) + (top[i - 1] - bit[i - 1]));
    }
    phi
}

/// Solves `a x = b` (a small normal-equation matrix) by Gauss–Jordan elimination
/// with partial pivoting; also returns a⁻¹ for the covariance.
fn solve_with_inverse(mut a: Vec<Vec<f64>>, mut rhs: Vec<f64>) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let m = rhs.len();
    let mut inv: Vec<Vec<f64>> = (0..m).map(|i| (0..m).map(|j| if i == j { 1.0 } else { 0.0 }).collect()).collect();
    for col in 0..m {
        let piv = (col..m).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, piv);
        inv.swap(col, piv);
        rhs.swap(col, piv);
        for r in 0..m {
            if r != col {
                let f = a[r][col] / a[col][col];
                for c in 0..m {
                    a[r][c] -= f * a[col][c];
                    inv[r][c] -= f * inv[col][c];
                }
                rhs[r] -= f * rhs[col];
            }
        }
    }
    let x = (0..m).map(|i| rhs[i] / a[i][i]).collect();
    for (i, row) in inv.iter_mut().enumerate() {
        let d = a[i][i];
        row.iter_mut().for_each(|v| *v /= d);
    }
    Some((x, inv))
}

/// Least squares on the equation of motion divided by J:
/// Ω̇ = (k/J) (Δφ + φ0) + (c/J) (Ω_top − Ω) − (1/J) T,
/// unknowns p = (k/J, c/J, 1/J, k φ0 / J), with Δφ the integrated twist from
/// the first sample. `bit_accel_rad_s2` is the caller's derivative of the bit
/// speed (filtered: differentiation amplifies noise). `bit_torque_nm` is the
/// measured torque the contact applies (in stick too). With
/// `fixed_damping_nm_s_rad = Some(c)` the damping is not estimated: the
/// regressor becomes c (Ω_top − Ω) − T with coefficient 1/J (stderr of c = 0).
pub fn fit_one_dof(
    time_s: &[f64],
    top_speed_rad_s: &[f64],
    bit_speed_rad_s: &[f64],
    bit_accel_rad_s2: &[f64],
    bit_torque_nm: &[f64],
    fixed_damping_nm_s_rad: Option<f64>,
) -> Result<OneDofFit, ModelError> {
    let n = time_s.len();
    check_lengths(
        n,
        &[
            ("top_speed_rad_s", top_speed_rad_s.len()),
            ("bit_speed_rad_s", bit_speed_rad_s.len()),
            ("bit_accel_rad_s2", bit_accel_rad_s2.len()),
            ("bit_torque_nm", bit_torque_nm.len()),
        ],
    )?;
    if n < 8 {
        return Err(ModelError::InvalidParameter { name: "time_s.len()", value: n as f64, rule: "at least 8 samples" });
    }
    check_times(time_s)?;
    let dphi = integrated_twist_rad(time_s, top_speed_rad_s, bit_speed_rad_s);
    // Columns: Δφ, [Ω_top − Ω], −T (or c(Ω_top − Ω) − T), 1. Index of 1/J in p: `ij`.
    let row = |i: usize| -> Vec<f64> {
        let rate = top_speed_rad_s[i] - bit_speed_rad_s[i];
        match fixed_damping_nm_s_rad {
            None => vec![dphi[i], rate, -bit_torque_nm[i], 1.0],
            Some(c) => vec![dphi[i], c * rate - bit_torque_nm[i], 1.0],
        }
    };
    let (ij, m) = if fixed_damping_nm_s_rad.is_some() { (1, 3) } else { (2, 4) };
    let (mut ata, mut atb) = (vec![vec![0.0; m]; m], vec![0.0; m]);
    for (i, acc) in bit_accel_rad_s2.iter().enumerate() {
        let x = row(i);
        for r in 0..m {
            atb[r] += x[r] * acc;
            for c in 0..m {
                ata[r][c] += x[r] * x[c];
            }
        }
    }
    let (p, inv) = solve_with_inverse(ata, atb).ok_or(ModelError::InvalidParameter {
        name: "regressors",
        value: n as f64,
        rule: "twist, twist rate and torque must not be collinear (is the record long enough?)",
    })?;
    let mean_acc = bit_accel_rad_s2.iter().sum::<f64>() / n as f64;
    let (mut sse, mut sst) = (0.0, 0.0);
    for (i, acc) in bit_accel_rad_s2.iter().enumerate() {
        let pred: f64 = row(i).iter().zip(&p).map(|(x, pj)| x * pj).sum();
        sse += (acc - pred).powi(2);
        sst += (acc - mean_acc).powi(2);
    }
    let s2 = sse / (n - m) as f64;
    let var = |j: usize| (s2 * inv[j][j]).max(0.0);
    if p[ij] <= 0.0 {
        return Err(ModelError::InvalidParameter {
            name: "1/J",
            value: p[ij],
            rule: "the fitted inverse inertia must be positive (torque sign or units wrong?)",
        });
    }
    let j = 1.0 / p[ij];
    // First-order propagation: J = 1/p_J, k = p_k/p_J, c = p_c/p_J (cross-covariances neglected).
    let rel_j = var(ij).sqrt() / p[ij];
    let (c, c_se) = match fixed_damping_nm_s_rad {
        Some(c) => (c, 0.0),
        None => (p[1] * j, (p[1] * j).abs() * ((var(1).sqrt() / p[1]).powi(2) + rel_j * rel_j).sqrt()),
    };
    Ok(OneDofFit {
        inertia_kgm2: j,
        stiffness_nm_rad: p[0] * j,
        damping_nm_s_rad: c,
        initial_twist_rad: p[m - 1] / p[0],
        inertia_stderr: j * rel_j,
        stiffness_stderr: (p[0] * j) * ((var(0).sqrt() / p[0]).powi(2) + rel_j * rel_j).sqrt(),
        damping_stderr: c_se,
        r_squared: 1.0 - sse / sst,
        points: n,
    })
}

/// A simulated bit response at the input's sample times.
#[derive(Debug, Clone, PartialEq)]
pub struct OneDofRun {
    pub bit_speed_rad_s: Vec<f64>,
    pub twist_rad: Vec<f64>,
    /// Torque the contact applies (the slip law in slip, the holding torque in stick).
    pub friction_torque_nm: Vec<f64>,
    pub stuck: Vec<bool>,
}

/// Integrates the model under the measured top speed (linear between samples)
/// from twist `twist0_rad` and bit speed `speed0_rad_s`, by classical RK4 with
/// `substeps` steps per sample interval. Stick: when Ω changes sign within a
/// step (or sits at 0) and the holding torque |k φ + c Ω_top| ≤ a + b, Ω is set
/// to 0 until the holding torque exceeds a + b. Event times are resolved to one
/// substep (0.1 ms at 1 kHz and 10 substeps), far below the 10 Hz band compared.
pub fn simulate_one_dof(
    p: &OneDofParams,
    time_s: &[f64],
    top_speed_rad_s: &[f64],
    twist0_rad: f64,
    speed0_rad_s: f64,
    substeps: usize,
) -> Result<OneDofRun, ModelError> {
    check_lengths(time_s.len(), &[("top_speed_rad_s", top_speed_rad_s.len())])?;
    check_times(time_s)?;
    for (name, v) in [
        ("inertia_kgm2", p.inertia_kgm2),
        ("stiffness_nm_rad", p.stiffness_nm_rad),
        ("stribeck_speed_rad_s", p.friction.stribeck_speed_rad_s),
    ] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(ModelError::InvalidParameter { name, value: v, rule: "must be finite and > 0" });
        }
    }
    let (j, k, c, f) = (p.inertia_kgm2, p.stiffness_nm_rad, p.damping_nm_s_rad, p.friction);
    let m = substeps.max(1);
    let n = time_s.len();
    let mut out = OneDofRun {
        bit_speed_rad_s: Vec::with_capacity(n),
        twist_rad: Vec::with_capacity(n),
        friction_torque_nm: Vec::with_capacity(n),
        stuck: Vec::with_capacity(n),
    };
    let (mut phi, mut om) = (twist0_rad, speed0_rad_s);
    let hold = |phi: f64, top: f64| k * phi + c * top;
    let mut stuck = om == 0.0 && hold(phi, top_speed_rad_s.first().copied().unwrap_or(0.0)).abs() <= f.static_nm();
    let record = |out: &mut OneDofRun, phi: f64, om: f64, top: f64, stuck: bool| {
        out.bit_speed_rad_s.push(om);
        out.twist_rad.push(phi);
        out.friction_torque_nm.push(if stuck { hold(phi, top) } else { f.slip_torque_nm(om) });
        out.stuck.push(stuck);
    };
    record(&mut out, phi, om, top_speed_rad_s[0], stuck);
    for i in 1..n {
        let (t0, t1) = (time_s[i - 1], time_s[i]);
        let (u0, u1) = (top_speed_rad_s[i - 1], top_speed_rad_s[i]);
        let h = (t1 - t0) / m as f64;
        let top_at = |s: f64| u0 + (u1 - u0) * s / (t1 - t0);
        // Slip dynamics (Eq. of the module doc); the friction sign follows Ω,
        // or the driving torque at the instant of break-away (Ω = 0).
        let rhs = |s: f64, phi: f64, om: f64| -> (f64, f64) {
            let top = top_at(s);
            let drive = k * phi + c * (top - om);
            let fr = if om == 0.0 { drive.signum() * f.static_nm() } else { f.slip_torque_nm(om) };
            (top - om, (drive - fr) / j)
        };
        for sub in 0..m {
            let s = sub as f64 * h;
            if stuck {
                // Ω = 0: the twist grows with the top's rotation (trapezoid is exact for linear top speed).
                phi += 0.5 * h * (top_at(s) + top_at(s + h));
                let tau = hold(phi, top_at(s + h));
                if tau.abs() > f.static_nm() {
                    stuck = false;
                }
                continue;
            }
            let (k1p, k1o) = rhs(s, phi, om);
            let (k2p, k2o) = rhs(s + h / 2.0, phi + h / 2.0 * k1p, om + h / 2.0 * k1o);
            let (k3p, k3o) = rhs(s + h / 2.0, phi + h / 2.0 * k2p, om + h / 2.0 * k2o);
            let (k4p, k4o) = rhs(s + h, phi + h * k3p, om + h * k3o);
            let next_phi = phi + h / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p);
            let next_om = om + h / 6.0 * (k1o + 2.0 * k2o + 2.0 * k3o + k4o);
            if om != 0.0 && next_om.signum() != om.signum() && hold(next_phi, top_at(s + h)).abs() <= f.static_nm() {
                stuck = true;
                om = 0.0;
                phi = next_phi;
            } else {
                phi = next_phi;
                om = next_om;
            }
        }
        if !(phi.is_finite() && om.is_finite()) {
            return Err(ModelError::IntegratorFailed { time_s: t1, reason: "non-finite state".into() });
        }
        record(&mut out, phi, om, u1, stuck);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FS: f64 = 1000.0;

    fn rig() -> OneDofParams {
        OneDofParams {
            inertia_kgm2: 0.05,
            stiffness_nm_rad: 2.0,
            damping_nm_s_rad: 0.02,
            friction: OneDofFriction {
                kinetic_nm: 1.0,
                weakening_nm: 0.8,
                stribeck_speed_rad_s: 1.0,
                shape_exponent: 1.0,
            },
        }
    }

    fn drive(seconds: f64, f: impl Fn(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..(seconds * FS) as usize).map(|i| i as f64 / FS).collect();
        let u = t.iter().map(|&x| f(x)).collect();
        (t, u)
    }

    #[test]
    fn steady_slip_twist_balances_the_friction_law() {
        // Constant top speed 20 rad/s: the oscillation decays (ζ = 0.032, decay
        // time 5 s; 60 s leave e^{-12}), Ω → 20 and k φ → a + b e^{−20/vs}.
        let (t, u) = drive(60.0, |_| 20.0);
        let r = simulate_one_dof(&rig(), &t, &u, 0.0, 20.0, 10).unwrap();
        let n = t.len() - 1;
        let expect = (1.0 + 0.8 * (-20.0f64).exp()) / 2.0;
        assert!((r.bit_speed_rad_s[n] - 20.0).abs() < 1e-3, "{}", r.bit_speed_rad_s[n]);
        assert!((r.twist_rad[n] - expect).abs() < 1e-4, "{} vs {expect}", r.twist_rad[n]);
    }

    #[test]
    fn slow_drive_sticks_and_the_fit_recovers_j_k_c() {
        let (t, u) = drive(20.0, |x| 3.0 + 1.0 * (2.0 * std::f64::consts::PI * 0.3 * x).sin());
        let p = rig();
        let r = simulate_one_dof(&p, &t, &u, 0.0, 0.0, 10).unwrap();
        let stuck = r.stuck.iter().filter(|s| **s).count();
        assert!(stuck > 1000, "expected stick-slip, stuck samples {stuck}");
        // Acceleration by central difference of the simulated speed (what the
        // stage does on filtered data). Differences that straddle a stick/slip
        // kink are biased; they are few, and the fit must cope with them.
        let acc_all: Vec<f64> = (0..t.len())
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(t.len() - 1));
                (r.bit_speed_rad_s[b] - r.bit_speed_rad_s[a]) / (t[b] - t[a])
            })
            .collect();
        let fit = fit_one_dof(&t, &u, &r.bit_speed_rad_s, &acc_all, &r.friction_torque_nm, None).unwrap();
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        assert!(rel(fit.inertia_kgm2, 0.05) < 0.01, "{fit:?}");
        assert!(rel(fit.stiffness_nm_rad, 2.0) < 0.01, "{fit:?}");
        assert!(rel(fit.damping_nm_s_rad, 0.02) < 0.05, "{fit:?}");
        // Measured: J +0.8 %, k +0.6 %, c +1.1 %, φ0 −0.003 rad (of a ≈ 0.9 rad twist).
        assert!(fit.initial_twist_rad.abs() < 0.01 && fit.r_squared > 0.99, "{fit:?}");
        // Damping fixed at its true value: J and k as well recovered.
        let fixed = fit_one_dof(&t, &u, &r.bit_speed_rad_s, &acc_all, &r.friction_torque_nm, Some(0.02)).unwrap();
        assert!(rel(fixed.inertia_kgm2, 0.05) < 0.01 && rel(fixed.stiffness_nm_rad, 2.0) < 0.01, "{fixed:?}");
        assert_eq!((fixed.damping_nm_s_rad, fixed.damping_stderr), (0.02, 0.0));
    }

    #[test]
    fn refuses_bad_inputs() {
        let p = rig();
        assert!(matches!(
            simulate_one_dof(&p, &[0.0, 0.0], &[1.0, 1.0], 0.0, 0.0, 1),
            Err(ModelError::BadSampleTimes { index: 1 })
        ));
        let bad = OneDofParams { inertia_kgm2: 0.0, ..p };
        assert!(simulate_one_dof(&bad, &[0.0, 1.0], &[1.0, 1.0], 0.0, 0.0, 1).is_err());
    }
}
