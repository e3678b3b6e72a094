//! The structure selection's study on the one engine: a structure fitted
//! per training set, its four views (balance, free run, events, ring) and
//! the admission rule read from them ([`FourViews`]).

use super::*;

/// A structure fitted on one training set: its [`REGISTRY`] index and fit.
#[derive(Clone)]
pub(super) struct Structured {
    pub(super) k: usize,
    pub(super) fit: Fitted,
}

/// The structure selection as a study of the one engine
/// ([`rig_types::select::select_on_views`]): the units are the diagnosis'
/// runs (`runs` order), scored in the four views.
pub(super) struct Study<'a> {
    pub(super) c: &'a Campaign,
    pub(super) data: &'a StructureData,
    pub(super) ext: &'a RigParams,
    /// The model each candidate extends ([`REGISTRY`] order): the extended
    /// model, with the motor side re-estimated under the candidate's damping
    /// for one that moves it ([`MotorSide`]).
    pub(super) models: Vec<RigParams>,
    pub(super) runs: &'a [crate::RunRow],
    /// The extended model's free-run misfit of each run (`None`: no misfit).
    pub(super) ext_free_run: Vec<Option<f64>>,
    pub(super) floor_rad_s: f64,
    pub(super) s: &'a FreeRunSettings,
    /// The records' side of every free run, measured once under `s` (the
    /// diagnosis' [`MeasuredRuns`]): a candidate's held-out free runs only simulate.
    pub(super) measured: &'a MeasuredRuns,
    pub(super) min_t: f64,
}

impl Study<'_> {
    /// Whether run `id` is one of the units `train`.
    pub(super) fn include<'b>(&'b self, train: &'b [usize]) -> impl Fn(&str) -> bool + 'b {
        move |id: &str| train.iter().any(|&u| self.runs[u].id == id)
    }

    /// The candidate's fit to every run, its fold-jackknife standard errors
    /// (`fits`: one per fold), the terms the records do not support and the
    /// parameters pinned at their bounds (module docs: admissible when both
    /// are empty); `None` when it does not fit every run.
    pub(super) fn assess(&self, k: usize, fits: &[Structured]) -> Option<Assessment> {
        let cand = REGISTRY[k];
        let full = cand.fit(self.ext, self.data, &|_| true)?;
        let fits: Vec<Option<Fitted>> = fits.iter().map(|f| Some(f.fit.clone())).collect();
        // Each term must be supported by the balance itself: its fit to every
        // run at least `min_t` fold-jackknife standard errors above its bound.
        let se = jackknife_se(&fits, cand.params().len());
        // The terms whose departure from the baseline the records must
        // support ([`StructureCandidate::support`]), with their own jackknife.
        let support_fits: Vec<Option<Fitted>> = fits
            .iter()
            .map(|f| f.as_ref().map(|f| Fitted { values: cand.support(f).iter().map(|x| x.1).collect(), ..f.clone() }))
            .collect();
        let support = cand.support(&full);
        let support_se = jackknife_se(&support_fits, support.len());
        let weak: Vec<String> = support
            .iter()
            .zip(&support_se)
            .filter(|((_, v, p), se)| {
                matches!((*v - p.lower).partial_cmp(&(self.min_t * **se)), Some(std::cmp::Ordering::Less) | None)
            })
            .map(|((name, v, p), se)| format!("{name} = {v:.2e} ± {se:.1e} {}", p.unit))
            .collect();
        let pinned = cand.pinned(&full);
        Some(Assessment { full, se, weak, pinned })
    }
}

/// [`Study::assess`]'s answer.
pub(super) struct Assessment {
    pub(super) full: Fitted,
    pub(super) se: Vec<f64>,
    pub(super) weak: Vec<String>,
    pub(super) pinned: Vec<(&'static ParamSpec, f64)>,
}

impl rig_types::select::ViewStudy<Structured> for Study<'_> {
    fn views(&self) -> usize {
        4
    }
    fn score_view(&self, m: &Structured, view: usize, unit: usize) -> Option<f64> {
        let id = self.runs[unit].id.as_str();
        let only = |r: &str| r == id;
        match view {
            BALANCE => self.data.of_fit(&m.fit).run_rms(&m.fit.balance, only).first().map(|x| x.1),
            EVENTS => self.data.of_fit(&m.fit).run_event_rms(&m.fit.balance, only).first().map(|x| x.1),
            // As recorded unless the candidate models the force sensor (the baseline's too).
            RING => REGISTRY[m.k].ring_rms(self.data, &m.fit, &only).first().map(|x| x.1),
            // The baseline and a structure that does not move the model
            // (a sensor's) have the extended model's free run.
            _ if m.k == 0 || !REGISTRY[m.k].moves() => self.ext_free_run[unit],
            _ => {
                // Compared only where the extended model's free run has a misfit.
                self.ext_free_run[unit]?;
                let p = with_run_phases(&REGISTRY[m.k].apply(&self.models[m.k], &m.fit), self.runs[unit].phases_rad);
                free_run_misfit_measured(self.c, self.s, self.measured, id, &p, self.floor_rad_s)
            }
        }
    }
}

/// A structural candidate as the engine's candidate: its [`REGISTRY`] index.
pub(super) struct Cand(pub(super) usize);

impl rig_types::select::Candidate<Study<'_>, Structured> for Cand {
    fn id(&self) -> &str {
        REGISTRY[self.0].id()
    }
    fn fit(&self, st: &Study<'_>, _: &Structured, train: &[usize]) -> Result<Structured, String> {
        let fit = REGISTRY[self.0].fit(st.ext, st.data, &st.include(train));
        fit.map(|fit| Structured { k: self.0, fit }).ok_or_else(|| format!("`{}` does not fit", self.id()))
    }
    fn inadmissible(&self, st: &Study<'_>, _: &[Structured], fitted: &[Structured]) -> Option<String> {
        match st.assess(self.0, fitted) {
            None => Some("no fit to every run".into()),
            Some(a) if !a.pinned.is_empty() => Some("a parameter below its bound".into()),
            Some(a) if !a.weak.is_empty() => Some(format!("not supported by the balance: {}", a.weak.join(", "))),
            Some(_) => None,
        }
    }
}

/// The structure's criterion on its four views (module docs), the
/// engine's [`rig_types::select::ViewRule`].
pub(super) struct FourViews<'a> {
    pub(super) rule: &'a rig_types::contract::SelectionRule,
    /// Per engine candidate (the [`REGISTRY`] from its second entry on):
    /// its fit to every run sits at its grid's edge ([`GridEdge`]).
    pub(super) at_edge: Vec<bool>,
}

impl rig_types::select::ViewRule for FourViews<'_> {
    fn standing(&self, k: usize, c: &[Comparison]) -> Option<rig_types::select::Standing> {
        let (balance, free_run, events, ring) = (&c[BALANCE], &c[FREE_RUN], &c[EVENTS], &c[RING]);
        let passes = |x: &Comparison| self.rule.admits(x);
        // The free run refutes a candidate it finds significantly worse: a
        // negative gain with a paired t at or below −min_t; so does the held-out
        // balance (below). Either sign alone is not evidence: in the full battery's
        // `structural-velocity_weakening_friction+damping_rotor_absolute-0` the
        // true structure (drag and shaft damping, fitted C 2.20e-3 and C_r
        // 3.32e-3 N·m·s/rad; balance gain 38.3 %, t 6.73) moves the free-run misfit
        // by +0.9 % with t = −2.60 (most runs a little worse, a few better), and
        // was refused under the former rule (gain < 0 or t ≤ −min_t), leaving a
        // 8 ms encoder delay, the drag's alias in the balance, to be named.
        let worse = |x: &Comparison| x.gain < 0.0 && x.t <= -self.rule.min_t;
        // The held-out rotor balance refutes a candidate by the same rule,
        // whatever the free run gains: a drag that lowers
        // the free-run misfit while the balance on held-out runs rises (t ≤ −min_t)
        // compensates something else (a right velocity-weakening model, seed 9322
        // of the right-model calibration: balance −62 %, t = −4.1; free run +17 %).
        // A candidate admitted on the event-locked rows alone needs the held-out
        // steady windows to move its way too (balance gain > 0 and t > 0): a
        // right sensor model leaves them as they were or better, a fit to the
        // training runs' noise loses there. Calibration null seed 9117
        // (stick-slipping, 8 of 12 runs): a 2 ms force delay gained 9.1 % at
        // the transitions (t 2.24) and −0.1 % on the balance (t −1.15); every
        // structural winner of the full battery's cases gains ≥ 0.6 % there
        // (t ≥ 1.70). t > 0 alone is a coin toss for a candidate that does
        // nothing on the steady windows, and the full battery (sixth session)
        // found two such: strong normal-force modulations
        // (`ladder-normal_force_modulation-1-11`: an encoder coupling at the
        // grid's 12 Hz, ζ 0.40, events +23.1 % t 4.91, balance +0.0 % t 0.05;
        // `-1-7`: a 2 ms encoder delay, events +24.8 % t 2.04, balance +1.1 %
        // t 0.84). The corroboration asks t ≥ min_t/2 (one-sided p ≈ 0.16 on
        // its own, an independent second test of the event-locked one).
        let corroborated = |x: &Comparison| x.gain > 0.0 && x.t >= self.rule.min_t / 2.0;
        // Admitted by the balance (or the event-locked rows it corroborates),
        // never by the free run alone: every candidate is a term of the rotor
        // balance with the measured r·F, where a torque on the rotor shows
        // against a friction the record carries whatever the model's law.
        // A friction the vocabulary step left out (a weak velocity weakening,
        // a viscous brake friction: torques that grow with Ω1 in slip like a
        // drag) is in r·F, so the balance has nothing for a drag to take,
        // while the free run, simulated with the model's law, lacks it: a
        // refitted damping then compensates it there. The last full battery's
        // four spurious `damping_rotor_absolute` (`ladder-velocity_weakening_friction-5-2`,
        // `-5-18`, `ladder-angle_periodic_friction-5-2`,
        // `compound-normal_force_modulation+viscous_brake_friction-0`) were
        // `twist_rate_and_rotor` admitted on the free run alone (gains 5.0–11.9 %,
        // t 3.37–5.06) with C_r 4e-6–2e-5 N·m·s/rad and a balance gain of 0.0 %
        // (t 0.16–1.04): the free-run gain was the twist-rate C refitted
        // through the balance (1–9 % below the estimation's), not the drag.
        // The force's ring after the break-aways (sensor_dynamics) admits on
        // its own: only a sensor that rings can gain there (a delay is a
        // shift, which the ring's fit absorbs); a candidate it finds
        // significantly worse is refuted like the other views'.
        // A fit at its grid's edge (module docs, "A fit at its grid's edge")
        // is not admitted by the steady balance: there the grid's largest
        // lag is the catch-all of any slow error of the balance; only the
        // views where a sensor's or a delay's footprint is its own (the
        // ring, the transitions) can admit it.
        let by_balance = passes(balance) && !self.at_edge.get(k).copied().unwrap_or(false);
        let admitted = !worse(free_run)
            && !worse(balance)
            && !worse(events)
            && !worse(ring)
            && (by_balance || passes(ring) || (passes(events) && corroborated(balance)));
        // A candidate that moves the model wins over one that does not only when
        // the motion supports it (its free-run comparison passes the criterion):
        // a drag and a late rotor encoder both read as C_r ≈ K·delay in the
        // balance, and a drag whose free run neither gains nor loses
        // significantly is not evidence against the delay (full battery
        // `structural-channel_delay-1`: the encoder 10 ms late, the delay fitted
        // at 10.0 ms with balance gain 22.6 % (t 5.99), the drag 20.5 % (t 5.25)
        // with free run +7.8 %, t = −0.18, chosen before this rule). Then one
        // that passes on the balance, by the larger held-out
        // balance gain; then, among candidates admitted on the event-locked rows
        // alone, the larger event-locked gain (the statistic they were admitted
        // on). A force delay and a ringing force sensor both reach the 0.1 s
        // balance windows as a lag (docs/findings.md): their run-level balance
        // gains, a few percent each, said nothing between them, and the delay
        // was named beside a velocity weakening with a ringing sensor
        // (`structural-velocity_weakening_friction+force_sensor_dynamics-0`).
        // One that passes on the ring ranks next within each of those: where
        // the force rings, the lag a force delay and a ringing sensor share
        // in the balance is the sensor's.
        // `k` counts the engine's candidates, the REGISTRY from its second entry on.
        let moves_free = REGISTRY[k + 1].moves() && passes(free_run);
        let on_balance = by_balance || moves_free;
        let tier = 4 * u32::from(moves_free) + 2 * u32::from(passes(ring)) + u32::from(on_balance);
        admitted.then_some(rig_types::select::Standing { tier, by_view: if on_balance { BALANCE } else { EVENTS } })
    }
}
