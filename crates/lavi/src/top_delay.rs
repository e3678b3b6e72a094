//! `top_delay`: the top-speed channel on another clock than the bit speed.
//!
//! The bit's equation of motion (Real et al. 2018's 1-DOF, [`crate::eom`]):
//! J Ω̇ = k φ + c (Ω_top − Ω) − c_a Ω − T_f, φ̇ = Ω_top − Ω, with the top's
//! speed read from its channel τ_top later, Ω_top(t) = Ω_top,m(t + τ_top)
//! (τ_top > 0: the channel is late on the bit speed; < 0: early), and the
//! torque channel late by τ on the same bit-speed clock (`channel_delay`'s
//! T_f(t) = T_m(t + τ)). A clock offset moves no sample's value: the twist
//! φ = ∫(Ω_top − Ω) dt and the drive a free run is given move by τ_top, the
//! record's angle is kept (the integral of a shifted channel is the shifted
//! integral).
//!
//! Why it is a candidate: with the torque read 31 ms late, the top speed
//! *leads* the string torque by about 21 ms (a motor inertia fitted with the
//! torque as the output crosses 0 when the top speed is read 21 ms earlier:
//! `motor_drive`'s section), while the bit's equation of motion hardly sees
//! the top's clock (its R² moves little over ±40 ms while k trades 3–8 N m/rad).
//! A top speed on the wrong clock drives a free run with the right samples at
//! the wrong phase of the stick-slip cycle.
//!
//! Fit, on the calibration window only ([`fit`]):
//! 1. *The scan* ([`scan`]): τ_top over ±[`MAX_DELAY_S`] (a 5 ms grid, then
//!    1 ms steps within ±4 ms of its best); for each, the torque delay by least
//!    squares of the equation of motion with the top read τ_top later
//!    ([`crate::fit::best_delay_s`], ±50 ms), J, k, c and the law of the torque as
//!    that structure reads it ([`crate::fit::derive`]: the falling law the
//!    torque channel shows, no simulation fit), and its free run's calibration
//!    misfit. The best τ_top is where the least-squares law runs best.
//! 2. *The law by simulation*: on that structure (τ_top, the torque delay and
//!    J, k, c held), the law refitted like `friction_law`'s (three families by
//!    Nelder–Mead from the least-squares law, on the calibration misfit), as
//!    `channel_delay` refits it after its least-squares delay.
//! 3. The better of 1 and 2 on the calibration window (`law_from_torque` 1:
//!    step 1's least-squares law). A best τ_top at ±50 ms, the end of the scan,
//!    is reported at its bound.

use crate::Candidate;
use crate::LaviError;
use crate::fit::{AtBound, MAX_DELAY_S, Structure, best_delay_s, family_of, insert_law_params, law_by_simulation};
use crate::score::Evaluator;
use crate::select::Selection;
use crate::sim::Model;
use rig_types::select::{Comparison, compare, overall};
use serde::Serialize;
use std::collections::BTreeMap;

/// One τ_top of the scan: the structure's least-squares model on the calibration window and its free run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ScanPoint {
    pub top_delay_s: f64,
    /// The torque channel's delay that fits the equation of motion best with the top read τ_top later, s.
    pub torque_delay_s: f64,
    /// R² of the equation of motion (unconstrained) at that pair.
    pub r_squared: f64,
    pub stiffness_nm_rad: f64,
    /// c on the twist rate, unconstrained, N m s/rad.
    pub damping_nm_s_rad: f64,
    /// The least-squares law at 0 and at the calibration window's mean cycle maximum, N m.
    pub law_static_nm: f64,
    pub law_at_max_nm: f64,
    /// Calibration misfit of the free run with that J, k, c and law.
    pub calibration_misfit: f64,
}

/// Grid of the scan's first pass, s.
const COARSE_S: f64 = 0.005;

/// The structure `current` carries, with the top read `top_delay_s` later and the torque delay re-chosen by least squares.
fn structure_at(ev: &Evaluator, current: &Model, top_delay_s: f64) -> Structure {
    let cal = &ev.windows[ev.calibration()];
    let st = Structure { top_delay_s, ..current.structure };
    Structure { torque_delay_s: best_delay_s(ev.data, cal, st, MAX_DELAY_S), ..st }
}

/// The scan point and its model at `top_delay_s` (module docs, step 1).
fn point(ev: &Evaluator, current: &Model, top_delay_s: f64) -> Result<(ScanPoint, Model), LaviError> {
    let cal = ev.calibration();
    let st = structure_at(ev, current, top_delay_s);
    let (m, der) = ev.derivation(st)?;
    let m = m.with_effects_of(current);
    let vmax = ev.measured[cal].bit_speed_max_rpm * crate::data::RPM_TO_RAD_S;
    let p = ScanPoint {
        top_delay_s,
        torque_delay_s: st.torque_delay_s,
        r_squared: der.free.r_squared,
        stiffness_nm_rad: der.free.stiffness_nm_rad,
        damping_nm_s_rad: der.free.damping_nm_s_rad,
        law_static_nm: m.friction.slip_nm(0.0),
        law_at_max_nm: m.friction.slip_nm(vmax),
        // Made with the scan's other points ([`scan_models`]).
        calibration_misfit: f64::NAN,
    };
    Ok((p, m))
}

/// Step 1 of the module docs on top of `current`: every point visited, in
/// ascending τ_top, and the index of the best (least calibration misfit; ties: the smaller |τ_top|).
pub fn scan(ev: &Evaluator, current: &Model) -> Result<(Vec<ScanPoint>, usize), LaviError> {
    let (pts, i) = scan_models(ev, current)?;
    Ok((pts.into_iter().map(|p| p.0).collect(), i))
}

/// [`scan`] with each point's model (the best one is the fit's step 1: not derived twice).
fn scan_models(ev: &Evaluator, current: &Model) -> Result<(Vec<(ScanPoint, Model)>, usize), LaviError> {
    use rayon::prelude::*;
    let fs = ev.data.fs_hz;
    let whole = |s: f64| crate::sim::delay_samples(s, fs);
    let m = whole(MAX_DELAY_S);
    let step = whole(COARSE_S).max(1);
    let coarse: Vec<isize> = (-m..=m).filter(|k| k % step == 0).collect();
    let run = |ks: &[isize]| -> Result<Vec<(ScanPoint, Model)>, LaviError> {
        let mut pts: Vec<(ScanPoint, Model)> =
            ks.par_iter().map(|&k| point(ev, current, k as f64 / fs)).collect::<Result<_, _>>()?;
        let cal = ev.calibration();
        let misfits = ev.misfits(&pts.iter().map(|p| (&p.1, cal)).collect::<Vec<_>>());
        for (p, v) in pts.iter_mut().zip(misfits) {
            p.0.calibration_misfit = v;
        }
        Ok(pts)
    };
    let mut pts = run(&coarse)?;
    let best_k = |pts: &[(ScanPoint, Model)]| -> isize {
        let b = pts
            .iter()
            .map(|p| &p.0)
            .reduce(|a, b| {
                let key = |p: &ScanPoint| (p.calibration_misfit, p.top_delay_s.abs());
                if key(b) < key(a) { b } else { a }
            })
            .expect("a point at least");
        whole(b.top_delay_s)
    };
    let c = best_k(&pts);
    let fine: Vec<isize> = (c - step + 1..c + step).filter(|k| k.abs() <= m && k % step != 0).collect();
    pts.extend(run(&fine)?);
    pts.sort_by(|a, b| a.0.top_delay_s.total_cmp(&b.0.top_delay_s));
    let b = best_k(&pts);
    let i = pts.iter().position(|p| whole(p.0.top_delay_s) == b).expect("the best is a point");
    Ok((pts, i))
}

/// Fits `top_delay` on top of `current` (module docs); fills the candidate's
/// parameters and bounds; returns the model and the evaluations spent.
pub fn fit(
    current: &Model,
    ev: &Evaluator,
    max_evals: usize,
    params: &mut BTreeMap<String, f64>,
    at_bounds: &mut Vec<AtBound>,
    scan_out: &mut Vec<ScanPoint>,
) -> Result<(Model, usize), LaviError> {
    let cal = ev.calibration();
    let (pts, best) = scan_models(ev, current)?;
    let from_torque = pts[best].1;
    let pts: Vec<ScanPoint> = pts.into_iter().map(|p| p.0).collect();
    // Step 2: the law refitted by simulation on that structure (τ_top and the torque delay held).
    let (refit, n, _) = law_by_simulation(&from_torque, ev, max_evals);
    let law_from_torque = ev.misfit(&refit, cal) >= pts[best].calibration_misfit;
    let m = if law_from_torque { from_torque } else { refit };
    if pts[best].top_delay_s.abs() >= MAX_DELAY_S - 0.5 / ev.data.fs_hz {
        at_bounds.push(AtBound {
            parameter: "top_delay_s",
            bound: pts[best].top_delay_s,
            unconstrained: f64::NAN,
            stderr: f64::NAN,
            meaning: "the calibration window wants the top speed read 50 ms or more off the bit speed, the end of the \
                      scanned range: no clock offset the scan can place"
                .into(),
        });
    }
    params.insert("top_delay_s".into(), m.structure.top_delay_s);
    params.insert("torque_delay_s".into(), m.torque_delay_s);
    params.insert("law_from_torque".into(), f64::from(u8::from(law_from_torque)));
    insert_law_params(params, &m, family_of(&m.friction));
    let evals = pts.len() + n;
    *scan_out = pts;
    Ok((m, evals))
}

/// What the study reports of `top_delay`: its step-1 trial (fitted on the
/// baseline) with its scan, side by side with every other step-1 candidate,
/// and per window the targets before (`channel_delay`'s step-1 trial, the
/// model the selection chose before this candidate existed) and after.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TopDelayReport {
    pub scan: Vec<ScanPoint>,
    /// Index into `scan` of the τ_top the fit kept.
    pub best: usize,
    pub model: Model,
    pub law_from_torque: bool,
    pub calibration_misfit: f64,
    pub heldout: Vec<f64>,
    /// Per window (calibration first): the trial's features, and `channel_delay`'s.
    pub features: Vec<crate::Features>,
    pub before: Vec<crate::Features>,
    /// Against every other step-1 candidate: the engine's comparison with it
    /// as `before` and `top_delay` as `after` (paired t of ln(M_it/M_top_delay)
    /// over the held-out windows), and the windows where `top_delay` is better.
    pub rivals: Vec<(Candidate, Comparison, usize)>,
}

/// [`TopDelayReport`] of the selection's step-1 `top_delay` trial (None: refused or not tried).
pub fn report(sel: &Selection, candidate_features: &[(Candidate, Vec<crate::Features>)]) -> Option<TopDelayReport> {
    let step1 = |c: Candidate| sel.trials.iter().find(|t| t.step == 1 && t.candidate == c && t.refused.is_none());
    let t = step1(Candidate::TopDelay)?;
    let feats = |c: Candidate| candidate_features.iter().find(|(x, _)| *x == c).map(|(_, f)| f.clone());
    let best = t.fitted.top_scan.iter().position(|p| p.top_delay_s == t.fitted.model.structure.top_delay_s)?;
    let n = t.heldout.len();
    let folds: Vec<usize> = (0..n).collect();
    let rivals = sel
        .trials
        .iter()
        .filter(|r| r.step == 1 && r.candidate != Candidate::TopDelay && r.refused.is_none())
        .map(|r| {
            let c = compare(&r.heldout, &t.heldout, &folds, n);
            (r.candidate, c, t.heldout.iter().zip(&r.heldout).filter(|(a, b)| a < b).count())
        })
        .collect();
    Some(TopDelayReport {
        scan: t.fitted.top_scan.clone(),
        best,
        model: t.fitted.model,
        law_from_torque: t.fitted.params.get("law_from_torque").is_some_and(|v| *v > 0.5),
        calibration_misfit: t.fitted.calibration_misfit,
        heldout: t.heldout.clone(),
        features: feats(Candidate::TopDelay)?,
        before: feats(Candidate::ChannelDelay)?,
        rivals,
    })
}

/// The `lavi.md` section of `top_delay`: the equation, the scan, the fit, the
/// rivals side by side, per window before → after, and what the data resolve.
pub fn section(s: &crate::study::Study) -> String {
    use std::fmt::Write as _;
    let Some(r) = &s.top_delay else { return String::new() };
    let ms = |x: f64| 1e3 * x;
    let b = &r.scan[r.best];
    let zero = r.scan.iter().find(|p| p.top_delay_s == 0.0).unwrap_or(b);
    let mut md = String::from("## The top speed's clock (`top_delay`)\n\n");
    let _ = writeln!(
        md,
        "The bit's equation of motion J Ω' = k φ + c (Ω_top − Ω) − T_f, φ' = Ω_top − Ω (Real et al. 2018; rig_lavi::eom) with \
         the top's speed read from its channel τ_top later, Ω_top(t) = Ω_top,m(t + τ_top) [s; > 0: the channel late on the bit \
         speed], and the torque channel late by τ on the same clock (`channel_delay`'s T_f(t) = T_m(t + τ)). A clock offset moves \
         no sample: the twist and the drive of a free run move by τ_top, the record's angle is kept. Fitted on the calibration \
         window only (rig_lavi::top_delay): for each τ_top within ±50 ms (5 ms steps, then 1 ms within ±4 ms of the best), τ by \
         least squares of the equation of motion, J, k, c and the law of the torque as that structure reads it (no simulation \
         fit), and the free run's calibration misfit; then the law refitted by simulation on the best structure, the better of \
         the two kept.\n"
    );
    md.push_str(
        "| τ_top [ms] | τ (torque) [ms] | R² of the equation of motion | k [N m/rad] | c [N m s/rad] | least-squares law T(0) → \
         T(cycle max) [N m] | calibration misfit |\n|---|---|---|---|---|---|---|\n",
    );
    for (i, p) in r.scan.iter().enumerate() {
        let mark = if i == r.best { " **(kept)**" } else { "" };
        let _ = writeln!(
            md,
            "| {:+.0}{mark} | {:+.0} | {:.4} | {:.3} | {:+.4} | {:.3} → {:.3} | {:.3} |",
            ms(p.top_delay_s),
            ms(p.torque_delay_s),
            p.r_squared,
            p.stiffness_nm_rad,
            p.damping_nm_s_rad,
            p.law_static_nm,
            p.law_at_max_nm,
            p.calibration_misfit
        );
    }
    let f = &r.model.friction;
    let _ = writeln!(
        md,
        "\n**The fit.** τ_top = {:+.0} ms with τ = {:+.0} ms (the top speed {:.0} ms late on the torque): J = {:.4} kg m², k = {:.3} \
         N m/rad, c = {:.4} N m s/rad (R² {:.4}; at τ_top = 0: k = {:.3}, c = {:.4}, R² {:.4}). {} T = {:.3} + {:.3} exp(−(Ω/{:.2} \
         rad/s)^{:.0}) N m ({:.3} → {:.3} N m from 0 to the calibration window's mean cycle maximum): calibration misfit {:.3} (at \
         τ_top = 0 the same kind of law runs to {:.3}), held-out misfit {:.3} (per window: {}).\n",
        ms(b.top_delay_s),
        ms(b.torque_delay_s),
        ms(b.top_delay_s - b.torque_delay_s),
        r.model.inertia_kgm2,
        r.model.stiffness_nm_rad,
        r.model.damping_nm_s_rad,
        b.r_squared,
        zero.stiffness_nm_rad,
        zero.damping_nm_s_rad,
        zero.r_squared,
        if r.law_from_torque {
            "The law refitted by simulation did no better on the calibration window: the least-squares law of the torque is kept, \
             the falling law the torque channel shows,"
        } else {
            "The law refitted by simulation did better on the calibration window:"
        },
        f.kinetic_nm,
        f.static_nm - f.kinetic_nm,
        f.stribeck_speed_rad_s,
        f.shape_exponent,
        b.law_static_nm,
        b.law_at_max_nm,
        r.calibration_misfit,
        zero.calibration_misfit,
        overall(&r.heldout),
        r.heldout.iter().map(|m| format!("{m:.3}")).collect::<Vec<_>>().join(", ")
    );
    md.push_str(
        "**Side by side** (every step-1 candidate fitted on the calibration window alone; paired t of ln(M_it/M_top_delay) over \
         the held-out windows, the engine's statistic):\n\n| candidate | its held-out misfit | `top_delay`'s | gain of `top_delay` \
         over it | paired t | windows `top_delay` is better |\n|---|---|---|---|---|---|\n",
    );
    for (c, cmp, wins) in &r.rivals {
        let _ = writeln!(
            md,
            "| {} | {:.3} | {:.3} | {:.3} | {:.2} | {}/{} |",
            c.id(),
            cmp.before,
            cmp.after,
            cmp.gain,
            cmp.t,
            wins,
            r.heldout.len()
        );
    }
    let beaten = r.rivals.iter().filter(|(_, c, _)| c.t >= s.selection.rule.min_t && c.gain > 0.0).count();
    let _ = writeln!(
        md,
        "\n`top_delay` beats {} of the {} other step-1 candidates with a paired t of at least {} (the selection rule's).\n",
        beaten,
        r.rivals.len(),
        s.selection.rule.min_t
    );
    md.push_str(
        "Per held-out window, the targets held (of 7) before (`channel_delay`, step 1: the selection's choice before this \
         candidate) and after (`top_delay`, step 1), and what the latter still misses (error over tolerance):\n\n| window | before: \
         targets held | after: targets held | missed after |\n|---|---|---|---|\n",
    );
    md.push_str(&crate::drive::targets_before_after(s, &r.before, &r.features));
    let (rmin, rmax) =
        r.scan.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| (a.0.min(p.r_squared), a.1.max(p.r_squared)));
    let (kmin, kmax) = r
        .scan
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| (a.0.min(p.stiffness_nm_rad), a.1.max(p.stiffness_nm_rad)));
    let _ = writeln!(
        md,
        "**What the data resolve.** Teacher-forced, the bit's balance hardly sees the top's clock: over the scan its R² stays \
         within {rmin:.4}–{rmax:.4} while k trades {kmin:.2}–{kmax:.2} N m/rad and c {:+.4} to {:+.4} N m s/rad; only the free run \
         places τ_top (calibration misfit {:.3} at 0, {:.3} at {:+.0} ms). The record fixes the channels' clocks only relative to \
         one another: the top {:+.0} ms and the torque {:+.0} ms late on the bit speed is as well the bit-speed channel early on \
         both; which channel's clock is off, the data cannot say. What the shift brings into the free run is a stiffer, damped \
         shaft (k {:.2} N m/rad, c {:.3} N m s/rad against {:.2} and {:.4} at τ_top = 0): a damping on the twist rate that holds the \
         falling law's negative slope, which the shaft of the top read on time (c {:.4}) cannot.\n",
        r.scan.iter().map(|p| p.damping_nm_s_rad).fold(f64::INFINITY, f64::min),
        r.scan.iter().map(|p| p.damping_nm_s_rad).fold(f64::NEG_INFINITY, f64::max),
        zero.calibration_misfit,
        b.calibration_misfit,
        ms(b.top_delay_s),
        ms(b.top_delay_s),
        ms(b.torque_delay_s),
        b.stiffness_nm_rad,
        b.damping_nm_s_rad,
        zero.stiffness_nm_rad,
        zero.damping_nm_s_rad,
        zero.damping_nm_s_rad,
    );
    md
}

#[cfg(test)]
mod tests {
    use crate::data::RPM_TO_RAD_S;
    use crate::fit::tests::prepared;
    use crate::fit::{Structure, best_delay_s, derive, top_rad_s};

    /// A top speed read 20 ms late is read on the bit's clock: the equation of
    /// motion of a record simulated with the true top and refitted with the
    /// late channel read 20 ms later gives back J, k, c.
    #[test]
    fn a_late_top_channel_read_later_gives_back_the_shaft() {
        use rig_model::one_dof::{Coulomb, Drive, OneDofState, simulate};
        let (n, fs, late) = (12_000, 1000.0, 20);
        let top: Vec<f64> = (0..n).map(|i| 2.0 + (std::f64::consts::TAU * 0.5 * i as f64 / fs).sin()).collect();
        let shaft = crate::fit::tests::shaft();
        let law = Coulomb { static_nm: 2.5, kinetic_nm: 1.5 };
        let r = simulate(&shaft, &law, Drive::Speed(&top), None, OneDofState::default(), fs, n, 10).unwrap();
        let rpm = |x: &[f64]| x.iter().map(|v| v / RPM_TO_RAD_S).collect::<Vec<f64>>();
        // The channel is late: its sample i is the top's speed at i − 20.
        let channel: Vec<f64> = (0..n).map(|i| top[i.saturating_sub(late)]).collect();
        let d = prepared((0..n).map(|i| i as f64 / fs).collect(), rpm(&channel), rpm(&r.bit_rad_s), r.friction_nm);
        let cal = crate::fit::tests::window_4_8();
        let read = top_rad_s(&d, 4000..8000, 0.020);
        assert!(read.iter().zip(&top[4000..8000]).all(|(a, b)| (a - b).abs() < 1e-9));
        let on_clock = Structure { top_delay_s: 0.020, ..Structure::BASELINE };
        let (m, der) = derive(&d, &cal, 5.0, on_clock).unwrap();
        let (_, off) = derive(&d, &cal, 5.0, Structure::BASELINE).unwrap();
        assert!((m.stiffness_nm_rad - 4.0).abs() < 0.1 && (m.inertia_kgm2 - 0.01).abs() < 5e-4, "{m:?}");
        assert!(der.free.r_squared > off.free.r_squared, "{} {}", der.free.r_squared, off.free.r_squared);
        // The torque channel is on time: its least-squares delay stays 0 with the top on the bit's clock.
        assert_eq!(best_delay_s(&d, &cal, on_clock, 0.01), 0.0);
    }
}
