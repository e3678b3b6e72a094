//! The equation of motion identified by linear least squares on a record
//! (moved from rig_model::one_dof: the model crate does no fitting), never
//! clamped: a constrained parameter that comes out beyond its bound is the
//! caller's finding to report.
//!
//! J Ω̇ = k φ + c (Ω_top − Ω) − c_a Ω − T (rig_model::one_dof's equation),
//! divided by J: Ω̇ = (k/J)(Δφ + φ0) + (c/J)(Ω_top − Ω) − (c_a/J) Ω − (1/J) T,
//! unknowns (k/J, [c/J], [c_a/J], 1/J, k φ0/J), Δφ the integrated twist from
//! the first sample. The friction torque is measured, so J is identifiable,
//! not only k/J and c/J.

use crate::LaviError;
use crate::lsq::{least_squares, sse};
use rig_estimate::linear::Normal;
use rig_model::one_dof::integrated_twist_rad;
use serde::Serialize;

/// Where the damping acts in the fitted equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Damping {
    /// c on the twist rate Ω_top − Ω (the baseline, Real et al. 2018).
    TwistRate,
    /// c_a on the absolute bit speed Ω (Eq. 4-7's placement).
    Absolute,
    /// Both.
    Both,
    /// None (a damping pinned at its bound 0).
    Fixed0,
}

/// J, k, c, c_a with standard errors (from (XᵀX)⁻¹ and the residual variance,
/// first-order propagation through the ratios, cross-covariances neglected).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EomFit {
    pub inertia_kgm2: f64,
    pub stiffness_nm_rad: f64,
    pub damping_nm_s_rad: f64,
    pub absolute_damping_nm_s_rad: f64,
    pub inertia_stderr: f64,
    pub stiffness_stderr: f64,
    pub damping_stderr: f64,
    pub absolute_damping_stderr: f64,
    /// Twist at the first sample, rad (the regression's constant term / k).
    pub initial_twist_rad: f64,
    /// 1 − SSE/SST of the acceleration regression.
    pub r_squared: f64,
    pub points: usize,
}

/// Least squares of the equation of motion (module docs) on speeds in rad/s,
/// the caller's (filtered) bit acceleration and the measured torque.
pub fn fit_equation_of_motion(
    time_s: &[f64],
    top_rad_s: &[f64],
    bit_rad_s: &[f64],
    bit_accel_rad_s2: &[f64],
    torque_nm: &[f64],
    damping: Damping,
) -> Result<EomFit, LaviError> {
    let n = time_s.len();
    if [top_rad_s.len(), bit_rad_s.len(), bit_accel_rad_s2.len(), torque_nm.len()].iter().any(|l| *l != n) || n < 8 {
        return Err(unequal_or_short(n));
    }
    let dphi = integrated_twist_rad(time_s, top_rad_s, bit_rad_s);
    let (with_c, with_ca) = columns(damping);
    // Column order: Δφ, [Ω_top − Ω], [−Ω], −T, 1.
    let row = |i: usize| -> Vec<f64> {
        let mut r = Vec::with_capacity(5);
        r.push(dphi[i]);
        if with_c {
            r.push(top_rad_s[i] - bit_rad_s[i]);
        }
        if with_ca {
            r.push(-bit_rad_s[i]);
        }
        r.push(-torque_nm[i]);
        r.push(1.0);
        r
    };
    let p = 3 + with_c as usize + with_ca as usize;
    let fit = least_squares(bit_accel_rad_s2, p, row).ok_or_else(collinear)?;
    let mean = bit_accel_rad_s2.iter().sum::<f64>() / n as f64;
    let sst: f64 = bit_accel_rad_s2.iter().map(|a| (a - mean).powi(2)).sum();
    eom_fit(&fit, damping, sst)
}

/// The error of series of unequal lengths or shorter than 8 samples (`n`: the time's).
fn unequal_or_short(n: usize) -> LaviError {
    LaviError::Input {
        what: "equation-of-motion fit",
        rule: format!("time, speeds, acceleration and torque need equal lengths of at least 8 samples ({n})"),
    }
}

/// The error of a singular design.
fn collinear() -> LaviError {
    LaviError::Input {
        what: "equation-of-motion fit",
        rule: "twist, damping terms and torque are collinear (is the window long enough?)".into(),
    }
}

/// J, k, c, c_a and their standard errors from the least squares of the
/// module's regression under `damping` (columns Δφ, [Ω_top − Ω], [−Ω], −T, 1),
/// `sst` the acceleration's sum of squares about its mean.
fn eom_fit(fit: &crate::lsq::LeastSquares, damping: Damping, sst: f64) -> Result<EomFit, LaviError> {
    let (with_c, with_ca) = columns(damping);
    let p = 3 + with_c as usize + with_ca as usize;
    let (ic, ica, ij) = (1, 1 + with_c as usize, p - 2);
    let b = &fit.coef;
    if b[ij] <= 0.0 {
        return Err(LaviError::Input {
            what: "equation-of-motion fit",
            rule: format!("the fitted inverse inertia {} must be positive (torque sign or units wrong?)", b[ij]),
        });
    }
    let j = 1.0 / b[ij];
    let rel_j = fit.stderr(ij) / b[ij];
    let ratio = |k: usize| (b[k] * j, (b[k] * j).abs() * ((fit.stderr(k) / b[k]).powi(2) + rel_j * rel_j).sqrt());
    let (c, c_se) = if with_c { ratio(ic) } else { (0.0, 0.0) };
    let (ca, ca_se) = if with_ca { ratio(ica) } else { (0.0, 0.0) };
    let (k, k_se) = ratio(0);
    Ok(EomFit {
        inertia_kgm2: j,
        stiffness_nm_rad: k,
        damping_nm_s_rad: c,
        absolute_damping_nm_s_rad: ca,
        inertia_stderr: j * rel_j,
        stiffness_stderr: k_se,
        damping_stderr: c_se,
        absolute_damping_stderr: ca_se,
        initial_twist_rad: b[p - 1] / b[0],
        r_squared: 1.0 - fit.sse / sst,
        points: fit.points,
    })
}

/// The equation of motion's least squares of one window for many torque
/// columns (the torque channel read at each delay of a scan, or less a
/// sensor inertia's J_s Ω̇ at each J_s of a fit): everything but the
/// torque's column is the same for every such column, so the twist, the
/// design's fixed columns and their sums in the normal equations are made
/// once, and a torque column costs its sums, a 5 × 5 solve and the residual
/// pass. The sums are the products [`fit_equation_of_motion`]'s rows add, in
/// the same row order: the same normal equations to the last bit, so the same
/// fit ([`TorqueScan::fit`]) and R² ([`TorqueScan::r_squared`]).
#[derive(Debug)]
pub struct TorqueScan {
    acc: Vec<f64>,
    /// The fixed columns per row, in [`fit_equation_of_motion`]'s order with the torque's slot 0.
    rows: Vec<[f64; 5]>,
    damping: Damping,
    p: usize,
    ij: usize,
    /// AᵀA (row-major, p × p) and Aᵀy of the fixed columns; the torque's row and column 0.
    ata: Vec<f64>,
    atb: Vec<f64>,
    sst: f64,
}

impl TorqueScan {
    /// The fixed part of [`fit_equation_of_motion`]'s design on these samples.
    pub fn new(
        time_s: &[f64],
        top_rad_s: &[f64],
        bit_rad_s: &[f64],
        bit_accel_rad_s2: &[f64],
        damping: Damping,
    ) -> Self {
        let n = time_s.len();
        let dphi = integrated_twist_rad(time_s, top_rad_s, bit_rad_s);
        let (with_c, with_ca) = columns(damping);
        let p = 3 + with_c as usize + with_ca as usize;
        let ij = p - 2;
        let rows: Vec<[f64; 5]> = (0..n)
            .map(|i| {
                let mut r = [0.0; 5];
                let mut k = 0;
                r[k] = dphi[i];
                k += 1;
                if with_c {
                    r[k] = top_rad_s[i] - bit_rad_s[i];
                    k += 1;
                }
                if with_ca {
                    r[k] = -bit_rad_s[i];
                }
                r[p - 1] = 1.0;
                r
            })
            .collect();
        let (mut ata, mut atb) = (vec![0.0; p * p], vec![0.0; p]);
        for (r, y) in rows.iter().zip(bit_accel_rad_s2) {
            for a in (0..p).filter(|&a| a != ij) {
                atb[a] += r[a] * y;
                for b in (0..p).filter(|&b| b != ij) {
                    ata[a * p + b] += r[a] * r[b];
                }
            }
        }
        let mean = bit_accel_rad_s2.iter().sum::<f64>() / n as f64;
        let sst: f64 = bit_accel_rad_s2.iter().map(|a| (a - mean).powi(2)).sum();
        TorqueScan { acc: bit_accel_rad_s2.to_vec(), rows, damping, p, ij, ata, atb, sst }
    }

    /// The normal equations with `torque_nm` as the torque's column.
    fn normal(&self, torque_nm: &[f64]) -> Normal {
        let (p, ij) = (self.p, self.ij);
        let (mut ata, mut atb) = (self.ata.clone(), self.atb.clone());
        // The torque's entries: −T times each column (itself included), summed in row order.
        let mut col = [0.0; 5];
        let mut ty = 0.0;
        for ((r, t), y) in self.rows.iter().zip(torque_nm).zip(&self.acc) {
            let v = -t;
            ty += v * y;
            for b in 0..p {
                col[b] += v * if b == ij { v } else { r[b] };
            }
        }
        atb[ij] = ty;
        for b in 0..p {
            ata[ij * p + b] = col[b];
            ata[b * p + ij] = col[b];
        }
        Normal::from_row_major(p, &ata, atb)
    }

    /// Σ (Ω̇ − X β)² with `torque_nm` as the torque's column, in row order.
    fn sse(&self, torque_nm: &[f64], coef: &[f64]) -> f64 {
        sse(&self.acc, coef, |i, x| {
            x.copy_from_slice(&self.rows[i][..self.p]);
            x[self.ij] = -torque_nm[i];
        })
    }

    /// R² of [`fit_equation_of_motion`] with `torque_nm` (bit for bit); None where it
    /// errs (a singular design, or an inverse inertia not above 0).
    pub fn r_squared(&self, torque_nm: &[f64]) -> Option<f64> {
        let coef = self.normal(torque_nm).solve()?;
        if coef[self.ij] <= 0.0 {
            return None;
        }
        Some(1.0 - self.sse(torque_nm, &coef) / self.sst)
    }

    /// [`fit_equation_of_motion`] with `torque_nm` as the torque (the time,
    /// speeds, acceleration and damping of [`TorqueScan::new`]), bit for bit,
    /// its errors included.
    pub fn fit(&self, torque_nm: &[f64]) -> Result<EomFit, LaviError> {
        let n = self.acc.len();
        if torque_nm.len() != n || n < 8 {
            return Err(unequal_or_short(n));
        }
        let normal = self.normal(torque_nm);
        let (coef, flat) = normal.solve().zip(normal.inverse()).ok_or_else(collinear)?;
        let inverse = flat.chunks(self.p).map(<[f64]>::to_vec).collect();
        let sse = self.sse(torque_nm, &coef);
        let fit = crate::lsq::LeastSquares { coef, inverse, sse, points: n };
        eom_fit(&fit, self.damping, self.sst)
    }
}

/// Which damping columns a structure's design carries: (on the twist rate, on the bit speed).
fn columns(damping: Damping) -> (bool, bool) {
    match damping {
        Damping::TwistRate => (true, false),
        Damping::Absolute => (false, true),
        Damping::Both => (true, true),
        Damping::Fixed0 => (false, false),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig_model::one_dof::{Coulomb, Drive, OneDofState, Shaft, simulate};

    const FS: f64 = 1000.0;

    /// Stick-slip under a top speed 1 + 0.5 sin(2π 0.3 t) rad/s, simulated by the one core;
    /// acceleration by central difference of the simulated speed (what the study does on filtered data).
    /// Time, top speed, bit speed, bit acceleration, contact torque.
    type Record = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

    fn record(twist_c: f64, abs_c: f64) -> Record {
        let n = 20_000;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / FS).collect();
        let u: Vec<f64> = t.iter().map(|x| 1.0 + 0.5 * (std::f64::consts::TAU * 0.3 * x).sin()).collect();
        let shaft = Shaft {
            inertia_kgm2: 0.05,
            stiffness_nm_rad: 2.0,
            twist_damping_nm_s_rad: twist_c,
            absolute_damping_nm_s_rad: abs_c,
            mid: None,
        };
        let law = Coulomb { static_nm: 1.8, kinetic_nm: 1.0 };
        let r = simulate(&shaft, &law, Drive::Speed(&u), None, OneDofState::default(), FS, n, 10).unwrap();
        assert!(r.stuck.iter().filter(|s| **s).count() > 1000, "expected stick-slip");
        let acc = crate::data::derivative(&r.bit_rad_s, FS);
        (t, u, r.bit_rad_s, acc, r.friction_nm)
    }

    #[test]
    fn the_fit_recovers_j_k_and_the_damping_where_it_acts() {
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        // Differences that straddle a stick/slip kink are biased; they are few, and the fit must cope.
        let (t, u, om, acc, tq) = record(0.02, 0.0);
        let f = fit_equation_of_motion(&t, &u, &om, &acc, &tq, Damping::TwistRate).unwrap();
        assert!(rel(f.inertia_kgm2, 0.05) < 0.01 && rel(f.stiffness_nm_rad, 2.0) < 0.01, "{f:?}");
        assert!(rel(f.damping_nm_s_rad, 0.02) < 0.05 && f.r_squared > 0.99, "{f:?}");
        assert!(f.initial_twist_rad.abs() < 0.01, "{f:?}");
        // A drag on the absolute speed is found where it acts, and not mistaken for twist damping.
        let (t, u, om, acc, tq) = record(0.0, 0.03);
        let f = fit_equation_of_motion(&t, &u, &om, &acc, &tq, Damping::Both).unwrap();
        assert!(rel(f.absolute_damping_nm_s_rad, 0.03) < 0.05, "{f:?}");
        assert!(f.damping_nm_s_rad.abs() < 3.0 * f.damping_stderr.max(1e-3), "{f:?}");
        // Fitted with the damping on the twist rate only, the drag is not representable: a worse fit.
        let wrong = fit_equation_of_motion(&t, &u, &om, &acc, &tq, Damping::TwistRate).unwrap();
        assert!(wrong.r_squared < f.r_squared, "{wrong:?} vs {f:?}");
    }

    #[test]
    fn the_scan_gives_each_delays_r_squared_bit_for_bit() {
        let (t, u, om, acc, tq) = record(0.02, 0.01);
        for damping in [Damping::TwistRate, Damping::Absolute, Damping::Both, Damping::Fixed0] {
            let scan = TorqueScan::new(&t, &u, &om, &acc, damping);
            for k in [0usize, 7, 30] {
                // The torque read k samples later (the record's end standing in beyond it).
                let late: Vec<f64> = (0..tq.len()).map(|i| tq[(i + k).min(tq.len() - 1)]).collect();
                let one = fit_equation_of_motion(&t, &u, &om, &acc, &late, damping).unwrap();
                assert_eq!(scan.r_squared(&late).map(f64::to_bits), Some(one.r_squared.to_bits()), "{damping:?} {k}");
            }
            // A torque of the wrong sign gives a negative inverse inertia: refused like the fit refuses it.
            let neg: Vec<f64> = tq.iter().map(|x| -x).collect();
            assert_eq!(
                scan.r_squared(&neg).is_some(),
                fit_equation_of_motion(&t, &u, &om, &acc, &neg, damping).is_ok()
            );
            assert_eq!(
                scan.fit(&neg).map_err(|e| e.to_string()),
                fit_equation_of_motion(&t, &u, &om, &acc, &neg, damping).map_err(|e| e.to_string())
            );
        }
    }

    #[test]
    fn the_scan_fits_each_torque_column_bit_for_bit() {
        let (t, u, om, acc, tq) = record(0.02, 0.01);
        for damping in [Damping::TwistRate, Damping::Absolute, Damping::Both, Damping::Fixed0] {
            let scan = TorqueScan::new(&t, &u, &om, &acc, damping);
            // The torque less a sensor inertia's J_s Ω̇ (the `sensor_inertia` fit's column), and read late.
            for (js, k) in [(0.0, 0usize), (0.004, 0), (0.05, 3), (0.5, 30)] {
                let tf: Vec<f64> = (0..tq.len()).map(|i| tq[(i + k).min(tq.len() - 1)] - js * acc[i]).collect();
                let one = fit_equation_of_motion(&t, &u, &om, &acc, &tf, damping).unwrap();
                // Debug prints every float's shortest round trip: equal strings, equal bits.
                assert_eq!(format!("{:?}", scan.fit(&tf).unwrap()), format!("{one:?}"), "{damping:?} {js} {k}");
            }
            // A column too short is refused as the fit refuses it.
            assert!(scan.fit(&tq[..5]).is_err());
        }
    }
}
