//! The LAVI models, one struct for the baseline and every extension, and their
//! free run under the measured top speed (and weight on bit).
//!
//! Baseline (Real et al. 2018, the lumped 1-DOF model of the rig; physics of a
//! torsion spring driven at its top end):
//!
//! J Ω̇ = k φ + c (Ω_top − Ω) − T_f,   φ̇ = Ω_top − Ω,
//!
//! T_f(Ω) = sign(Ω) [T_k + (T_s − T_k) exp(−(|Ω|/v_s)^δ) + c_v |Ω|] in slip,
//! and stick (Ω = 0) while the holding torque |k φ + c Ω_top| ≤ T_s (Karnopp).
//! The extensions (crate docs list their effect ids):
//! - `wob_normal_force`: T_f scaled by W(t)/W_ref: torque = WOB·μ(Ω) with
//!   μ = law/W_ref (Coulomb's law T = r μ N; the thesis' Eq. 4-11 idea of a
//!   varying normal force, with N measured);
//! - `sensor_inertia`: the sensor reads T_m = T_f + J_s Ω̇ (Newton on the part
//!   of the bit between sensor and contact);
//! - `friction_memory`: the slip friction magnitude lags its steady law,
//!   τ ṁ = |T_ss(Ω)| − m (a first-order frictional memory, Hess & Soom 1990);
//! - `second_dof`: a mid inertia J_1 splits the shaft: k_1 = k/s, k_2 = k/(1−s)
//!   (series stiffness k kept);
//! - `compliant_drive`: the top speed is a state, J_m Ω̇_top = K_p (Ω_ref − Ω_top)
//!   plus K_i ∫(Ω_ref − Ω_top) minus the torque into the shaft, with Ω_ref the
//!   measured top speed's moving mean (a PI speed loop; Newton on the motor).
//!
//! Integration: semi-implicit Euler with `substeps` steps per sample (0.2 ms
//! at 1 kHz and 5 substeps; the compared band is below 10 Hz). Inputs are held
//! linear between samples.

use crate::LaviError;
use serde::Serialize;

/// Friction law at the reference normal force: T_k + (T_s − T_k) e^{−(|Ω|/v_s)^δ} + c_v |Ω| (N m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrictionLaw {
    pub static_nm: f64,
    pub kinetic_nm: f64,
    pub stribeck_speed_rad_s: f64,
    /// δ: 1 exponential, 2 Gaussian Stribeck.
    pub shape_exponent: f64,
    pub viscous_nm_s_rad: f64,
}

impl FrictionLaw {
    /// Magnitude of the slip torque at speed |Ω|.
    pub fn slip_nm(&self, omega_rad_s: f64) -> f64 {
        let w = omega_rad_s.abs();
        self.kinetic_nm
            + (self.static_nm - self.kinetic_nm)
                * rig_spectra::stickslip::weakening_shape(w / self.stribeck_speed_rad_s, self.shape_exponent)
            + self.viscous_nm_s_rad * w
    }
}

/// A mid inertia on the shaft (the second torsional DOF).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MidDof {
    pub inertia_kgm2: f64,
    /// s in (0, 1): k_1 = k/s (top side), k_2 = k/(1−s) (bit side).
    pub split: f64,
}

/// A speed-controlled drive whose speed is not imposed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Drive {
    pub inertia_kgm2: f64,
    pub kp_nm_s_rad: f64,
    pub ki_nm_rad: f64,
}

/// The baseline and every extension (an extension is off at its neutral value).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Model {
    pub inertia_kgm2: f64,
    pub stiffness_nm_rad: f64,
    pub damping_nm_s_rad: f64,
    pub friction: FrictionLaw,
    /// Some(W_ref): friction scales with W(t)/W_ref.
    pub wob_ref_n: Option<f64>,
    pub sensor_inertia_kgm2: f64,
    /// 0: no frictional memory.
    pub friction_lag_s: f64,
    pub mid: Option<MidDof>,
    pub drive: Option<Drive>,
}

/// What a free run is driven by (rad/s and N, one value per sample).
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    pub fs_hz: f64,
    pub top_rad_s: &'a [f64],
    pub wob_n: &'a [f64],
    /// Set point of the compliant drive (moving mean of the measured top speed).
    pub top_ref_rad_s: &'a [f64],
}

/// Measured state at the first sample: bit speed, its derivative, measured torque.
#[derive(Debug, Clone, Copy)]
pub struct Start {
    pub bit_rad_s: f64,
    pub bit_acc_rad_s2: f64,
    pub torque_nm: f64,
}

/// A free run at the input's sample times.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    pub bit_rad_s: Vec<f64>,
    /// What the torque sensor reads (friction plus J_s Ω̇).
    pub torque_nm: Vec<f64>,
    pub top_rad_s: Vec<f64>,
}

const STICK_RAD_S: f64 = 1e-3;

/// Integrates `m` from `start` under `u` (see the module docs).
pub fn simulate(m: &Model, u: &Inputs, start: Start, substeps: usize) -> Result<Run, LaviError> {
    let n = u.top_rad_s.len();
    if u.wob_n.len() != n || u.top_ref_rad_s.len() != n || n < 2 {
        return Err(LaviError::Input { what: "simulate", rule: "inputs must have equal lengths >= 2".into() });
    }
    for (name, v) in [("inertia_kgm2", m.inertia_kgm2), ("stiffness_nm_rad", m.stiffness_nm_rad)] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(LaviError::Input { what: "simulate", rule: format!("{name} = {v} must be finite and > 0") });
        }
    }
    let steps = substeps.max(1);
    let h = 1.0 / (u.fs_hz * steps as f64);
    let (k, c, jb) = (m.stiffness_nm_rad, m.damping_nm_s_rad, m.inertia_kgm2);
    let (k1, k2, c1, c2) = match m.mid {
        Some(d) => (k / d.split, k / (1.0 - d.split), c / d.split, c / (1.0 - d.split)),
        None => (k, k, c, c),
    };
    let w_ref = m.wob_ref_n.unwrap_or(1.0);
    // Initial state from the measured start (quasi-static twist: J Ω̇ = k φ + c(Ω_top − Ω) − T_f).
    let top0 = u.top_rad_s[0];
    let tf0 = start.torque_nm - m.sensor_inertia_kgm2 * start.bit_acc_rad_s2;
    let tau0 = jb * start.bit_acc_rad_s2 + tf0;
    let mut om = start.bit_rad_s;
    let mut om1 = 0.5 * (top0 + om);
    let (mut phi1, mut phi2) = match m.mid {
        Some(_) => (tau0 / k1, tau0 / k2),
        None => ((tau0 - c * (top0 - om)) / k, 0.0),
    };
    let mut om_top = top0;
    let mut integ = match m.drive {
        Some(d) if d.ki_nm_rad > 0.0 => tau0 / d.ki_nm_rad,
        _ => 0.0,
    };
    let mut mag = tf0.abs();
    let scale0 = u.wob_n[0] / w_ref;
    let mut stuck = om.abs() < STICK_RAD_S && tau0.abs() <= scale0 * m.friction.static_nm;
    if stuck {
        om = 0.0;
    }
    let mut out =
        Run { bit_rad_s: Vec::with_capacity(n), torque_nm: Vec::with_capacity(n), top_rad_s: Vec::with_capacity(n) };
    out.bit_rad_s.push(om);
    out.torque_nm.push(start.torque_nm);
    out.top_rad_s.push(om_top);
    for i in 1..n {
        let mut acc = 0.0;
        let mut fric = 0.0;
        for sub in 0..steps {
            let a = (sub as f64 + 0.5) / steps as f64;
            let lin = |x: &[f64]| x[i - 1] + a * (x[i] - x[i - 1]);
            let top = if m.drive.is_some() { om_top } else { lin(u.top_rad_s) };
            let g = if m.wob_ref_n.is_some() { lin(u.wob_n) / w_ref } else { 1.0 };
            let ts = g * m.friction.static_nm;
            // Torque the shaft applies to the bit, and at the top.
            let (drive_bit, shaft_top) = match m.mid {
                Some(_) => (k2 * phi2 + c2 * (om1 - om), k1 * phi1 + c1 * (top - om1)),
                None => {
                    let t = k * phi1 + c * (top - om);
                    (t, t)
                }
            };
            if stuck && drive_bit.abs() > ts {
                stuck = false;
                mag = ts;
            }
            if stuck {
                acc = 0.0;
                fric = drive_bit;
                mag = drive_bit.abs();
            } else {
                let dir = if om.abs() > 0.0 { om.signum() } else { drive_bit.signum() };
                let target = if om.abs() > 0.0 { g * m.friction.slip_nm(om) } else { ts };
                if m.friction_lag_s > 0.0 {
                    mag += (h / m.friction_lag_s).min(1.0) * (target - mag);
                } else {
                    mag = target;
                }
                fric = dir * mag;
                acc = (drive_bit - fric) / jb;
                let next = om + h * acc;
                if (next == 0.0 || next.signum() != dir) && drive_bit.abs() <= ts {
                    stuck = true;
                    om = 0.0;
                    acc = 0.0;
                } else {
                    om = next;
                }
            }
            if let Some(d) = m.mid {
                om1 += h * (shaft_top - drive_bit) / d.inertia_kgm2;
                phi1 += h * (top - om1);
                phi2 += h * (om1 - om);
            } else {
                phi1 += h * (top - om);
            }
            if let Some(d) = m.drive {
                let r = lin(u.top_ref_rad_s);
                let motor = d.kp_nm_s_rad * (r - om_top) + d.ki_nm_rad * integ;
                om_top += h * (motor - shaft_top) / d.inertia_kgm2;
                integ += h * (r - om_top);
            }
        }
        if !(om.is_finite() && phi1.is_finite() && phi2.is_finite() && om_top.is_finite()) || om.abs() > 1e4 {
            return Err(LaviError::Diverged { sample: i });
        }
        out.bit_rad_s.push(om);
        out.torque_nm.push(fric + m.sensor_inertia_kgm2 * acc);
        out.top_rad_s.push(if m.drive.is_some() { om_top } else { u.top_rad_s[i] });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Model {
        Model {
            inertia_kgm2: 0.05,
            stiffness_nm_rad: 2.0,
            damping_nm_s_rad: 0.02,
            friction: FrictionLaw {
                static_nm: 1.8,
                kinetic_nm: 1.0,
                stribeck_speed_rad_s: 1.0,
                shape_exponent: 1.0,
                viscous_nm_s_rad: 0.0,
            },
            wob_ref_n: None,
            sensor_inertia_kgm2: 0.0,
            friction_lag_s: 0.0,
            mid: None,
            drive: None,
        }
    }

    fn run(m: &Model, top: f64, secs: f64) -> Run {
        let n = (secs * 1000.0) as usize;
        let (u, w) = (vec![top; n], vec![500.0; n]);
        let inp = Inputs { fs_hz: 1000.0, top_rad_s: &u, wob_n: &w, top_ref_rad_s: &u };
        simulate(m, &inp, Start { bit_rad_s: top, bit_acc_rad_s2: 0.0, torque_nm: 1.0 }, 5).unwrap()
    }

    #[test]
    fn steady_slip_settles_at_the_top_speed_with_the_kinetic_torque() {
        // 20 rad/s: far past v_s, T → T_k = 1 N m; decay time 2J/c = 5 s, 60 s leave e^{-12}.
        let r = run(&base(), 20.0, 60.0);
        let n = r.bit_rad_s.len() - 1;
        assert!((r.bit_rad_s[n] - 20.0).abs() < 1e-3 && (r.torque_nm[n] - 1.0).abs() < 1e-3, "{:?}", r.bit_rad_s[n]);
    }

    #[test]
    fn slow_drive_sticks_and_slips() {
        let r = run(&base(), 1.0, 20.0);
        let stuck = r.bit_rad_s.iter().filter(|v| **v == 0.0).count();
        assert!(stuck > 2000, "stuck samples {stuck}");
        // The sensor never reads more than the static torque in stick.
        assert!(r.torque_nm.iter().all(|t| *t <= 1.8 + 1e-9));
    }

    #[test]
    fn the_extensions_run() {
        let mut m = base();
        m.mid = Some(MidDof { inertia_kgm2: 0.02, split: 0.5 });
        m.drive = Some(Drive { inertia_kgm2: 0.1, kp_nm_s_rad: 2.0, ki_nm_rad: 5.0 });
        m.friction_lag_s = 0.02;
        m.sensor_inertia_kgm2 = 0.01;
        m.wob_ref_n = Some(500.0);
        let r = run(&m, 3.0, 10.0);
        assert!(r.bit_rad_s.iter().all(|v| v.is_finite()));
    }
}
