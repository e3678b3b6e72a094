//! Line analysis: which spectral lines are harmonics of one fundamental, which
//! are combination tones |m f0 ± n f2| of two incommensurate base frequencies,
//! and which are unrelated — with a tolerance tied to the frequency resolution.
//!
//! Tolerance of a line (stated once, used everywhere):
//! `tol = max(tolerance_bins · resolution_hz, sigma_factor · σ_f)`, with
//! `resolution_hz` = fs/N = 1 / record length and σ_f the line's own frequency
//! uncertainty when the caller knows it (0 otherwise). Default 1.5 bins, 3σ.
//!
//! Procedure:
//! 1. Fundamental f0 (best common divisor): for every line at least
//!    `min_fundamental_rel` of the strongest, f0 is scanned
//!    over the line's frequency ± its tolerance (41 points); the score of an
//!    f0 is the summed amplitude of the lines within tolerance of some k·f0
//!    (k = 1..max_harmonic). Highest score wins (ties: the first found, i.e.
//!    the lower line and the lower f0), so a line that divides the others
//!    wins over a stronger line that does not. f0 is then refined by a
//!    weighted least-squares fit f_k ≈ k·f0 over its matched harmonics
//!    (weights = amplitude), and the matching is repeated with the refined f0
//!    (now at each line's own tolerance) until the matched set is stable.
//! 2. The strongest line left is a base candidate f2. If f2 ≈ (p/q)·f0 with
//!    q ≤ max_denominator within tolerance, it is `commensurate` (the two are
//!    locked: period-q motion, not quasi-periodic) and the next strongest is
//!    tried. The first incommensurate one becomes the second base f2.
//! 3. Remaining lines: n·f2 (n ≥ 2) is `harmonic` of f2; |m f0 ± n f2| with
//!    m, n ≥ 1 and m + n ≤ max_order is `combination` (lowest order first,
//!    then smallest error); anything else is `unrelated`.

use crate::peaks::Peak;
use serde::{Deserialize, Serialize};

/// A line given to the analysis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Line {
    pub freq_hz: f64,
    pub amplitude: f64,
    /// Frequency standard uncertainty, Hz (0 if unknown).
    pub sigma_hz: f64,
}

impl From<&Peak> for Line {
    fn from(p: &Peak) -> Self {
        Line { freq_hz: p.freq_hz, amplitude: p.amplitude, sigma_hz: p.sigma_hz }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LineOptions {
    pub tolerance_bins: f64,
    pub sigma_factor: f64,
    pub max_harmonic: u32,
    /// Largest m + n of a combination tone.
    pub max_order: u32,
    /// Largest q of a ratio p/q that counts as "commensurate".
    pub max_denominator: u32,
    /// Only lines at least this fraction of the strongest line's amplitude may
    /// seed the fundamental: with a tolerance of 1.5 bins the comb k·f0 of a
    /// weak low line covers a large share of the axis and would "explain"
    /// unrelated lines by chance.
    pub min_fundamental_rel: f64,
}

impl Default for LineOptions {
    fn default() -> Self {
        LineOptions {
            tolerance_bins: 1.5,
            sigma_factor: 3.0,
            max_harmonic: 10,
            max_order: 4,
            max_denominator: 3,
            min_fundamental_rel: 0.25,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LineClass {
    /// k·f0 (k = 1 is the fundamental itself), or n·f2.
    Harmonic,
    /// The second, incommensurate base frequency f2.
    Base,
    /// |m f0 ± n f2|.
    Combination,
    /// (p/q)·f0 with 1 < q ≤ max_denominator: a sub/ultra-harmonic, locked to f0.
    Commensurate,
    Unrelated,
}

impl LineClass {
    pub fn as_str(self) -> &'static str {
        match self {
            LineClass::Harmonic => "harmonic",
            LineClass::Base => "base",
            LineClass::Combination => "combination",
            LineClass::Commensurate => "commensurate",
            LineClass::Unrelated => "unrelated",
        }
    }
}

/// One classified line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LineRow {
    pub freq_hz: f64,
    pub amplitude: f64,
    pub class: LineClass,
    /// e.g. "1×f0", "2×f0", "f2", "f0+f2", "2×f0−f2", "3/2×f0"; empty when unrelated.
    pub relation: String,
    /// Measured minus predicted frequency, Hz (0 for the bases themselves).
    pub error_hz: f64,
    pub tolerance_hz: f64,
}

/// The ratio test of two base frequencies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RatioTest {
    /// f2 / f0.
    pub ratio: f64,
    /// The nearest p/q with q ≤ max_denominator.
    pub p: u32,
    pub q: u32,
    /// f2 − (p/q)·f0, Hz.
    pub error_hz: f64,
    pub tolerance_hz: f64,
    /// True when |error| > tolerance for every p/q with q ≤ max_denominator.
    pub incommensurate: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LineAnalysis {
    pub f0_hz: Option<f64>,
    pub f2_hz: Option<f64>,
    /// Ratio test of the strongest line not harmonic of f0 (the f2 candidate).
    pub ratio: Option<RatioTest>,
    /// In the order of the input lines sorted by frequency.
    pub rows: Vec<LineRow>,
}

impl LineAnalysis {
    pub fn count(&self, class: LineClass) -> usize {
        self.rows.iter().filter(|r| r.class == class).count()
    }
}

fn tolerance(l: &Line, resolution_hz: f64, o: &LineOptions) -> f64 {
    (o.tolerance_bins * resolution_hz).max(o.sigma_factor * l.sigma_hz)
}

/// Nearest harmonic number k ≥ 1 of f0 to f, if within max_harmonic.
fn nearest_k(f: f64, f0: f64, max_k: u32) -> Option<u32> {
    let k = (f / f0).round();
    (k >= 1.0 && k <= max_k as f64).then_some(k as u32)
}

/// Half-width of the f0 scan around each candidate line, in steps (the scan
/// spans ± the line's tolerance).
const SCAN_STEPS: i32 = 20;

/// Indices of lines within tolerance of a harmonic of f0, with their k.
fn harmonics_of(lines: &[Line], tol: &[f64], f0: f64, max_k: u32) -> Vec<(usize, u32)> {
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if let Some(k) = nearest_k(l.freq_hz, f0, max_k)
            && (l.freq_hz - k as f64 * f0).abs() <= tol[i]
        {
            out.push((i, k));
        }
    }
    out
}

/// The best p/q (q ≤ max_q) for f ≈ (p/q)·f0: smallest |error|, ties → smaller q.
pub fn ratio_test(f2: f64, f0: f64, tolerance_hz: f64, max_q: u32) -> RatioTest {
    let mut best = (0u32, 1u32, f64::INFINITY);
    for q in 1..=max_q.max(1) {
        let p = (f2 / f0 * q as f64).round().max(1.0) as u32;
        let err = f2 - p as f64 / q as f64 * f0;
        if err.abs() < best.2.abs() - 1e-12 {
            best = (p, q, err);
        }
    }
    RatioTest {
        ratio: f2 / f0,
        p: best.0,
        q: best.1,
        error_hz: best.2,
        tolerance_hz,
        incommensurate: best.2.abs() > tolerance_hz,
    }
}

fn times(k: u32, base: &str) -> String {
    format!("{k}×{base}")
}

/// Classifies `lines` (any order) at frequency resolution `resolution_hz`.
pub fn analyse_lines(lines: &[Line], resolution_hz: f64, o: &LineOptions) -> LineAnalysis {
    let mut lines: Vec<Line> = lines.iter().copied().filter(|l| l.freq_hz > 0.0 && l.amplitude > 0.0).collect();
    lines.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    let tol: Vec<f64> = lines.iter().map(|l| tolerance(l, resolution_hz, o)).collect();
    let mut rows: Vec<LineRow> = lines
        .iter()
        .zip(&tol)
        .map(|(l, t)| LineRow {
            freq_hz: l.freq_hz,
            amplitude: l.amplitude,
            class: LineClass::Unrelated,
            relation: String::new(),
            error_hz: 0.0,
            tolerance_hz: *t,
        })
        .collect();
    if lines.is_empty() {
        return LineAnalysis { f0_hz: None, f2_hz: None, ratio: None, rows };
    }

    // 1. Fundamental by harmonic score: best common divisor near each line.
    let mut best: Option<(f64, f64)> = None; // (score, f0)
    let strongest = lines.iter().map(|l| l.amplitude).fold(0.0, f64::max);
    for (j, cand) in lines.iter().enumerate() {
        if cand.amplitude < o.min_fundamental_rel * strongest {
            continue;
        }
        for step in -SCAN_STEPS..=SCAN_STEPS {
            let f = cand.freq_hz + tol[j] * step as f64 / SCAN_STEPS as f64;
            if f <= 0.0 {
                continue;
            }
            let score: f64 =
                harmonics_of(&lines, &tol, f, o.max_harmonic).iter().map(|(i, _)| lines[*i].amplitude).sum();
            if best.is_none_or(|(s, _)| score > s * (1.0 + 1e-12)) {
                best = Some((score, f));
            }
        }
    }
    let (_, mut f0) = best.expect("lines is not empty");
    let mut matched = harmonics_of(&lines, &tol, f0, o.max_harmonic);
    // Refine and rematch until the matched set no longer changes (a few rounds at most).
    for _ in 0..8 {
        let (num, den) = matched.iter().fold((0.0, 0.0), |(n, d), (i, k)| {
            let w = lines[*i].amplitude;
            (n + w * *k as f64 * lines[*i].freq_hz, d + w * (*k as f64).powi(2))
        });
        if den <= 0.0 {
            break;
        }
        let next = harmonics_of(&lines, &tol, num / den, o.max_harmonic);
        f0 = num / den;
        if next == matched {
            break;
        }
        matched = next;
    }
    let mut taken = vec![false; lines.len()];
    for (i, k) in harmonics_of(&lines, &tol, f0, o.max_harmonic) {
        taken[i] = true;
        rows[i].class = LineClass::Harmonic;
        rows[i].relation = times(k, "f0");
        rows[i].error_hz = lines[i].freq_hz - k as f64 * f0;
    }

    // 2. Second base: strongest remaining line that is not locked to f0.
    let mut order: Vec<usize> = (0..lines.len()).filter(|&i| !taken[i]).collect();
    order.sort_by(|&a, &b| lines[b].amplitude.total_cmp(&lines[a].amplitude).then(a.cmp(&b)));
    let mut f2 = None;
    let mut ratio = None;
    for i in order {
        let rt = ratio_test(lines[i].freq_hz, f0, tol[i], o.max_denominator);
        if ratio.is_none() {
            ratio = Some(rt);
        }
        taken[i] = true;
        if rt.incommensurate {
            rows[i].class = LineClass::Base;
            rows[i].relation = "f2".into();
            f2 = Some(lines[i].freq_hz);
            ratio = Some(rt);
            break;
        }
        rows[i].class = LineClass::Commensurate;
        rows[i].relation = format!("{}/{}×f0", rt.p, rt.q);
        rows[i].error_hz = rt.error_hz;
    }

    // 3. Harmonics of f2 and combination tones.
    if let Some(f2) = f2 {
        for i in 0..lines.len() {
            if taken[i] {
                continue;
            }
            let f = lines[i].freq_hz;
            if let Some(n) = nearest_k(f, f2, o.max_harmonic)
                && n >= 2
                && (f - n as f64 * f2).abs() <= tol[i]
            {
                rows[i].class = LineClass::Harmonic;
                rows[i].relation = times(n, "f2");
                rows[i].error_hz = f - n as f64 * f2;
                continue;
            }
            let mut found: Option<(u32, f64, String)> = None;
            for order in 2..=o.max_order {
                for m in 1..order {
                    let n = order - m;
                    let cands = [
                        (m as f64 * f0 + n as f64 * f2, format!("{}f0+{}f2", coef(m), coef(n))),
                        ((m as f64 * f0 - n as f64 * f2).abs(), diff_name(m, n, m as f64 * f0 > n as f64 * f2)),
                    ];
                    for (pred, name) in cands {
                        let err = f - pred;
                        if err.abs() <= tol[i] && found.as_ref().is_none_or(|(_, e, _)| err.abs() < e.abs()) {
                            found = Some((order, err, name));
                        }
                    }
                }
                if found.is_some() {
                    break;
                }
            }
            if let Some((_, err, name)) = found {
                rows[i].class = LineClass::Combination;
                rows[i].relation = name;
                rows[i].error_hz = err;
            }
        }
    }
    LineAnalysis { f0_hz: Some(f0), f2_hz: f2, ratio, rows }
}

fn coef(m: u32) -> String {
    if m == 1 { String::new() } else { format!("{m}×") }
}

fn diff_name(m: u32, n: u32, f0_side_larger: bool) -> String {
    if f0_side_larger { format!("{}f0−{}f2", coef(m), coef(n)) } else { format!("{}f2−{}f0", coef(n), coef(m)) }
}
