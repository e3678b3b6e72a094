//! Spectral windows with their coherent and energy gains, and detrending.
//!
//! Windows are "periodic" (DFT-even, scipy's `get_window(..., fftbins=True)`):
//! w[n] = Σ_j (−1)^j a_j cos(2π j n / N), so a tone on a bin centre leaks only
//! into the window's own main-lobe bins.

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Window {
    Rectangular,
    Hann,
    Hamming,
    /// scipy's `flattop` (SRS coefficients): amplitude error < 0.02 dB anywhere in a bin.
    FlatTop,
}

impl Window {
    /// Cosine-sum coefficients a_j.
    fn coefficients(self) -> &'static [f64] {
        match self {
            Window::Rectangular => &[1.0],
            Window::Hann => &[0.5, 0.5],
            Window::Hamming => &[0.54, 0.46],
            Window::FlatTop => &[0.215_578_95, 0.416_631_58, 0.277_263_158, 0.083_578_947, 0.006_947_368],
        }
    }

    /// The n samples of the periodic window. The last window made on this
    /// thread is kept and handed out again (a fit's inner loop analyses
    /// records of one length thousands of times: the LAVI study): the same
    /// bits, without n cosines per term each time.
    pub fn samples(self, n: usize) -> Vec<f64> {
        thread_local! {
            static LAST: std::cell::RefCell<Option<(Window, Vec<f64>)>> = const { std::cell::RefCell::new(None) };
        }
        LAST.with(|last| {
            let mut last = last.borrow_mut();
            match &*last {
                Some((w, v)) if *w == self && v.len() == n => v.clone(),
                _ => {
                    let v = self.compute(n);
                    *last = Some((self, v.clone()));
                    v
                }
            }
        })
    }

    fn compute(self, n: usize) -> Vec<f64> {
        let a = self.coefficients();
        (0..n)
            .map(|i| {
                let x = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                a.iter().enumerate().map(|(j, &aj)| if j % 2 == 0 { aj } else { -aj } * (j as f64 * x).cos()).sum()
            })
            .collect()
    }
}

/// Gains of a window of length N: they turn |DFT| into amplitude or power.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowGains {
    /// Σw / N: a sinusoid's DFT peak is scaled by this (amplitude correction = 1 / coherent).
    pub coherent: f64,
    /// Σw² / N: broadband power is scaled by this (PSD correction = 1 / energy).
    pub energy: f64,
    /// Equivalent noise bandwidth in bins, N Σw² / (Σw)² (1 rectangular, 1.5 Hann).
    pub enbw_bins: f64,
}

pub fn gains(w: &[f64]) -> WindowGains {
    let n = w.len() as f64;
    let s1: f64 = w.iter().sum();
    let s2: f64 = w.iter().map(|v| v * v).sum();
    WindowGains { coherent: s1 / n, energy: s2 / n, enbw_bins: n * s2 / (s1 * s1) }
}

/// What is removed from a record (or Welch segment) before windowing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Detrend {
    None,
    /// Subtract the mean (a DC offset leaks through the window's side lobes otherwise).
    Constant,
    /// Subtract the least-squares line (drifting sensors, ramps).
    Linear,
}

/// Returns `x` with the trend removed.
pub fn detrend(x: &[f64], how: Detrend) -> Vec<f64> {
    let n = x.len();
    match how {
        Detrend::None => x.to_vec(),
        Detrend::Constant => {
            let m = x.iter().sum::<f64>() / n.max(1) as f64;
            x.iter().map(|v| v - m).collect()
        }
        Detrend::Linear => {
            if n < 2 {
                return detrend(x, Detrend::Constant);
            }
            // Least-squares line on the index t = 0..n-1 (centred for conditioning).
            let tm = (n - 1) as f64 / 2.0;
            let xm = x.iter().sum::<f64>() / n as f64;
            let (mut sxy, mut sxx) = (0.0, 0.0);
            for (i, v) in x.iter().enumerate() {
                let t = i as f64 - tm;
                sxy += t * (v - xm);
                sxx += t * t;
            }
            let slope = sxy / sxx;
            x.iter().enumerate().map(|(i, v)| v - xm - slope * (i as f64 - tm)).collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kept_window_is_the_computed_one() {
        // Alternate windows and lengths: every call hands out the window of its own kind and length.
        for (w, n) in [
            (Window::Hann, 4000),
            (Window::Hann, 4000),
            (Window::FlatTop, 4000),
            (Window::Hann, 7),
            (Window::Hann, 4000),
        ] {
            assert_eq!(w.samples(n), w.compute(n), "{w:?} {n}");
        }
        // Hann's known values: 0 at the start, 1 at the middle of the periodic window.
        let h = Window::Hann.samples(8);
        assert!(h[0].abs() < 1e-15 && (h[4] - 1.0).abs() < 1e-15, "{h:?}");
    }
}
