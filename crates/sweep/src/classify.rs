//! The regime classifier: one rotor-speed window in, severity and regime out.
//! The same function classifies simulated sweeps and measured recordings, so
//! its thresholds carry noise floors sized for the encoder differentiator.
//!
//! Procedure (every threshold is a field of [`ClassifyOptions`]):
//! 1. **Severity** from the window's min, max and mean of Ω1, in both
//!    conventions: (max − min)/(2·mean) and (max − min)/mean.
//! 2. **Equilibrium** when max − min ≤ max(`equilibrium_floor_rad_s`,
//!    `equilibrium_rel` · |mean|): steady sliding with at most noise on it.
//!    A window whose second half swings less than `decay_ratio` of its first
//!    half is a transient decaying towards sliding: also equilibrium (`decay`).
//! 3. **Stick** when min ≤ max(`stick_floor_rad_s`, `stick_rel` · |mean|);
//!    [`Regime::stick_slip`] is the workspace's one definition of stick-slip
//!    (the sweeps' tables and the simulation stage's misfit table use it).
//! 4. **Poincaré section**: upward crossings of Ω1 through its window mean,
//!    with a hysteresis band of ± `hysteresis_rel` · (max − min) so that noise
//!    does not count as crossings. One cycle = between two consecutive upward
//!    crossings; its value is the peak Ω1 inside it (a peak map). The brief's
//!    suggestion, Ω1 at upward crossings of a twist level, is not used: in
//!    stick-slip the twist rises *while the rotor is stuck*, so that section
//!    lands in the stick phase where Ω1 = 0 on every cycle and cannot tell
//!    period-1 from chaos. The cycle peaks are sorted and split into clusters
//!    at gaps larger than max(`cluster_abs_rad_s`, `cluster_rel` · (max − min)).
//!    With k clusters each no wider than that same tolerance (k ≤ `max_period`), at least `min_cycles_per_period`·k
//!    cycles and a label sequence that repeats with period k, the motion is
//!    **period-k**.
//! 5. Otherwise the **spectrum** decides (`rig_spectra::line_analysis` of the
//!    Hann-windowed, mean-removed Ω1 between `min_freq_hz` and `max_freq_hz`):
//!    **quasi-periodic** is rig-spectra's one definition
//!    (`SignalLines::quasi_periodic`: an incommensurate second base f2 in a
//!    discrete spectrum — every line explained, none unrelated, and the lines
//!    carrying at least `min_line_power_fraction` of the variance);
//!    no f2 and no unrelated line means the section was blurred by noise but
//!    the motion is periodic: **period-k** with k = round(f_cycle / f0),
//!    f_cycle the section's crossing rate; anything else — unrelated lines,
//!    or lines carrying less than `min_line_power_fraction` of the variance
//!    (a broadband floor) — is **chaotic**.

use rig_spectra::{LineAnalysisOptions, line_analysis};
use serde::{Deserialize, Serialize};

/// Thresholds of the classifier (see the module docs for where each is used).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClassifyOptions {
    /// Peak-to-peak below which a window is an equilibrium, rad/s. 0.5 rad/s is
    /// about three ticks of the differentiator's resolution (2π/1000 rad over 40 ms).
    pub equilibrium_floor_rad_s: f64,
    /// ... or below this fraction of the mean speed.
    pub equilibrium_rel: f64,
    /// A window whose second half has a peak-to-peak below this fraction of
    /// the first half's is a decaying transient: equilibrium (`decay`). 0.6
    /// sits between a free decay over half a 20 s window at ξ = 0.03
    /// (e^{-2π·0.03·5} ≈ 0.39) and a stationary oscillation (≈ 1).
    pub decay_ratio: f64,
    /// Min speed at or below which the rotor counts as stuck, rad/s.
    pub stick_floor_rad_s: f64,
    pub stick_rel: f64,
    /// Section hysteresis as a fraction of max − min.
    pub hysteresis_rel: f64,
    /// Cluster gap, absolute (rad/s) and as a fraction of max − min.
    pub cluster_abs_rad_s: f64,
    pub cluster_rel: f64,
    /// Largest k called period-k from the section.
    pub max_period: usize,
    /// Cycles needed per period to trust a period-k label.
    pub min_cycles_per_period: usize,
    /// Band of the spectral test, Hz.
    pub min_freq_hz: f64,
    pub max_freq_hz: f64,
    /// Line tolerance in bins for the line analysis. 0.5 bin: a 20 s window has
    /// 0.05 Hz bins, and the library's 1.5 bins would call f2 = √2·f0 "3/2·f0"
    /// (a 0.04 Hz miss); Gaussian interpolation is good to a few hundredths of
    /// a bin on clean lines (rig-spectra tests).
    pub tolerance_bins: f64,
    /// The spectral lines must carry at least this fraction of the window's
    /// variance (Σ A²/2 over var): a broadband (chaotic) spectrum with a few
    /// bumps standing out is not "periodic" or "quasi-periodic".
    pub min_line_power_fraction: f64,
}

impl Default for ClassifyOptions {
    fn default() -> Self {
        ClassifyOptions {
            equilibrium_floor_rad_s: 0.5,
            equilibrium_rel: 0.1,
            decay_ratio: 0.6,
            stick_floor_rad_s: 0.3,
            stick_rel: 0.1,
            hysteresis_rel: 0.1,
            cluster_abs_rad_s: 0.3,
            cluster_rel: 0.05,
            max_period: 4,
            min_cycles_per_period: 3,
            min_freq_hz: 0.1,
            max_freq_hz: 10.0,
            tolerance_bins: 0.5,
            min_line_power_fraction: 0.5,
        }
    }
}

impl ClassifyOptions {
    /// The spectral test's band and line tolerance for `rig_spectra::line_analysis`:
    /// 0.1 Hz keeps the drift of a 20 s window (2 bins) out, 10 Hz is the
    /// stick-slip harmonics' range that the encoder differentiator passes
    /// (pipeline.toml `sweeps`); the tolerance is argued at `tolerance_bins`.
    pub fn line_options(&self) -> LineAnalysisOptions {
        LineAnalysisOptions {
            min_freq_hz: self.min_freq_hz,
            max_freq_hz: self.max_freq_hz,
            tolerance_bins: self.tolerance_bins,
        }
    }
}

/// The regime of one window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "regime", rename_all = "snake_case")]
pub enum Regime {
    /// Steady sliding (or noise only).
    Equilibrium,
    /// Period-k oscillation; `stick` when the rotor stops in it (stick-slip).
    Periodic {
        period: u32,
        stick: bool,
    },
    QuasiPeriodic {
        stick: bool,
    },
    Chaotic {
        stick: bool,
    },
}

impl Regime {
    /// Short label used in tables: `equilibrium`, `stick-slip P1`,
    /// `oscillation P2`, `quasi-periodic stick-slip`, `chaotic`, ...
    pub fn label(&self) -> String {
        let prefix = |stick: bool| if stick { " stick-slip" } else { "" };
        match *self {
            Regime::Equilibrium => "equilibrium".into(),
            Regime::Periodic { period, stick: true } => format!("stick-slip P{period}"),
            Regime::Periodic { period, stick: false } => format!("oscillation P{period}"),
            Regime::QuasiPeriodic { stick } => format!("quasi-periodic{}", prefix(stick)),
            Regime::Chaotic { stick } => format!("chaotic{}", prefix(stick)),
        }
    }

    /// Stick-slip, the one definition: a vibrating regime in which the rotor
    /// stops (its window's min speed reaches max(`stick_floor_rad_s`,
    /// `stick_rel` · |mean|), step 3 of the module docs). A window that
    /// decays towards sliding is an equilibrium, so it does not stick-slip
    /// even if the rotor stopped early in it.
    pub fn stick_slip(&self) -> bool {
        matches!(
            self,
            Regime::Periodic { stick: true, .. }
                | Regime::QuasiPeriodic { stick: true }
                | Regime::Chaotic { stick: true }
        )
    }

    /// True for every regime but equilibrium (the chapter's "vibrating").
    pub fn vibrating(&self) -> bool {
        !matches!(self, Regime::Equilibrium)
    }

    /// Integer code for heat maps: 0 equilibrium, k periodic-k, 8 quasi-periodic, 9 chaotic.
    pub fn code(&self) -> u32 {
        match *self {
            Regime::Equilibrium => 0,
            Regime::Periodic { period, .. } => period.min(7),
            Regime::QuasiPeriodic { .. } => 8,
            Regime::Chaotic { .. } => 9,
        }
    }
}

/// What the classifier found in one window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    pub min_rad_s: f64,
    pub max_rad_s: f64,
    pub mean_rad_s: f64,
    /// (max − min) / (2 · mean).
    pub severity_half: f64,
    /// (max − min) / mean.
    pub severity_full: f64,
    pub regime: Regime,
    /// Full cycles in the Poincaré section.
    pub cycles: usize,
    /// Distinct clusters of cycle peaks (0 at equilibrium).
    pub clusters: usize,
    /// How the regime was decided: `range`, `decay`, `section` or `spectrum`.
    pub decided_by: String,
}

/// Classifies a window of rotor speed sampled at `fs_hz`.
pub fn classify(speed_rad_s: &[f64], fs_hz: f64, o: &ClassifyOptions) -> Classification {
    let n = speed_rad_s.len().max(1) as f64;
    let min = speed_rad_s.iter().copied().fold(f64::INFINITY, f64::min);
    let max = speed_rad_s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mean = speed_rad_s.iter().sum::<f64>() / n;
    let range = max - min;
    let mut out = Classification {
        min_rad_s: min,
        max_rad_s: max,
        mean_rad_s: mean,
        severity_half: range / (2.0 * mean),
        severity_full: range / mean,
        regime: Regime::Equilibrium,
        cycles: 0,
        clusters: 0,
        decided_by: "range".into(),
    };
    if speed_rad_s.len() < 4 || range <= o.equilibrium_floor_rad_s.max(o.equilibrium_rel * mean.abs()) {
        return out;
    }
    // A transient still ringing down towards steady sliding (ξ of a few per
    // cent leaves ~40 % of a step's ringing after 5 periods) is not an attractor.
    let half = speed_rad_s.len() / 2;
    let pp = |x: &[f64]| {
        x.iter().copied().fold(f64::NEG_INFINITY, f64::max) - x.iter().copied().fold(f64::INFINITY, f64::min)
    };
    if pp(&speed_rad_s[half..]) < o.decay_ratio * pp(&speed_rad_s[..half]) {
        out.decided_by = "decay".into();
        return out;
    }
    let stick = min <= o.stick_floor_rad_s.max(o.stick_rel * mean.abs());
    let peaks = cycle_peaks(speed_rad_s, mean, o.hysteresis_rel * range);
    out.cycles = peaks.len();
    let tol = o.cluster_abs_rad_s.max(o.cluster_rel * range);
    let (labels, k, width) = clusters(&peaks, tol);
    out.clusters = k;
    let tight = width <= tol;
    if tight && k >= 1 && k <= o.max_period && peaks.len() >= o.min_cycles_per_period * k && repeats(&labels, k) {
        out.regime = Regime::Periodic { period: k as u32, stick };
        out.decided_by = "section".into();
        return out;
    }
    out.decided_by = "spectrum".into();
    let window_s = speed_rad_s.len() as f64 / fs_hz;
    let f_cycle = peaks.len() as f64 / window_s;
    out.regime = spectral_regime(speed_rad_s, fs_hz, f_cycle, stick, o);
    out
}

/// Peak speed of each full cycle between consecutive upward crossings of
/// `level` (armed after dropping below level − h, fired above level + h).
fn cycle_peaks(x: &[f64], level: f64, h: f64) -> Vec<f64> {
    let mut peaks = Vec::new();
    let mut armed = false;
    let mut in_cycle = false;
    let mut peak = f64::NEG_INFINITY;
    for &v in x {
        if in_cycle {
            peak = peak.max(v);
        }
        if v < level - h {
            armed = true;
        } else if armed && v > level + h {
            armed = false;
            if in_cycle {
                peaks.push(peak);
            }
            in_cycle = true;
            peak = v;
        }
    }
    peaks
}

/// Cluster label of each value (clusters split at sorted gaps > tol, labelled
/// in increasing value), the number of clusters and the widest cluster's
/// spread: a chaotic section fills a continuum with small gaps, so a single
/// gap-split cluster is not enough — each must also be narrower than tol.
fn clusters(values: &[f64], tol: f64) -> (Vec<usize>, usize, f64) {
    if values.is_empty() {
        return (Vec::new(), 0, 0.0);
    }
    let mut sorted: Vec<f64> = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    // Upper edges of each cluster.
    let mut edges = Vec::new();
    for w in sorted.windows(2) {
        if w[1] - w[0] > tol {
            edges.push(w[0]);
        }
    }
    let labels: Vec<usize> = values.iter().map(|v| edges.iter().filter(|&&e| *v > e).count()).collect();
    let k = edges.len() + 1;
    let width = (0..k)
        .map(|c| {
            let members = values.iter().zip(&labels).filter(|(_, l)| **l == c).map(|(v, _)| *v);
            let (lo, hi) = members.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
            hi - lo
        })
        .fold(0.0, f64::max);
    (labels, k, width)
}

/// True when the label sequence repeats with period k and uses all k labels
/// in one period.
fn repeats(labels: &[usize], k: usize) -> bool {
    labels.windows(k + 1).all(|w| w[0] == w[k]) && {
        let mut first: Vec<usize> = labels.iter().take(k).copied().collect();
        first.sort_unstable();
        first.dedup();
        first.len() == k
    }
}

fn spectral_regime(x: &[f64], fs_hz: f64, f_cycle_hz: f64, stick: bool, o: &ClassifyOptions) -> Regime {
    let Ok(sl) = line_analysis(x, fs_hz, &o.line_options()) else {
        return Regime::Chaotic { stick };
    };
    if sl.quasi_periodic(o.min_line_power_fraction) {
        return Regime::QuasiPeriodic { stick };
    }
    match (sl.lines.f0_hz, sl.lines.f2_hz) {
        (Some(f0), None) if sl.discrete(o.min_line_power_fraction) && f_cycle_hz > 0.0 => {
            Regime::Periodic { period: ((f_cycle_hz / f0).round() as u32).max(1), stick }
        }
        _ => Regime::Chaotic { stick },
    }
}
