//! Log-axis ticks, the one home for every log axis of the workspace: labels
//! at decades (0.01, 0.1, 1, 10 …), and also at 2 and 5 times a decade when
//! the axis spans less than two decades; the other 2–9 multiples are short
//! unlabelled ticks with light grid lines, thinned before they crowd into a
//! grey block; and no label ever overlaps its neighbour at the size the axis
//! is drawn (labels are dropped, densest tier first, until they fit).
//!
//! Values are built from their decimal mantissa and exponent (`n · 10^e`),
//! so a label is the exact decimal ("0.05", never "0.05000000000000001").

/// Gap kept between two neighbouring labels, pixels.
pub const LABEL_GAP_PX: f64 = 8.0;
/// Minor grid lines closer together than this (pixels) are thinned: every
/// 2–9 multiple, then only 2 and 5, then none.
pub const MINOR_MIN_SPACING_PX: f64 = 5.0;
/// Below this span (decades) 2 and 5 times each decade are labelled too.
pub const LABEL_2_5_BELOW_DECADES: f64 = 2.0;

/// The ticks of one log axis, each list increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct LogTicks {
    /// Labelled ticks (long tick, grid line): value and its text.
    pub labelled: Vec<(f64, String)>,
    /// Unlabelled minor ticks (short tick, light grid line).
    pub minor: Vec<f64>,
}

impl LogTicks {
    /// The label of a labelled value (the nearest one: plotters hands back the
    /// values it was given); empty for anything else.
    pub fn label_of(&self, v: f64) -> String {
        self.labelled
            .iter()
            .min_by(|a, b| (a.0.ln() - v.ln()).abs().total_cmp(&(b.0.ln() - v.ln()).abs()))
            .filter(|(w, _)| (w.ln() - v.ln()).abs() < 1e-9)
            .map(|(_, s)| s.clone())
            .unwrap_or_default()
    }
}

/// A tick candidate `n · 10^e`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tick {
    n: u32,
    e: i32,
    v: f64,
}

impl Tick {
    fn new(n: u32, e: i32) -> Tick {
        // Parsing the decimal gives the correctly rounded f64 of n·10^e.
        let v = format!("{n}e{e}").parse().unwrap_or(f64::NAN);
        Tick { n, e, v }
    }

    /// The exact decimal text: 0.05, 2, 300, or 1e-7 / 2e8 beyond six
    /// decimals or eight digits.
    fn text(&self) -> String {
        let digits = self.n.to_string();
        let point = digits.len() as i32 + self.e; // digits before the decimal point
        if self.e < -6 || point > 8 {
            let mantissa = digits.trim_end_matches('0');
            let (first, rest) = mantissa.split_at(1);
            let dot = if rest.is_empty() { String::new() } else { format!(".{rest}") };
            return format!("{first}{dot}e{}", point - 1);
        }
        let s = if self.e >= 0 {
            format!("{digits}{}", "0".repeat(self.e as usize))
        } else if point > 0 {
            format!("{}.{}", &digits[..point as usize], &digits[point as usize..])
        } else {
            format!("0.{}{digits}", "0".repeat((-point) as usize))
        };
        if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
    }
}

/// Every `n · 10^e` (n in `mantissas`, at exponent `e + shift` for each
/// decade `10^e` touching the range) inside `lo..=hi`, increasing.
fn candidates(lo: f64, hi: f64, mantissas: &[u32], shift: i32) -> Vec<Tick> {
    let (k0, k1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let slack = 1e-9 * (hi.log10() - lo.log10());
    let inside = |v: f64| v.log10() >= lo.log10() - slack && v.log10() <= hi.log10() + slack;
    let mut out: Vec<Tick> = (k0..=k1)
        .flat_map(|e| mantissas.iter().map(move |&n| Tick::new(n, e + shift)))
        .filter(|t| inside(t.v))
        .collect();
    out.sort_by(|a, b| a.v.total_cmp(&b.v));
    out.dedup_by(|a, b| a.v == b.v);
    out
}

/// The label tiers, densest first: tenths of a decade (only for an axis too
/// short to hold two of the others), every 1–9 multiple, 1-2-5, decades, then
/// every second, third … decade.
fn tiers(lo: f64, hi: f64) -> Vec<Vec<Tick>> {
    let all: Vec<u32> = (1..=9).collect();
    let tenths: Vec<u32> = (10..=99).collect();
    let mut t = vec![
        candidates(lo, hi, &tenths, -1),
        candidates(lo, hi, &tenths, -1).into_iter().filter(|t| t.n % 2 == 0).collect(),
        candidates(lo, hi, &tenths, -1).into_iter().filter(|t| t.n % 5 == 0).collect(),
        candidates(lo, hi, &all, 0),
        candidates(lo, hi, &[1, 2, 5], 0),
    ];
    let decades = candidates(lo, hi, &[1], 0);
    t.push(decades.clone());
    for every in 2..=decades.len().max(2) as i32 {
        t.push(decades.iter().copied().filter(|d| d.e.rem_euclid(every) == 0).collect());
    }
    t
}

/// Index of the 1-2-5 tier and of the decade tier in [`tiers`].
const TIER_1_2_5: usize = 4;
const TIER_DECADES: usize = 5;

/// Whether the labels of `ticks` overlap (or come closer than [`LABEL_GAP_PX`])
/// on an axis `axis_px` long from `lo` to `hi`.
fn overlaps(ticks: &[Tick], lo: f64, hi: f64, axis_px: f64, text_width_px: &dyn Fn(&str) -> f64) -> bool {
    label_extents(ticks, lo, hi, axis_px, text_width_px).windows(2).any(|w| w[0].1 + LABEL_GAP_PX > w[1].0)
}

/// (left, right) pixel extent of each label, centred on its tick.
fn label_extents(
    ticks: &[Tick],
    lo: f64,
    hi: f64,
    axis_px: f64,
    text_width_px: &dyn Fn(&str) -> f64,
) -> Vec<(f64, f64)> {
    ticks
        .iter()
        .map(|t| {
            let x = position_px(t.v, lo, hi, axis_px);
            let w = text_width_px(&t.text());
            (x - w / 2.0, x + w / 2.0)
        })
        .collect()
}

/// Pixel position of `v` on a log axis `axis_px` long from `lo` to `hi`.
pub fn position_px(v: f64, lo: f64, hi: f64, axis_px: f64) -> f64 {
    (v.log10() - lo.log10()) / (hi.log10() - lo.log10()) * axis_px
}

/// The ticks of a log axis from `lo` to `hi` (both > 0) drawn `axis_px` long,
/// labels measured with `text_width_px`.
///
/// The axis starts at the 1-2-5 tier under [`LABEL_2_5_BELOW_DECADES`] and at
/// decades above it; it goes denser only while it holds fewer than two labels
/// (and the denser labels fit), and sparser while labels overlap.
pub fn log_ticks(lo: f64, hi: f64, axis_px: f64, text_width_px: &dyn Fn(&str) -> f64) -> LogTicks {
    if !(lo > 0.0 && hi > lo && hi.is_finite() && axis_px > 0.0) {
        return LogTicks { labelled: Vec::new(), minor: Vec::new() };
    }
    let tiers = tiers(lo, hi);
    let fits = |t: &[Tick]| !overlaps(t, lo, hi, axis_px, text_width_px);
    let span = hi.log10() - lo.log10();
    let mut k = if span < LABEL_2_5_BELOW_DECADES { TIER_1_2_5 } else { TIER_DECADES };
    while k > 0 && tiers[k].len() < 2 && fits(&tiers[k - 1]) {
        k -= 1;
    }
    while k + 1 < tiers.len() && !fits(&tiers[k]) {
        k += 1;
    }
    let labelled: Vec<Tick> = if fits(&tiers[k]) { tiers[k].clone() } else { Vec::new() };

    // Minor ticks: the 2-9 multiples (and unlabelled decades), thinned by their tightest spacing.
    let px_per_decade = axis_px / span;
    let minor_set: &[u32] = if px_per_decade * (10f64 / 9.0).log10() >= MINOR_MIN_SPACING_PX {
        &[1, 2, 3, 4, 5, 6, 7, 8, 9]
    } else if px_per_decade * 2f64.log10() >= MINOR_MIN_SPACING_PX {
        &[1, 2, 5]
    } else if px_per_decade >= MINOR_MIN_SPACING_PX {
        &[1]
    } else {
        &[]
    };
    let minor = candidates(lo, hi, minor_set, 0)
        .into_iter()
        .filter(|m| !labelled.iter().any(|l| l.v == m.v))
        .map(|m| m.v)
        .collect();
    LogTicks { labelled: labelled.iter().map(|t| (t.v, t.text())).collect(), minor }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A crude width (8 px a character) for tests of the tier logic alone;
    /// the drawing tests measure with the embedded font.
    fn w8(s: &str) -> f64 {
        8.0 * s.len() as f64
    }

    fn labels(t: &LogTicks) -> Vec<&str> {
        t.labelled.iter().map(|(_, s)| s.as_str()).collect()
    }

    #[test]
    fn texts_are_exact_decimals() {
        let text = |n, e| Tick::new(n, e).text();
        assert_eq!(text(5, -2), "0.05");
        assert_eq!(text(1, 0), "1");
        assert_eq!(text(2, 2), "200");
        assert_eq!(text(1, -6), "0.000001");
        assert_eq!(text(1, -7), "1e-7");
        assert_eq!(text(2, 8), "2e8");
        assert_eq!(text(2, 7), "20000000");
        assert_eq!(text(15, -7), "1.5e-6");
        assert_eq!(text(15, -1), "1.5");
        assert_eq!(text(15, -3), "0.015");
        assert_eq!(text(15, 9), "1.5e10");
        assert_eq!(Tick::new(3, -1).v, 0.3);
    }

    #[test]
    fn short_axes_label_2_and_5_long_ones_decades() {
        let t = log_ticks(0.004, 0.25, 450.0, &w8);
        assert_eq!(labels(&t), ["0.005", "0.01", "0.02", "0.05", "0.1", "0.2"]);
        assert!(t.minor.contains(&0.03) && t.minor.contains(&0.004) && !t.minor.contains(&0.05));
        let t = log_ticks(0.05, 50.0, 450.0, &w8);
        assert_eq!(labels(&t), ["0.1", "1", "10"]);
        assert!(t.minor.contains(&0.2) && t.minor.contains(&0.09) && t.minor.contains(&50.0));
    }

    #[test]
    fn crowded_axes_drop_labels_and_minor_lines() {
        // Twelve decades on 150 px: a few decades labelled, the others minor, no 2-9 minor lines.
        let t = log_ticks(1e-6, 1e6, 150.0, &w8);
        assert!(t.labelled.len() < 13 && t.labelled.len() >= 2, "{:?}", labels(&t));
        assert!(t.minor.iter().all(|v| t.labelled.iter().all(|l| l.0 != *v)));
        let spacing = 150.0 / 12.0 * 2f64.log10();
        assert!(spacing < MINOR_MIN_SPACING_PX);
        assert!(t.minor.iter().all(|v| (v.log10().round() - v.log10()).abs() < 1e-12), "{:?}", t.minor);
    }

    #[test]
    fn narrow_axes_go_denser_to_hold_two_labels() {
        let t = log_ticks(0.3, 0.45, 400.0, &w8);
        assert!(t.labelled.len() >= 2, "{:?}", labels(&t));
        let t = log_ticks(1.12, 1.9, 400.0, &w8);
        assert!(t.labelled.len() >= 2, "{:?}", labels(&t));
        assert!(labels(&t).iter().all(|s| s.starts_with("1.")), "{:?}", labels(&t));
    }

    #[test]
    fn bad_ranges_give_no_ticks() {
        for (lo, hi) in [(0.0, 1.0), (-1.0, 1.0), (2.0, 1.0), (1.0, f64::INFINITY)] {
            assert!(log_ticks(lo, hi, 400.0, &w8).labelled.is_empty());
        }
    }
}
