//! The selection's conclusion ([`Selection::conclude`]): the adequacy test of
//! the final model, the `unexplained` finding and its residual signature
//! (residual samples of both channels, binned against the best library
//! signal), the evidence sentences and the report's detail (μ against slip
//! speed, residual against rotor angle). Split from the selection itself:
//! it runs once, on the selection's result.

use super::features::measured_features;
use super::{Comparison, Cv, DriveCv, FrictionCv, Selection, combine, compare, noise_floor_parts, overall, params_of};
use crate::composite::{self, Composite, Phases};
use crate::effects::{NONE, Term, UNEXPLAINED, VocabularyEffect};
use crate::friction::SlipData;
use crate::prepare::RunSignals;
use crate::result::{Adequacy, CandidateScore, Detail, Diagnosis, Finding, MuBin, RunRow, SignatureEntry, round_sig};
use crate::signature::{self, Library, Samples};
use crate::{DiagnoseOptions, drive, lines};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Residual samples of the final model in both channels, for the signature.
fn residual_samples(cv: &Cv, fr: &FrictionCv, dr: &DriveCv, disc_radius_m: f64) -> (Samples, Samples) {
    let per_run: Vec<(Samples, Samples)> = cv
        .runs
        .par_iter()
        .enumerate()
        .map(|(r, s)| {
            let lib = Library::of(s, disc_radius_m);
            let mut mu = Samples::default();
            if let Some(m) = fr.models[s.fold].as_ref() {
                for (j, &k) in s.slip_idx.iter().enumerate().step_by(5) {
                    let mh = m.mu(s.time_s[k], s.rotor_angle_rad[k], s.rotor_speed_rad_s[k].abs(), fr.phases[r]);
                    if mh.abs() < 1e-9 {
                        continue;
                    }
                    mu.run.push(r);
                    mu.fold.push(s.fold);
                    mu.x.push(lib.row(k));
                    mu.y.push(s.mu_obs[j] / mh - 1.0);
                    mu.scale.push(mh);
                }
            }
            let mut v = Samples::default();
            if let Some(pi) = dr.pis[s.fold].as_ref() {
                let (vh, _, _) = drive::predict_voltage(pi, s);
                for k in (0..s.time_s.len()).step_by(10) {
                    v.run.push(r);
                    v.fold.push(s.fold);
                    v.x.push(lib.row(k));
                    v.y.push((s.voltage_v[k] - vh[k]) / cv.supply_v);
                    v.scale.push(1.0);
                }
            }
            (mu, v)
        })
        .collect();
    let mut mu = Samples::default();
    let mut v = Samples::default();
    for (a, b) in per_run {
        for (dst, src) in [(&mut mu, a), (&mut v, b)] {
            dst.run.extend(src.run);
            dst.fold.extend(src.fold);
            dst.x.extend(src.x);
            dst.y.extend(src.y);
            dst.scale.extend(src.scale);
        }
    }
    (mu, v)
}

/// Binned mean residual against the best signal, training folds and the held-out fold 0 apart.
fn signature_curve(s: &Samples, col: usize) -> Vec<(f64, f64, bool)> {
    if s.y.is_empty() {
        return vec![];
    }
    let lo = s.x.iter().map(|r| r[col]).fold(f64::INFINITY, f64::min);
    let hi = s.x.iter().map(|r| r[col]).fold(f64::NEG_INFINITY, f64::max);
    if hi <= lo {
        return vec![];
    }
    let nb = 24;
    let mut out = Vec::new();
    for held in [false, true] {
        let mut acc = vec![(0.0, 0usize); nb];
        for i in 0..s.y.len() {
            if (s.fold[i] == 0) != held {
                continue;
            }
            let b = (((s.x[i][col] - lo) / (hi - lo) * nb as f64) as usize).min(nb - 1);
            acc[b].0 += s.y[i];
            acc[b].1 += 1;
        }
        for (b, a) in acc.iter().enumerate() {
            if a.1 >= 10 {
                out.push((lo + (b as f64 + 0.5) * (hi - lo) / nb as f64, a.0 / a.1 as f64, held));
            }
        }
    }
    out
}

impl Selection<'_> {
    /// The diagnosis of this selection given the significant checks of the
    /// other run kinds (`channel_checks`: (run kind, text)): adequacy, the
    /// `unexplained` finding and its signature, the report's detail.
    pub fn conclude(
        &self,
        campaign: &str,
        disc_radius_m: f64,
        thesis_mu_dynamic: Option<f64>,
        channel_checks: &[(String, String)],
        opts: &DiagnoseOptions,
    ) -> Diagnosis {
        let Selection {
            registry,
            runs,
            supply_v,
            cv,
            fr_cache,
            dr_cache,
            current,
            base_ms,
            cur_ms,
            accepted,
            steps,
            first_step,
            full,
            limit_fit,
            pi_base,
            coulomb,
            d_all,
        } = self;
        let (registry, runs, supply_v, current) = (*registry, *runs, *supply_v, *current);
        let folds = cv.folds;
        let all: Vec<&RunSignals> = runs.iter().collect();
        let significant = |c: &Comparison| opts.selection.admits(c);

        // Adequacy: the final model against noise, and the other run kinds.
        let floor_parts: Vec<(Option<f64>, f64)> = runs.iter().map(|s| noise_floor_parts(s, supply_v)).collect();
        let floor_ms: Vec<f64> = floor_parts.iter().map(|(a, b)| combine(*a, *b)).collect();
        let floor_m = overall(&floor_ms);
        let final_m = overall(cur_ms);
        let ratio = final_m / floor_m;
        let fr_final = fr_cache.get(&current.friction).expect("evaluated").clone();
        let dr_final = dr_cache.get(&current.limit).expect("evaluated").clone();
        let ch_mu = {
            let e: Vec<f64> = fr_final.e_mu.iter().flatten().copied().collect();
            let f: Vec<f64> = floor_parts.iter().filter_map(|p| p.0).collect();
            overall(&e) / overall(&f)
        };
        let ch_v = overall(&dr_final.e_v) / overall(&floor_parts.iter().map(|p| p.1).collect::<Vec<_>>());
        let all_lines: Vec<lines::OrderLine> = runs
            .par_iter()
            .map(|s| {
                let mut v = lines::order_lines(s, true, opts.max_order);
                v.extend(lines::order_lines(s, false, opts.max_order));
                v
            })
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect();
        // Lines a fitted effect drives (an angle-locked friction of order n: order
        // n and its harmonics, in either speed) are explained, not left over.
        let explained_order = registry.iter().find_map(|e| e.explained_order(&full.model));
        let consistent: Vec<lines::ConsistentLine> = lines::consistent_lines(&all_lines, opts.line_ratio)
            .into_iter()
            .filter(|l| explained_order.is_none_or(|n| l.order % n != 0))
            .collect();
        let line_text: Vec<String> = consistent
            .iter()
            .map(|l| {
                format!(
                    "{} speed has an order-{} line (per {} revolution) in {}/{} runs, median {:.0}× the local floor",
                    l.channel, l.order, l.channel, l.runs_significant, l.runs_tested, l.median_ratio
                )
            })
            .collect();
        let adequate = ratio <= opts.adequacy_ratio && consistent.is_empty() && channel_checks.is_empty();
        let adequacy = Adequacy {
            residual_over_noise: round_sig(ratio, 3),
            threshold: opts.adequacy_ratio,
            order_lines: consistent.len(),
            channel_checks: channel_checks.iter().filter(|(k, _)| k != "free_run").count(),
            free_run_checks: channel_checks.iter().filter(|(k, _)| k == "free_run").count(),
            adequate,
        };

        let run_ids: Vec<String> = runs.iter().map(|s| s.id.clone()).collect();
        // Every fitted parameter of the final model, by the term that fitted it.
        let fitted: Vec<(Term, &str, f64, f64)> = full
            .params
            .iter()
            .map(|&(t, k, v, s)| (Term::Friction(t), k, v, s))
            .chain(limit_fit.map(|(pi, _, _, s)| (Term::DriveLimit, drive::LIMIT_PARAM, pi.limit_v, s)))
            .collect();
        let mut findings = Vec::new();
        for (e, c) in accepted {
            let mut params = BTreeMap::new();
            let mut se = BTreeMap::new();
            let mut ptext = Vec::new();
            for (k, v, s) in params_of(&fitted, *e) {
                params.insert(k.to_string(), round_sig(v, 4));
                se.insert(k.to_string(), round_sig(s, 2));
                ptext.push((k, v));
            }
            findings.push(Finding {
                effect: e.id().into(),
                params,
                params_stderr: se,
                evidence: evidence(e.0, &ptext, c),
                heldout_runs: run_ids.clone(),
                heldout_misfit_baseline: round_sig(c.before, 4),
                heldout_misfit_extended: round_sig(c.after, 4),
                relative_gain: round_sig(c.gain, 4),
                relative_gain_fold_sd: round_sig(c.gain_fold_sd, 2),
                criterion: Some(round_sig(-c.t, 4)),
                ..Default::default()
            });
        }

        // What is left: the signature of the final model's residual.
        let mut detail = Detail { folds, ..Default::default() };
        let mut verdict = accepted.first().map(|a| a.0.id().to_string()).unwrap_or_else(|| NONE.into());
        let mut ext_ms = cur_ms.clone();
        if !adequate {
            let (mu_s, v_s) = residual_samples(cv, &fr_final, &dr_final, disc_radius_m);
            let sig_mu = signature::channel_signature(&mu_s, "friction", folds, runs.len(), opts.signature_threshold);
            let sig_v = signature::channel_signature(&v_s, "drive", folds, runs.len(), opts.signature_threshold);
            // Best data-driven extension: each channel corrected by its sparse model, per run.
            ext_ms = (0..runs.len())
                .map(|r| {
                    let e_mu = fr_final.e_mu[r].map(|e| e * sig_mu.run_factor[r].max(0.0).sqrt());
                    combine(e_mu, dr_final.e_v[r] * sig_v.run_factor[r].max(0.0).sqrt())
                })
                .collect();
            let mut terms: Vec<signature::Term> =
                sig_mu.terms.iter().chain(sig_v.terms.iter()).filter(|t| t.heldout_gain > 0.0).cloned().collect();
            terms.sort_by(|a, b| b.heldout_gain.total_cmp(&a.heldout_gain).then(a.signal.cmp(b.signal)));
            if let Some(t0) = terms.first() {
                let (s, _) = if t0.channel == "friction" { (&mu_s, ()) } else { (&v_s, ()) };
                let col = signature::SIGNALS.iter().position(|x| *x == t0.signal).expect("library signal");
                detail.signature_curve = signature_curve(s, col);
            }
            detail.signature_gain = sig_mu.combined_gain.max(sig_v.combined_gain);
            let mut where_: Vec<String> = Vec::new();
            if ratio > opts.adequacy_ratio || !consistent.is_empty() {
                where_.push("operating_point".into());
            }
            for (kind, _) in channel_checks {
                if !where_.contains(kind) {
                    where_.push(kind.clone());
                }
            }
            let mut what = Vec::new();
            if ratio > opts.adequacy_ratio {
                what.push(format!(
                "the final model's cross-validated misfit is {:.1}× the noise floor (threshold {:.1}; friction channel \
                 {:.1}×, drive channel {:.1}×)",
                ratio, opts.adequacy_ratio, ch_mu, ch_v
            ));
            }
            what.extend(line_text.iter().take(2).cloned());
            what.extend(channel_checks.iter().take(3).map(|(k, t)| format!("{k}: {t}")));
            let signature_entries: Vec<SignatureEntry> = terms
            .iter()
            .take(4)
            .map(|t| SignatureEntry {
                signal: t.signal.into(),
                heldout_gain: round_sig(t.heldout_gain, 3),
                description: format!(
                    "{} residual changes by {:.3e} per unit of {} (±1 sd of the signal moves it by {:.3e}); a term in \
                     it removes {:.0} % of the held-out residual. Causes that leave this: {}.",
                    if t.channel == "friction" { "the relative friction-coefficient" } else { "the relative voltage" },
                    t.slope,
                    t.signal,
                    t.residual_sd,
                    100.0 * t.heldout_gain,
                    signature::causes(t.signal)
                ),
            })
            .collect();
            let explained = if findings.is_empty() {
                "No vocabulary effect earns its place".to_string()
            } else {
                format!(
                    "The vocabulary explains part of the mismatch ({})",
                    findings.iter().map(|f| f.effect.as_str()).collect::<Vec<_>>().join(", ")
                )
            };
            // A mismatch seen only in the free run, with the teacher-forced
            // channels within their noise: the residual signature describes
            // noise-level structure of those channels, not the motion's gap.
            let motion_only = ratio <= opts.adequacy_ratio
                && consistent.is_empty()
                && channel_checks.iter().all(|(k, _)| k == "free_run");
            let follows = match terms.first() {
                _ if motion_only => format!(
                    " The teacher-forced channels are within their noise ({ratio:.1}× the floor): the mismatch shows only \
                 in the motion, where the residual signature of those channels (listed, best {}) cannot see it.",
                    terms.first().map_or("none", |t| t.signal)
                ),
                Some(t) => format!(
                    " The leftover follows {} (held-out gain {:.0} %), pointing to {}.",
                    t.signal,
                    100.0 * t.heldout_gain,
                    signature::causes(t.signal)
                ),
                None => " No signal of the library explains the leftover on held-out runs.".into(),
            };
            findings.push(Finding {
                effect: UNEXPLAINED.into(),
                evidence: format!("{explained}, but {}.{follows}", what.join("; ")),
                residual_over_noise: Some(round_sig(ratio, 3)),
                where_,
                signature: signature_entries,
                heldout_runs: run_ids.clone(),
                heldout_misfit_baseline: round_sig(final_m, 4),
                heldout_misfit_extended: round_sig(overall(&ext_ms), 4),
                relative_gain: round_sig(1.0 - overall(&ext_ms) / final_m, 4),
                relative_gain_fold_sd: round_sig(compare(cur_ms, &ext_ms, runs, folds).gain_fold_sd, 2),
                criterion: None,
                ..Default::default()
            });
            detail.signature = terms;
            verdict = UNEXPLAINED.into();
        }

        let base_m = overall(base_ms);
        let mut candidates = Vec::new();
        for (e, c, _) in first_step {
            candidates.push(CandidateScore {
                effect: e.id().into(),
                heldout_misfit_extended: round_sig(c.after, 4),
                relative_gain: round_sig(c.gain, 4),
                relative_gain_fold_sd: round_sig(c.gain_fold_sd, 2),
                criterion: round_sig(-c.t, 4),
            });
            detail.scores.push((e.id().into(), -c.t, c.after, c.gain, significant(c), String::new()));
        }

        // Detail for the report.
        detail.steps = steps.clone();
        detail.heldout_misfit_baseline = base_m;
        detail.heldout_misfit_noise_floor = floor_m;
        detail.lines = line_text;
        detail.channel_over_noise = (ch_mu, ch_v);
        detail.baseline_text = format!(
            "μk = {:.4} (Coulomb, all slip samples); voltage predictor kp = {:.3} V·s/rad, ki = {:.3} V/rad, limit {:.1} V \
         (supply). These gains are the best teacher-forced predictor of the recorded voltage from the measured, \
         differentiated motor speed: speed noise biases kp low (errors in variables), so they are not the drive's \
         physical gains, which estimation.md gives with that bias corrected",
            coulomb.model.mu_k, pi_base.kp_v_s_rad, pi_base.ki_v_rad, supply_v
        );
        if let Some(c) = full.scan.first().map(|_| &full.scan) {
            let worst = c.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
            detail.freq_scan = c.iter().map(|&(f, r)| (f, 1.0 - r / worst)).collect();
        } else if let Some(scan) = composite::coulomb_time_scan(d_all, &cv.freqs) {
            // The scan of the set {normal_force_modulation} alone, without its
            // fit at the best frequency (only the scan is drawn).
            let worst = scan.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
            detail.freq_scan = scan.iter().map(|&(f, r)| (f, 1.0 - r / worst)).collect();
        }
        for (r, s) in runs.iter().enumerate() {
            detail.runs.push(RunRow {
                id: s.id.clone(),
                fold: s.fold,
                normal_force_n: s.normal_force_n,
                motor_rpm_setpoint: rig_types::units::rad_s_to_rpm(s.setpoint_rad_s),
                slip_samples: s.slip_idx.len(),
                misfit_baseline: base_ms[r],
                misfit_extended: cur_ms[r],
                misfit_noise_floor: floor_ms[r],
                force_noise_n: s.force_noise_n,
                voltage_noise_v: s.voltage_noise_v,
                measured: measured_features(s, opts.slip_speed_rad_s, &opts.classify),
                simulated: None,
                extended: None,
                phases_rad: full.phases.get(r).copied().unwrap_or((0.0, 0.0)),
            });
        }
        detail.mu_vs_speed = mu_vs_speed(d_all, &coulomb.model, &full.model, &full.phases);
        detail.residual_vs_angle = residual_vs_angle(&all, coulomb.model.mu_k);
        if let Some(mu_dyn) = thesis_mu_dynamic {
            let thesis = Composite::coulomb(mu_dyn);
            let tm: Vec<f64> = runs
                .iter()
                .enumerate()
                .map(|(r, s)| {
                    let dr = SlipData::from_runs(&[s]);
                    combine(composite::relative_mu_error(&thesis, &dr, (0.0, 0.0)), dr_cache[&false].e_v[r])
                })
                .collect();
            detail.rungs.push((
                "thesis model as published".into(),
                overall(&tm),
                format!("Table 4.7 μ_dyn = {mu_dyn} in slip, drive saturating at the supply"),
            ));
        }
        detail.rungs.push((
            "rig model recalibrated".into(),
            base_m,
            format!("μk = {:.4} fitted on the campaign's slip samples", coulomb.model.mu_k),
        ));
        let mut names = Vec::new();
        for (e, c) in accepted {
            names.push(e.id());
            detail.rungs.push(("extended model".into(), c.after, format!("+ {}", names.join(" + "))));
        }
        if verdict == UNEXPLAINED {
            detail.rungs.push((
                "data-driven extension".into(),
                overall(&ext_ms),
                format!(
                    "+ sparse regression of the residual on {}",
                    detail.signature.iter().take(2).map(|t| t.signal).collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        Diagnosis {
            campaign: campaign.into(),
            verdict,
            findings,
            candidates,
            adequacy,
            structure: Default::default(),
            parameters_at_bounds: Vec::new(),
            brake_open_runs: cv.brake_open_runs().iter().map(|s| s.id.clone()).collect(),
            drive_channel: drive_channel(cv, dr_cache, current.limit),
            detail,
        }
    }
}

/// The drive channel's runs and each brake-open run's held-out voltage
/// error under the baseline drive and the final model's (`limit`: with its
/// own limit), each from the fold fit that did not read it; `None` when
/// every operating point has the brake applied.
fn drive_channel(cv: &Cv, dr_cache: &BTreeMap<bool, DriveCv>, limit: bool) -> Option<crate::result::DriveChannel> {
    let open = cv.brake_open_runs();
    if open.is_empty() {
        return None;
    }
    let e_v = |limit: bool, s: &RunSignals| {
        let pi = dr_cache.get(&limit).and_then(|d| d.pis.get(s.fold).copied().flatten());
        pi.map_or(f64::INFINITY, |pi| drive::relative_voltage_error(&pi, s, cv.supply_v))
    };
    let brake_open_heldout = open
        .iter()
        .map(|s| crate::result::DriveRunError {
            run: s.id.clone(),
            relative_voltage_error_baseline: round_sig(e_v(false, s), 4),
            relative_voltage_error_final: round_sig(e_v(limit, s), 4),
            noise_floor: round_sig(s.voltage_noise_v / cv.supply_v, 4),
        })
        .collect();
    Some(crate::result::DriveChannel { runs: cv.drive_runs.len(), brake_open: open.len(), brake_open_heldout })
}

/// The evidence sentence: what the effect does in numbers (its own clause,
/// [`VocabularyEffect::evidence`]) and the criterion's numbers.
fn evidence(effect: &dyn VocabularyEffect, params: &[(&str, f64)], c: &Comparison) -> String {
    let p = |k: &str| params.iter().find(|x| x.0 == k).map(|x| x.1).unwrap_or(f64::NAN);
    let what = effect.evidence(&p);
    format!(
        "{what}; cross-validated misfit {:.4} → {:.4} (gain {:.1} % ± {:.1} % across folds, paired t = {:.1}).",
        c.before,
        c.after,
        100.0 * c.gain,
        100.0 * c.gain_fold_sd,
        c.t
    )
}

fn mu_vs_speed(d: &SlipData, base: &Composite, ext: &Composite, phases: &[Phases]) -> Vec<MuBin> {
    let wmax = d.omega.iter().copied().fold(0.0_f64, f64::max);
    if wmax <= 0.0 {
        return vec![];
    }
    let nb = 30;
    let mut acc = vec![(0.0, 0.0, 0.0, 0usize); nb];
    // Per bin and run: (Σμ, n), for the run-level spread of the bin mean.
    let mut per_run = vec![vec![(0.0, 0usize); d.n_runs]; nb];
    for i in 0..d.len() {
        let b = ((d.omega[i] / wmax * nb as f64) as usize).min(nb - 1);
        let ph = phases.get(d.run[i]).copied().unwrap_or((0.0, 0.0));
        acc[b].0 += d.mu[i];
        acc[b].1 += base.mu(d.t[i], d.phi[i], d.omega[i], (0.0, 0.0));
        acc[b].2 += ext.mu(d.t[i], d.phi[i], d.omega[i], ph);
        acc[b].3 += 1;
        per_run[b][d.run[i]].0 += d.mu[i];
        per_run[b][d.run[i]].1 += 1;
    }
    acc.iter()
        .zip(&per_run)
        .enumerate()
        .filter(|(_, (a, _))| a.3 >= 20)
        .map(|(b, (a, runs))| {
            // 95 % half-width with the run as the independent unit (samples of
            // one run are correlated): Student t over the runs' own bin means.
            let means: Vec<f64> = runs.iter().filter(|r| r.1 >= 5).map(|r| r.0 / r.1 as f64).collect();
            let k = means.len();
            let half = if k >= 2 {
                let m = means.iter().sum::<f64>() / k as f64;
                let sd = (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1) as f64).sqrt();
                rig_calibrate::stats::student_t_quantile(0.975, (k - 1) as f64)
                    .map_or(f64::NAN, |t| t * sd / (k as f64).sqrt())
            } else {
                f64::NAN
            };
            MuBin {
                speed_rad_s: (b as f64 + 0.5) * wmax / nb as f64,
                measured: a.0 / a.3 as f64,
                baseline: a.1 / a.3 as f64,
                extended: a.2 / a.3 as f64,
                measured_half_width_95: half,
            }
        })
        .collect()
}

/// μ_obs − μk of the run with most slip in 72 bins of φ1 mod 2π, with the
/// interval the data support: the independent unit is one pass of the disc
/// through a bin (samples inside one pass are correlated), so each bin gives
/// the mean over revolutions of the per-revolution mean and ±1.96 standard
/// errors over those revolutions; bins seen on fewer than 3 revolutions are
/// left out. Rows: (bin centre rad, mean, lower, upper, revolutions).
fn residual_vs_angle(runs: &[&RunSignals], mu_k: f64) -> Vec<(f64, f64, f64, f64, usize)> {
    let Some(s) = runs.iter().max_by_key(|s| s.slip_idx.len()) else { return vec![] };
    let nb = 72;
    // (revolution, bin) -> (sum, count), in a fixed order.
    let mut per_pass: std::collections::BTreeMap<(i64, usize), (f64, usize)> = std::collections::BTreeMap::new();
    for (j, &k) in s.slip_idx.iter().enumerate() {
        let phi = s.rotor_angle_rad[k];
        let rev = (phi / (2.0 * PI)).floor() as i64;
        let a = phi.rem_euclid(2.0 * PI);
        let b = ((a / (2.0 * PI) * nb as f64) as usize).min(nb - 1);
        let e = per_pass.entry((rev, b)).or_insert((0.0, 0));
        e.0 += s.mu_obs[j] - mu_k;
        e.1 += 1;
    }
    let mut bins: Vec<Vec<f64>> = vec![Vec::new(); nb];
    for ((_, b), (sum, n)) in per_pass {
        bins[b].push(sum / n as f64);
    }
    bins.iter()
        .enumerate()
        .filter(|(_, v)| v.len() >= 3)
        .map(|(b, v)| {
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let half = 1.96 * sd / n.sqrt();
            ((b as f64 + 0.5) * 2.0 * PI / nb as f64, mean, mean - half, mean + half, v.len())
        })
        .collect()
}
