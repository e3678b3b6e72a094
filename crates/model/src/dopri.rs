//! Dormand–Prince 5(4) with PI step-size control and Hairer's 4th-order dense
//! output (Hairer, Nørsett & Wanner, *Solving ODEs I*, II.5 and the `dopri5`
//! code). The caller owns the loop: it asks for one accepted step at a time,
//! evaluates its event functions on the step's dense output and, after an
//! event, truncates the step and restarts with [`Dopri::reset`].

/// Dimension of the rig state [φ1, φ2, Ω1, Ω2, i, ∫e].
/// State size: the six states of the crate docs plus the pad temperature
/// rise of [`rig_types::Effect::BrakeFade`] (identically 0 without it).
pub(crate) const DIM: usize = 7;
pub(crate) type Vector = [f64; DIM];

// Butcher tableau of Dormand & Prince (1980), as in Hairer's dopri5.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error estimate: 5th-order minus embedded 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output (Hairer's dopri5, `d1..d7`).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

// PI step control constants of Hairer's dopri5 (beta = 0.04 stabilises the
// step sequence on the non-smooth right-hand sides of saturation and friction).
const SAFETY: f64 = 0.9;
const BETA: f64 = 0.04;
const FAC_MIN: f64 = 0.2; // largest shrink 1/5
const FAC_MAX: f64 = 10.0; // largest growth
/// ln 10⁻⁴: dopri5's floor of `facold`.
const FAC_OLD_MIN_LN: f64 = -9.210340371976182;

/// One accepted step with its continuous extension.
#[derive(Debug, Clone, Default)]
pub(crate) struct Step {
    pub t0: f64,
    pub h: f64,
    pub y1: Vector,
    rcont: [Vector; 5],
}

impl Step {
    pub fn t1(&self) -> f64 {
        self.t0 + self.h
    }

    /// 4th-order interpolant at `t` in [t0, t0 + h].
    pub fn dense(&self, t: f64) -> Vector {
        let theta = ((t - self.t0) / self.h).clamp(0.0, 1.0);
        let theta1 = 1.0 - theta;
        let r = &self.rcont;
        let mut y = [0.0; DIM];
        for j in 0..DIM {
            y[j] = r[0][j] + theta * (r[1][j] + theta1 * (r[2][j] + theta * (r[3][j] + theta1 * r[4][j])));
        }
        y
    }
}

/// Why a step could not be taken.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum StepFailure {
    /// The step size fell below round-off of `t`.
    StepTooSmall { h: f64 },
    /// The right-hand side produced a non-finite value.
    NonFinite,
}

#[derive(Debug)]
pub(crate) struct Dopri {
    rtol: f64,
    atol: f64,
    max_step: f64,
    /// Step size proposed for the next step (0 = choose one).
    h: f64,
    /// ln of the previous accepted step's error (at least 10⁻⁴), dopri5's `facold`.
    ln_fac_old: f64,
    /// Number of components in the RMS error norm: the leading `norm_dim`
    /// states (6 unless the thermal state is in use, so that a run without
    /// it steps exactly as it did before the state existed).
    norm_dim: f64,
    /// f(t, y) at the current point when still valid (first-same-as-last).
    k1: Option<Vector>,
    /// The last accepted step (kept here: returning its 44 numbers by value
    /// cost a copy per step).
    last: Step,
    /// Number of right-hand-side evaluations, accepted and rejected steps.
    pub n_eval: u64,
    pub n_accept: u64,
    pub n_reject: u64,
}

/// y + h Σ a_s k_s; fixed arity so the compiler unrolls the stage sum.
#[inline(always)]
fn axpy<const S: usize>(y: &Vector, h: f64, a: [f64; S], k: [&Vector; S]) -> Vector {
    let mut out = *y;
    for j in 0..DIM {
        let mut s = 0.0;
        for i in 0..S {
            s += a[i] * k[i][j];
        }
        out[j] += h * s;
    }
    out
}

fn finite(v: &Vector) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl Dopri {
    pub fn new(rtol: f64, atol: f64, max_step: f64) -> Self {
        Dopri {
            rtol,
            atol,
            max_step,
            h: 0.0,
            ln_fac_old: FAC_OLD_MIN_LN,
            norm_dim: DIM as f64,
            k1: None,
            last: Step::default(),
            n_eval: 0,
            n_accept: 0,
            n_reject: 0,
        }
    }

    /// Error norm over the first `n` states only (the others must then have
    /// zero derivative, so they add exactly 0 to the sum).
    pub fn with_norm_dim(mut self, n: usize) -> Self {
        self.norm_dim = n.min(DIM) as f64;
        self
    }

    /// The step size the controller proposes next (0 before the first step).
    pub fn proposed_step(&self) -> f64 {
        self.h.min(self.max_step)
    }

    /// Forget the FSAL derivative: the right-hand side changed (new mode) or
    /// the state was modified at an event. The proposed step size is kept.
    pub fn reset(&mut self) {
        self.k1 = None;
    }

    /// Hairer's starting step (II.4, "hinit"), capped by `max_step`. Not by the
    /// span to the next stop: a step cut to a sliver before a sample time must
    /// not leave a sliver as the proposal for the steps after it (the probe
    /// evaluates f beyond the stop, which is defined there).
    fn initial_step(&self, t: f64, y: &Vector, k1: &Vector, f: &mut impl FnMut(f64, &Vector) -> Vector) -> f64 {
        let sc = |j: usize| self.atol + self.rtol * y[j].abs();
        let d0 = (y.iter().enumerate().map(|(j, v)| (v / sc(j)).powi(2)).sum::<f64>() / self.norm_dim).sqrt();
        let d1 = (k1.iter().enumerate().map(|(j, v)| (v / sc(j)).powi(2)).sum::<f64>() / self.norm_dim).sqrt();
        let h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
        let h0 = h0.min(self.max_step);
        let y1 = axpy(y, h0, [1.0], [k1]);
        let k2 = f(t + h0, &y1);
        let d2 = (k2.iter().zip(k1).enumerate().map(|(j, (a, b))| ((a - b) / sc(j)).powi(2)).sum::<f64>()
            / self.norm_dim)
            .sqrt()
            / h0;
        let h1 = if d1.max(d2) <= 1e-15 { (h0 * 1e-3).max(1e-6) } else { (0.01 / d1.max(d2)).powf(0.2) };
        // Not capped by `span`: this is the proposal for the steps after a cut one too.
        (100.0 * h0).min(h1).min(self.max_step)
    }

    /// The step [`Dopri::step`] accepted last.
    pub fn last_step(&self) -> &Step {
        &self.last
    }

    /// Takes one accepted step from (t, y) that does not pass `t_stop`
    /// ([`Dopri::last_step`] then holds it).
    pub fn step(
        &mut self,
        t: f64,
        y: &Vector,
        t_stop: f64,
        f: &mut impl FnMut(f64, &Vector) -> Vector,
    ) -> Result<(), StepFailure> {
        let k1 = match self.k1 {
            Some(k) => k,
            None => {
                self.n_eval += 1;
                let k = f(t, y);
                if !finite(&k) {
                    return Err(StepFailure::NonFinite);
                }
                k
            }
        };
        let span = t_stop - t;
        if self.h <= 0.0 {
            self.h = self.initial_step(t, y, &k1, f);
            self.n_eval += 1;
        }
        let mut h = self.h.min(self.max_step);
        let mut last = false;
        if h >= span {
            h = span;
            last = true;
        }
        loop {
            if h <= 16.0 * f64::EPSILON * t.abs().max(1.0) && !last {
                return Err(StepFailure::StepTooSmall { h });
            }
            let k2 = f(t + C2 * h, &axpy(y, h, [A21], [&k1]));
            let k3 = f(t + C3 * h, &axpy(y, h, [A31, A32], [&k1, &k2]));
            let k4 = f(t + C4 * h, &axpy(y, h, [A41, A42, A43], [&k1, &k2, &k3]));
            let k5 = f(t + C5 * h, &axpy(y, h, [A51, A52, A53, A54], [&k1, &k2, &k3, &k4]));
            let k6 = f(t + h, &axpy(y, h, [A61, A62, A63, A64, A65], [&k1, &k2, &k3, &k4, &k5]));
            let y1 = axpy(y, h, [A71, A73, A74, A75, A76], [&k1, &k3, &k4, &k5, &k6]);
            let t1 = if last { t_stop } else { t + h };
            let k7 = f(t1, &y1);
            self.n_eval += 6;
            let mut err = 0.0;
            for j in 0..DIM {
                let e = h * (E1 * k1[j] + E3 * k3[j] + E4 * k4[j] + E5 * k5[j] + E6 * k6[j] + E7 * k7[j]);
                let sc = self.atol + self.rtol * y[j].abs().max(y1[j].abs());
                err += (e / sc).powi(2);
            }
            let err = (err / self.norm_dim).sqrt();
            if !err.is_finite() || !finite(&y1) {
                // A non-finite trial: shrink hard and retry; give up below round-off.
                self.n_reject += 1;
                h *= FAC_MIN;
                last = false;
                if h <= 16.0 * f64::EPSILON * t.abs().max(1.0) {
                    return Err(StepFailure::NonFinite);
                }
                continue;
            }
            // err^(0.2 − 0.75 β) and fac_old^β by one logarithm each (fac_old's is kept):
            // dopri5's two powers of a step, for an exp and a ln.
            let ln_err = err.ln();
            if err <= 1.0 {
                let fac = (((0.2 - BETA * 0.75) * ln_err - BETA * self.ln_fac_old).exp() / SAFETY)
                    .clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                self.ln_fac_old = ln_err.max(FAC_OLD_MIN_LN);
                self.n_accept += 1;
                let rcont = &mut self.last.rcont;
                for j in 0..DIM {
                    let ydiff = y1[j] - y[j];
                    let bspl = h * k1[j] - ydiff;
                    rcont[0][j] = y[j];
                    rcont[1][j] = ydiff;
                    rcont[2][j] = bspl;
                    rcont[3][j] = ydiff - h * k7[j] - bspl;
                    rcont[4][j] = h * (D1 * k1[j] + D3 * k3[j] + D4 * k4[j] + D5 * k5[j] + D6 * k6[j] + D7 * k7[j]);
                }
                // Keep the controller's proposal when the step was cut to t_stop, unless
                // the error of the cut step asks for a smaller one (a step cut to a
                // sliver says nothing about the step size the solution allows).
                let h_new = h / fac;
                if !last || (h_new < h && h_new < self.h) {
                    self.h = h_new;
                }
                self.k1 = Some(k7);
                (self.last.t0, self.last.h, self.last.y1) = (t, t1 - t, y1);
                return Ok(());
            }
            self.n_reject += 1;
            h /= (((0.2 - BETA * 0.75) * ln_err).exp() / SAFETY).min(1.0 / FAC_MIN);
            last = false;
        }
    }
}

/// Finds t in (a, b] where g changes sign, g(a) and g(b) of opposite sign
/// (or g(b) = 0), by the Illinois variant of regula falsi. Returns the right
/// end of the final bracket, so g has already crossed at the returned time.
pub(crate) fn locate_root(mut a: f64, mut ga: f64, mut b: f64, mut gb: f64, mut g: impl FnMut(f64) -> f64) -> f64 {
    let tol = 4.0 * f64::EPSILON * b.abs().max(1.0);
    let mut side = 0i8;
    for _ in 0..200 {
        if gb == 0.0 || (b - a) <= tol {
            break;
        }
        let mut c = (a * gb - b * ga) / (gb - ga);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let gc = g(c);
        if gc == 0.0 || gc.signum() == gb.signum() {
            b = c;
            gb = gc;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            a = c;
            ga = gc;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y'' = −y in three copies with different phases: exact solution known.
    fn rhs(_t: f64, y: &Vector) -> Vector {
        [y[1], -y[0], y[3], -y[2], y[5], -y[4], 1.0]
    }

    fn exact(t: f64) -> Vector {
        [t.cos(), -t.sin(), t.sin(), t.cos(), (t + 1.0).cos(), -(t + 1.0).sin(), t]
    }

    /// Steps of fixed size h (tolerance so loose no step is rejected, max_step = h):
    /// the step error falls as h^5 and the dense output's as h^5 too (4th-order
    /// interpolant, local error O(h^5)), which checks every tableau coefficient.
    #[test]
    fn step_and_dense_output_have_the_expected_order() {
        let errs = |h: f64| {
            let mut dp = Dopri::new(1.0, 1.0, h);
            dp.h = h;
            let mut f = rhs;
            dp.step(0.0, &exact(0.0), 1.0, &mut f).unwrap();
            let s = dp.last_step();
            assert_eq!(s.h, h);
            let e_end = (0..DIM).map(|j| (s.y1[j] - exact(h)[j]).abs()).fold(0.0, f64::max);
            let e_mid = [0.3, 0.5, 0.8]
                .iter()
                .map(|th| {
                    let y = s.dense(th * h);
                    (0..DIM).map(|j| (y[j] - exact(th * h)[j]).abs()).fold(0.0, f64::max)
                })
                .fold(0.0, f64::max);
            (e_end, e_mid)
        };
        let (a_end, a_mid) = errs(0.2);
        let (b_end, b_mid) = errs(0.1);
        // Local error of a 5th-order step is O(h^6): ratio 2^6 = 64 per halving.
        let order_end = (a_end / b_end).log2();
        let order_mid = (a_mid / b_mid).log2();
        assert!(order_end > 5.5, "step order {order_end}");
        assert!(order_mid > 4.5, "dense order {order_mid}");
    }

    #[test]
    fn locate_root_finds_a_simple_crossing() {
        let g = |t: f64| t * t - 2.0;
        let r = locate_root(1.0, g(1.0), 2.0, g(2.0), g);
        assert!((r - 2f64.sqrt()).abs() < 1e-14 && g(r) >= 0.0);
    }
}
