//! Axis ranges from the data: finite values only, fixed relative padding, and
//! a fallback for empty or constant data, so the same spec always gets the
//! same axes.

/// Fraction of the data span added on each side of a line/point axis.
pub const PAD_FRACTION: f64 = 0.04;

/// Running min/max over finite values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extent {
    pub min: f64,
    pub max: f64,
}

impl Extent {
    pub fn empty() -> Self {
        Extent { min: f64::INFINITY, max: f64::NEG_INFINITY }
    }

    pub fn is_empty(&self) -> bool {
        self.min > self.max
    }

    pub fn add(&mut self, v: f64) {
        if v.is_finite() {
            self.min = self.min.min(v);
            self.max = self.max.max(v);
        }
    }

    /// The plotted range: padded by `pad` of the span on both sides; a
    /// constant value gets ±10 % of its magnitude (±1 at zero); no data gets 0..1.
    pub fn padded(&self, pad: f64) -> (f64, f64) {
        if self.is_empty() {
            return (0.0, 1.0);
        }
        let span = self.max - self.min;
        if span <= 0.0 {
            let half = if self.min == 0.0 { 1.0 } else { 0.1 * self.min.abs() };
            return (self.min - half, self.max + half);
        }
        (self.min - pad * span, self.max + pad * span)
    }
}

/// Cell edges for heat-map centres: midpoints between neighbours, the end
/// cells extended by half their neighbour spacing (a single centre gets ±0.5).
pub fn cell_edges(centres: &[f64]) -> Vec<f64> {
    match centres.len() {
        0 => Vec::new(),
        1 => vec![centres[0] - 0.5, centres[0] + 0.5],
        n => {
            let mut edges = Vec::with_capacity(n + 1);
            edges.push(centres[0] - 0.5 * (centres[1] - centres[0]));
            for w in centres.windows(2) {
                edges.push(0.5 * (w[0] + w[1]));
            }
            edges.push(centres[n - 1] + 0.5 * (centres[n - 1] - centres[n - 2]));
            edges
        }
    }
}

/// Decimals for tick labels on an axis showing `lo..hi`: enough that ticks
/// about a tenth of the span apart print differently, never more than 6.
pub fn tick_decimals(lo: f64, hi: f64) -> usize {
    let step = (hi - lo).abs() / 10.0;
    if !step.is_finite() || step <= 0.0 {
        return 2;
    }
    let d = -step.log10().floor();
    d.clamp(0.0, 6.0) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_and_infinity_are_ignored() {
        let mut e = Extent::empty();
        for v in [f64::NAN, 2.0, f64::INFINITY, -1.0, f64::NEG_INFINITY] {
            e.add(v);
        }
        assert_eq!(e, Extent { min: -1.0, max: 2.0 });
        let (lo, hi) = e.padded(PAD_FRACTION);
        assert!((lo - (-1.12)).abs() < 1e-12 && (hi - 2.12).abs() < 1e-12, "{lo} {hi}");
    }

    #[test]
    fn degenerate_extents_get_a_visible_range() {
        assert_eq!(Extent::empty().padded(PAD_FRACTION), (0.0, 1.0));
        let mut c = Extent::empty();
        c.add(5.0);
        assert_eq!(c.padded(PAD_FRACTION), (4.5, 5.5));
        let mut z = Extent::empty();
        z.add(0.0);
        assert_eq!(z.padded(PAD_FRACTION), (-1.0, 1.0));
    }

    #[test]
    fn cell_edges_bracket_centres() {
        assert_eq!(cell_edges(&[1.0, 2.0, 4.0]), vec![0.5, 1.5, 3.0, 5.0]);
        assert_eq!(cell_edges(&[3.0]), vec![2.5, 3.5]);
    }

    #[test]
    fn tick_decimals_follow_the_span() {
        assert_eq!(tick_decimals(0.0, 100.0), 0);
        assert_eq!(tick_decimals(0.0, 1.0), 1);
        assert_eq!(tick_decimals(0.0, 0.05), 3);
    }
}
