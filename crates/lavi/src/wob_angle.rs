//! `wob_angle`: the contact's normal force follows where the bit is, not when.
//!
//! Coulomb's law on the bit's face, T = r μ(Ω) N (the thesis' Eq. 4-11 idea
//! of a normal force that varies), with N a function of the bit's angle θ:
//! N(θ)/N̄ = 1 + Σ_{h=1..3} (a_h cos hθ + b_h sin hθ). The physics: a rotating
//! face that is not flat or not square to its axis (runout, a thickness
//! variation, a warped disc) pushes the pressed counter-face back by an amount
//! that depends on the face's angle, so the normal force and the friction
//! torque vary at harmonics of the revolution (disc-brake judder: a
//! non-parallel or wobbling disc gives a pad-force and torque variation per
//! revolution; Automotive Chassis Engineering §5.11; the thesis' Eq. 4-11
//! names the varying normal force, not its origin).
//!
//! Why it is a candidate (the diagnosis, docs/findings.md, twentieth
//! session): on the calibration window the weight on bit's fast part (std
//! 60 N, 11 % of its mean) is 82 % the bit angle's harmonics (least squares,
//! 91 N twice per revolution, 7 and 4 N once and three times), and the
//! stick-slip fundamental is twice the revolution rate on most windows
//! (2.70 Hz against 2.77; 52–54 s 3.06 against 3.06, 54–56 s 2.25 against
//! 2.27). `wob_normal_force` drives the friction with W(t), whose fast part
//! is in the record's phase of the cycle, not the free run's; here the free
//! run carries it in its own phase: the simulated bit's angle sets it.
//!
//! Fit (calibration window only, linear least squares, no simulation fit):
//! the relative WOB W/W̄_cal − 1 (W̄_cal its mean over the window) on
//! [1, cos hθ, sin hθ]_{h=1..3}, θ the measured bit angle (the record's bit
//! speed integrated from its first sample); the constant is dropped (the law
//! was fitted at the window's mean normal force). The law, J, k, c and every
//! other effect kept. In the free run θ starts at the measured angle and
//! advances with the simulated |Ω| (the bit hardly reverses: its least speed
//! is −4 rpm on the calibration window); while stuck it stays, so the
//! break-away level is the normal force where the bit stopped.
//!
//! On run 175 (docs/findings.md, twentieth session; lavi.md's section of the
//! angle): 16.5 % twice per revolution (R² 0.84); step 1 calibration 6.197 →
//! 5.852, held out 6.301 → 6.311 (gain −0.2 %); on top of `top_delay` the
//! calibration window refuses it (0.195 → 1.142): not kept. Why: the final
//! model's free run, with no angle in its contact, already enters stick at
//! the record's angles (within a few degrees of 2θ), carried there by the
//! imposed top speed; the WOB's angle harmonic is not the friction's (the
//! torque over the law in slip: 6 % at −89° of 2θ against the WOB's 16.5 %
//! at −36°; a candidate fitted on that, `angle_friction`, went 0.195 →
//! 0.372 on the calibration window and was removed).
//!
//! Admissibility, stated before any held-out result was looked at: the
//! harmonics must explain at least [`MIN_R2`] of the relative WOB's variance
//! on the calibration window (else the WOB does not follow the angle there
//! and the candidate is refused), the model must not drive the friction with
//! the instantaneous WOB already (`wob_normal_force`: the fast part twice),
//! and the selection's own rule (no worse on the calibration window, gain
//! ≥ 5 %, paired t ≥ 2).

use crate::score::Evaluator;
use crate::sim::Model;
use crate::{Candidate, LaviError};
use serde::Serialize;
use std::collections::BTreeMap;

/// Harmonics of the revolution fitted (1, 2, 3 per revolution).
pub const HARMONICS: usize = 3;
/// The least share of the relative WOB's variance on the calibration window the
/// angle's harmonics must explain (stated before the held-out windows were looked at).
pub const MIN_R2: f64 = 0.5;

/// The normal force's dependence on the bit's angle, relative to its mean:
/// N(θ)/N̄ = 1 + Σ_h (cos_h cos hθ + sin_h sin hθ), h = 1..[`HARMONICS`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WobAngle {
    pub cos: [f64; HARMONICS],
    pub sin: [f64; HARMONICS],
}

impl WobAngle {
    /// N(θ)/N̄ at the bit angle `theta_rad`.
    pub fn factor(&self, theta_rad: f64) -> f64 {
        let mut f = 1.0;
        for h in 0..HARMONICS {
            let (s, c) = ((h + 1) as f64 * theta_rad).sin_cos();
            f += self.cos[h] * c + self.sin[h] * s;
        }
        f
    }

    /// The amplitude of harmonic `h` (1-based), relative to the mean normal force.
    pub fn amplitude(&self, h: usize) -> f64 {
        self.cos[h - 1].hypot(self.sin[h - 1])
    }
}

/// The least-squares [`WobAngle`] of the relative WOB `wob_n` on the bit angle
/// `theta_rad` (same samples), and the share of the relative WOB's variance it explains.
pub fn fit_harmonics(wob_n: &[f64], theta_rad: &[f64]) -> Option<(WobAngle, f64)> {
    let mean = wob_n.iter().sum::<f64>() / wob_n.len().max(1) as f64;
    let y: Vec<f64> = wob_n.iter().map(|w| w / mean - 1.0).collect();
    harmonics_of(&y, theta_rad)
}

/// The least-squares harmonics of the angle `theta_rad` in the relative deviation `y`
/// (y ≈ c + Σ_h a_h cos hθ + b_h sin hθ; the constant c dropped), and the share of y's variance
/// they explain with c.
pub fn harmonics_of(y: &[f64], theta_rad: &[f64]) -> Option<(WobAngle, f64)> {
    let n = y.len();
    if n != theta_rad.len() || n < 4 * HARMONICS {
        return None;
    }
    let row = |i: usize| {
        let mut r = vec![1.0];
        for h in 1..=HARMONICS {
            let (s, c) = (h as f64 * theta_rad[i]).sin_cos();
            r.push(c);
            r.push(s);
        }
        r
    };
    let ls = crate::lsq::least_squares(y, 1 + 2 * HARMONICS, row)?;
    let ym = y.iter().sum::<f64>() / n as f64;
    let sst: f64 = y.iter().map(|v| (v - ym) * (v - ym)).sum();
    let r2 = if sst > 0.0 { 1.0 - ls.sse / sst } else { 0.0 };
    let mut a = WobAngle { cos: [0.0; HARMONICS], sin: [0.0; HARMONICS] };
    for h in 0..HARMONICS {
        a.cos[h] = ls.coef[1 + 2 * h];
        a.sin[h] = ls.coef[2 + 2 * h];
    }
    Some((a, r2))
}

/// Fits `wob_angle` on top of `current` (module docs); fills the candidate's parameters.
pub fn fit(current: &Model, ev: &Evaluator, params: &mut BTreeMap<String, f64>) -> Result<(Model, usize), LaviError> {
    let refuse = |reason: String| Err(LaviError::Refused { candidate: Candidate::WobAngle.id(), reason });
    if current.wob_ref_n.is_some() {
        return refuse(
            "the instantaneous weight on bit is the model's normal force already (`wob_normal_force`)".into(),
        );
    }
    if current.wob_angle.is_some() {
        return refuse("the model's normal force follows the bit's angle already".into());
    }
    let cal = &ev.windows[ev.calibration()];
    let r = cal.span.start + cal.window.start..cal.span.start + cal.window.end;
    let Some((a, r2)) = fit_harmonics(&ev.data.wob_n[r.clone()], &ev.bit_angle_rad()[r]) else {
        return refuse("the least squares of the weight on bit on the bit's angle is singular".into());
    };
    if r2 < MIN_R2 {
        return refuse(format!(
            "the weight on bit does not follow the bit's angle on the calibration window: its harmonics explain {:.0} \
             % of the relative WOB's variance, below {:.0} %",
            100.0 * r2,
            100.0 * MIN_R2
        ));
    }
    for h in 1..=HARMONICS {
        params.insert(format!("wob_angle_amplitude_{h}"), a.amplitude(h));
    }
    params.insert("wob_angle_r2".into(), r2);
    Ok((Model { wob_angle: Some(a), ..*current }, 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A WOB of 500 N ± 60 N twice per revolution and 10 N once, sampled over 3 revolutions:
    /// the least squares returns the relative amplitudes and phases, and all the variance.
    #[test]
    fn harmonics_of_a_known_wob_come_back() {
        let theta: Vec<f64> = (0..3000).map(|i| i as f64 * 3.0 * std::f64::consts::TAU / 3000.0).collect();
        let wob: Vec<f64> = theta.iter().map(|t| 500.0 + 60.0 * (2.0 * t - 0.5).cos() + 10.0 * t.sin()).collect();
        let (a, r2) = fit_harmonics(&wob, &theta).unwrap();
        assert!((a.amplitude(2) - 0.12).abs() < 1e-9, "{}", a.amplitude(2));
        assert!((a.amplitude(1) - 0.02).abs() < 1e-9, "{}", a.amplitude(1));
        assert!(a.amplitude(3) < 1e-9);
        assert!((a.cos[1] - 0.12 * 0.5f64.cos()).abs() < 1e-9);
        assert!((a.sin[1] - 0.12 * 0.5f64.sin()).abs() < 1e-9);
        assert!((r2 - 1.0).abs() < 1e-9);
        assert!((a.factor(0.25) - (1.0 + 0.12 * (0.5f64 - 0.5).cos() + 0.02 * 0.25f64.sin())).abs() < 1e-9);
    }

    /// A bit that enters stick every half turn at θ = 0.3 + kπ: every entry at one 2θ (resultant 1,
    /// phase 0.6 rad); entries at a quarter turn apart in turn cancel (resultant 0).
    #[test]
    fn stick_entries_at_one_angle_have_resultant_one() {
        // 1 rad per 100 samples; the speed below 5 rpm for 20 samples after each entry.
        let theta: Vec<f64> = (0..2000).map(|i| i as f64 * 0.01).collect();
        let entries = |step: f64| -> Vec<f64> {
            let mut v = vec![60.0; 2000];
            let mut a: f64 = 0.3;
            while a < 19.5 {
                let i = (a * 100.0).round() as usize;
                v[i..i + 20].iter_mut().for_each(|x| *x = 0.0);
                a += step;
            }
            v
        };
        let (n, r, ph) = lock_of(&entries(std::f64::consts::PI), &theta, 0..2000, 5.0);
        assert_eq!(n, 7);
        assert!((r - 1.0).abs() < 1e-3, "{r}");
        assert!((ph.to_radians() - 0.6).abs() < 0.02, "{ph}");
        let (n, r, _) = lock_of(&entries(std::f64::consts::FRAC_PI_2), &theta, 0..2000, 5.0);
        assert_eq!(n, 13);
        assert!(r < 0.1, "{r}");
    }

    /// A WOB that does not follow the angle (a function of time at an incommensurate rate) is not fitted by it.
    #[test]
    fn a_wob_off_the_angle_explains_little() {
        let theta: Vec<f64> = (0..4000).map(|i| i as f64 * 0.004).collect();
        let wob: Vec<f64> = (0..4000).map(|i| 500.0 + 50.0 * (i as f64 * 0.0173).sin()).collect();
        let (_, r2) = fit_harmonics(&wob, &theta).unwrap();
        assert!(r2 < MIN_R2, "{r2}");
    }
}

/// How one window's stick phases sit on the bit's angle, measured and in the final model's free run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AngleLock {
    /// Twice the bit's revolution rate over the window (measured), Hz.
    pub twice_rev_hz: f64,
    /// Stick entries in the window (the low-passed bit speed falling below the stick speed).
    pub entries: usize,
    /// |mean e^{i 2θ}| over the entries (1: every entry at one angle modulo half a turn; 0: spread).
    pub resultant: f64,
    /// arg mean e^{i 2θ}, degrees.
    pub phase_deg: f64,
    /// The same for the final model's free run, θ its own bit's angle from the measured one at its start.
    pub sim_entries: usize,
    pub sim_resultant: f64,
    pub sim_phase_deg: f64,
}

/// The entries into stick of the low-passed speed `v_rpm` within `window` (indices into `v_rpm`),
/// and the resultant and phase of 2θ there.
fn lock_of(v_rpm: &[f64], theta_rad: &[f64], window: std::ops::Range<usize>, stick_rpm: f64) -> (usize, f64, f64) {
    let (mut n, mut c, mut s) = (0usize, 0.0, 0.0);
    for i in window.start.max(1)..window.end {
        if v_rpm[i] < stick_rpm && v_rpm[i - 1] >= stick_rpm {
            n += 1;
            let (sn, cs) = (2.0 * theta_rad[i]).sin_cos();
            c += cs;
            s += sn;
        }
    }
    if n == 0 {
        return (0, f64::NAN, f64::NAN);
    }
    let (c, s) = (c / n as f64, s / n as f64);
    (n, c.hypot(s), s.atan2(c).to_degrees())
}

/// [`AngleLock`] per window (calibration first) of the record and of `model`'s free runs.
pub fn angle_locks(ev: &Evaluator, model: &Model) -> Result<Vec<AngleLock>, LaviError> {
    let o = &ev.fopts;
    let theta = ev.bit_angle_rad();
    (0..ev.windows.len())
        .map(|wi| {
            let w = &ev.windows[wi];
            let s = w.span.clone();
            let v = rig_spectra::lowpass_fft(&ev.data.bit_raw_rpm[s.clone()], o.fs_hz, o.cutoff_hz, o.transition_hz)?;
            let (entries, resultant, phase_deg) = lock_of(&v, &theta[s.clone()], w.window.clone(), o.stick_speed_rpm);
            let (a, b) = (s.start + w.window.start, s.start + w.window.end - 1);
            let secs = (b - a) as f64 / o.fs_hz;
            let twice_rev_hz = 2.0 * (theta[b] - theta[a]) / std::f64::consts::TAU / secs;
            let run = ev.simulate(model, wi)?;
            let rpm: Vec<f64> = run.bit_rad_s.iter().map(|x| x / crate::data::RPM_TO_RAD_S).collect();
            let vs = rig_spectra::lowpass_fft(&rpm, o.fs_hz, o.cutoff_hz, o.transition_hz)?;
            // The simulated bit's angle: the measured one at the run's start, then ∫ Ω dt (one trapezoid home).
            let zeros = vec![0.0; run.bit_rad_s.len()];
            let th_sim: Vec<f64> =
                rig_model::one_dof::integrated_twist_rad(&ev.data.time_s[s.clone()], &run.bit_rad_s, &zeros)
                    .into_iter()
                    .map(|x| x + theta[s.start])
                    .collect();
            let (sim_entries, sim_resultant, sim_phase_deg) =
                lock_of(&vs, &th_sim, w.window.clone(), o.stick_speed_rpm);
            Ok(AngleLock { twice_rev_hz, entries, resultant, phase_deg, sim_entries, sim_resultant, sim_phase_deg })
        })
        .collect()
}

/// lavi.md's section of the angle: where the bit sticks, in the record and in the final model's
/// free run, and the candidate that puts the angle in the contact.
pub fn section(s: &crate::study::Study) -> String {
    use std::fmt::Write as _;
    if s.angle_locks.is_empty() {
        return String::new();
    }
    let mut md = String::from("## Where the bit sticks: the bit's angle (`wob_angle`)\n\n");
    let _ = writeln!(
        md,
        "Per window, the entries into stick (the bit speed through the features' one low-pass falling below the stick speed) against the \
         bit's angle θ (the record's bit speed integrated from its first sample; in a free run the simulated bit's, from the measured angle \
         at its start): the resultant |mean e^{{i2θ}}| over the entries (1: every entry at one angle, modulo half a turn; about 1/√n for \
         entries spread at random) and its phase; and the measured fundamental against twice the revolution rate.\n"
    );
    let _ = writeln!(
        md,
        "| window | twice the revolution rate [Hz] | fundamental measured / final model [Hz] | stick entries measured: n, resultant, 2θ phase | final model's free run: n, resultant, 2θ phase |\n|---|---|---|---|---|"
    );
    for (i, l) in s.angle_locks.iter().enumerate() {
        let _ = writeln!(
            md,
            "| {} | {:.2} | {:.2} / {:.2} | {}, {:.2}, {:.0}° | {}, {:.2}, {:.0}° |",
            s.windows[i].label,
            l.twice_rev_hz,
            s.measured[i].fundamental_hz,
            s.final_features[i].fundamental_hz,
            l.entries,
            l.resultant,
            l.phase_deg,
            l.sim_entries,
            l.sim_resultant,
            l.sim_phase_deg
        );
    }
    // How far the free run's stick angle is from the record's, over the windows where both stick.
    let both: Vec<&AngleLock> = s.angle_locks.iter().filter(|l| l.entries > 0 && l.sim_entries > 0).collect();
    let gap = |l: &&AngleLock| {
        let d = (l.sim_phase_deg - l.phase_deg).rem_euclid(360.0);
        d.min(360.0 - d)
    };
    let worst_gap = both.iter().map(gap).fold(0.0f64, f64::max);
    let least_r = s.angle_locks.iter().filter(|l| l.entries > 1).map(|l| l.resultant).fold(f64::INFINITY, f64::min);
    let least_sim_r = both.iter().filter(|l| l.sim_entries > 1).map(|l| l.sim_resultant).fold(f64::INFINITY, f64::min);
    let _ = writeln!(
        md,
        "\nThe bit enters stick at one angle modulo half a turn in every window (resultant at least {least_r:.2} where it sticks more \
         than once), the phase drifting slowly over the record's revolutions. The final model's free run, whose contact has no angle in \
         it, does the same (resultant at least {least_sim_r:.2}), within {worst_gap:.0}° of 2θ of the record's phase on the {} windows \
         where both stick: the imposed top speed, as measured, carries the stick phases' place on the revolution into the free run. \
         So the locking is no sign of a contact that the model lacks.\n",
        both.len()
    );
    let trials: Vec<String> = s
        .selection
        .trials
        .iter()
        .filter(|t| t.candidate == Candidate::WobAngle)
        .map(|t| {
            let before = if t.step == 1 {
                s.selection.baseline_calibration
            } else {
                s.selection.trials[s.selection.chosen[t.step - 2]].fitted.calibration_misfit
            };
            match &t.refused {
                Some(r) => format!("step {}: refused ({r})", t.step),
                None => {
                    let p = |k: &str| t.fitted.params.get(k).copied().unwrap_or(f64::NAN);
                    format!(
                        "step {}: twice per revolution {:.1} % (once {:.1} %, three times {:.1} %), R² {:.2}; calibration misfit {:.3} \
                         against {:.3} without, held out {:.3} ({})",
                        t.step,
                        100.0 * p("wob_angle_amplitude_2"),
                        100.0 * p("wob_angle_amplitude_1"),
                        100.0 * p("wob_angle_amplitude_3"),
                        p("wob_angle_r2"),
                        t.fitted.calibration_misfit,
                        before,
                        t.heldout_misfit,
                        if t.earns_place { "earns its place" } else { "not kept" }
                    )
                }
            }
        })
        .collect();
    let _ = writeln!(
        md,
        "**The candidate** (rig_lavi::wob_angle): the weight on bit's fast part as a function of the bit's angle, N(θ)/N̄ = 1 + \
         Σ_{{h=1..3}} (a_h cos hθ + b_h sin hθ) by linear least squares on the calibration window (a face out of flat or square pushing \
         its counter-face back per revolution), the friction scaled by it with θ the free run's own angle, the law, J, k, c kept: {}.\n",
        trials.join("; ")
    );
    md
}
