//! Exact steps of the rig equations where they are affine.
//!
//! Between events, and away from the few switches inside the right-hand side
//! (voltage clamp, the sign of the motor friction, a segment of the friction
//! lookup), the equations of [`crate::system::System::rhs`] are linear in the
//! state with a forcing affine in t (the reference ramp). With the augmented
//! state z = [φ1 φ2 Ω1 Ω2 i ∫e t 1] they read ż = M z, so a step of length h
//! is z(t + h) = e^{M h} z(t) exactly: no truncation error, no stability
//! limit from the drive's fast modes (the armature's R/L and the PI loop,
//! −300…−600 1/s, or the thesis lookup's creep slope, ≈ −1.8·10⁴ 1/s), and
//! one 6 × 8 matrix-vector product per step once e^{M h} is known. The
//! caller (module `sim`) takes such a step only when the step ends in the
//! region it started in and no event function changed sign; otherwise it
//! takes a Dormand–Prince step, which locates the event on its dense output
//! exactly as before. Propagators e^{M h} are cached per (region, h): with a
//! uniform sample grid every step of a run reuses one or two of them.

use crate::dopri::Vector;
use crate::system::{Region, System};

/// Size of the augmented state [q (6), t, 1].
pub(crate) const AUG: usize = 8;
/// Index of t in the augmented state.
pub(crate) const TIME: usize = 6;
/// Index of the constant 1 in the augmented state.
pub(crate) const ONE: usize = 7;
/// Rows of e^{M h} that are propagated (the rows of t and 1 are trivial).
pub(crate) const ROWS: usize = 6;
pub(crate) type Mat = [[f64; AUG]; AUG];
/// The first [`ROWS`] rows of e^{M h}, stored by column: `p[j][i]` is row i,
/// column j, so that the six rows' products with one z_j are contiguous (see [`apply`]).
type Propagator = [[f64; ROWS]; AUG];

/// Steps whose lengths differ by at most this fraction of h, plus a few ulps
/// of t, share a propagator: the sample grid t0 + k/rate has spacings that
/// differ by ulps of t. Using e^{M h'} for a step of h moves the end state by
/// |h − h'|·|ż|: at most 10⁻¹⁰·h·|ż| (summed over a run, below 10⁻⁹ of any
/// state) plus the error the rounding of t itself already makes.
const H_MATCH_REL: f64 = 1e-10;

/// Whether steps of lengths `a` and `b` at time `t` share a propagator (see [`H_MATCH_REL`]).
#[inline]
pub(crate) fn same_step(a: f64, b: f64, t: f64) -> bool {
    (a - b).abs() <= H_MATCH_REL * a.abs() + 8.0 * f64::EPSILON * t.abs()
}
/// Cached propagators (regions × step lengths), replaced round-robin.
const CACHE: usize = 12;

fn matmul(a: &Mat, b: &Mat) -> Mat {
    let mut c = [[0.0; AUG]; AUG];
    for i in 0..AUG {
        for k in 0..AUG {
            let aik = a[i][k];
            if aik != 0.0 {
                for j in 0..AUG {
                    c[i][j] += aik * b[k][j];
                }
            }
        }
    }
    c
}

/// e^{M h} by scaling and squaring of the Taylor series (Moler & Van Loan,
/// "Nineteen dubious ways", method 3): M h / 2^s has ∞-norm ≤ 1/2, where the
/// 16 terms leave a remainder below 0.5¹⁷/17! ≈ 2·10⁻²⁰ of the norm. The
/// polynomial is evaluated by Paterson & Stockmeyer's scheme (blocks of four
/// powers, Horner in A⁴): 7 matrix products instead of 16.
pub(crate) fn expm(m: &Mat, h: f64) -> Mat {
    let norm = m.iter().map(|row| row.iter().map(|x| (x * h).abs()).sum::<f64>()).fold(0.0, f64::max);
    let s = if norm > 0.5 { (norm / 0.5).log2().ceil() as i32 } else { 0 };
    let scale = h / 2f64.powi(s);
    let a = m.map(|row| row.map(|x| x * scale));
    let mut identity = [[0.0; AUG]; AUG];
    for (i, row) in identity.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let a2 = matmul(&a, &a);
    let a3 = matmul(&a2, &a);
    let a4 = matmul(&a2, &a2);
    let powers = [&identity, &a, &a2, &a3];
    // 1/k! for k = 0..=16.
    let mut inv_fact = [1.0; 17];
    for k in 1..17 {
        inv_fact[k] = inv_fact[k - 1] / k as f64;
    }
    // Block j: Σ_{i<4} A^i / (4j + i)!; the last block is I/16!.
    let block = |j: usize| -> Mat {
        let mut b = [[0.0; AUG]; AUG];
        for (i, p) in powers.iter().enumerate().filter(|(i, _)| 4 * j + i <= 16) {
            let c = inv_fact[4 * j + i];
            for (br, pr) in b.iter_mut().zip(p.iter()) {
                for (x, y) in br.iter_mut().zip(pr) {
                    *x += c * y;
                }
            }
        }
        b
    };
    let mut e = block(4);
    for j in (0..4).rev() {
        let mut next = matmul(&a4, &e);
        for (nr, br) in next.iter_mut().zip(block(j)) {
            for (x, y) in nr.iter_mut().zip(br) {
                *x += y;
            }
        }
        e = next;
    }
    for _ in 0..s {
        e = matmul(&e, &e);
    }
    e
}

/// What [`Exact::propagator`] may do when no cached propagator fits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Compute {
    /// Compute one and cache it.
    Cache,
    /// Compute one for this step only.
    Once,
    /// Nothing: the caller takes a Dormand–Prince step.
    No,
}

/// Cache of propagators e^{M h} of one run.
#[derive(Debug, Default)]
pub(crate) struct Exact {
    entries: Vec<(Region, f64, Propagator)>,
    next: usize,
    /// The entry used last (checked first).
    last: usize,
    /// A propagator computed for one step only.
    once: Propagator,
    /// Exact steps taken and propagators computed.
    pub steps: u64,
    pub computed: u64,
}

impl Exact {
    /// Whether propagators may still be computed (see [`Exact::propagator`]).
    pub fn viable(&self) -> bool {
        self.computed < 32 + self.steps / 16
    }

    /// The propagator of `region` over `h` and the step length it was computed
    /// for (which `h` matches by [`same_step`]): cached; or computed and cached when
    /// [`Compute::Cache`] (a step length the run will reuse); or computed for
    /// this step alone when [`Compute::Once`]. Computing stops when the run has computed many more
    /// than it used (a jittered sample grid would need one per step).
    #[inline]
    pub fn propagator(
        &mut self,
        sys: &System,
        region: &Region,
        y: &Vector,
        t: f64,
        h: f64,
        compute: Compute,
    ) -> Option<(&Propagator, f64)> {
        let (cache, once) = (compute == Compute::Cache, compute == Compute::Once);
        let hit = |(r, hh, _): &(Region, f64, Propagator)| r == region && same_step(*hh, h, t);
        let found = if self.entries.get(self.last).is_some_and(hit) {
            Some(self.last)
        } else {
            self.entries.iter().position(hit)
        };
        let k = match found {
            Some(k) => k,
            None => {
                if !(cache || once) || !self.viable() {
                    return None;
                }
                let e = expm(&sys.affine_matrix(region, y), h);
                self.computed += 1;
                let phi: Propagator = std::array::from_fn(|j| std::array::from_fn(|i| e[i][j]));
                if !cache {
                    self.once = phi;
                    return Some((&self.once, h));
                }
                if self.entries.len() < CACHE {
                    self.entries.push((*region, h, phi));
                    self.entries.len() - 1
                } else {
                    let k = self.next;
                    self.entries[k] = (*region, h, phi);
                    self.next = (k + 1) % CACHE;
                    k
                }
            }
        };
        self.last = k;
        Some((&self.entries[k].2, self.entries[k].1))
    }
}

/// z(t + h) = Φ z(t) for the six mechanical and electrical states; the
/// thermal state (absent wherever a region exists) is carried unchanged.
#[inline]
pub(crate) fn apply(phi: &Propagator, y: &Vector, t: f64) -> Vector {
    let q = step(phi, &[y[0], y[1], y[2], y[3], y[4], y[5]], t);
    let mut out = *y;
    out[..ROWS].copy_from_slice(&q);
    out
}

/// Repeated [`apply`] along sample times: the state at `times[j]`, reached
/// from `y` at `t` by steps of the same Φ, each starting at the previous
/// sample (at `t` for the first), is written channel by channel to
/// `out[c][at + j]`; the last is returned. The same products as `apply` one
/// step at a time, but the state stays in registers from step to step (a
/// state written to memory and read back as the next step's input stalls on
/// store forwarding), and the stores of one sample overlap the next step.
#[inline]
pub(crate) fn apply_along<const P: usize>(
    phi: &Propagator,
    y: &Vector,
    t: f64,
    times: &[f64],
    out: &mut [[f64; P]; ROWS],
    at: usize,
) -> Vector {
    let mut q = [y[0], y[1], y[2], y[3], y[4], y[5]];
    let mut tk = t;
    for (j, &tn) in times.iter().enumerate() {
        q = step(phi, &q, tk);
        for (c, v) in out.iter_mut().zip(q) {
            c[at + j] = v;
        }
        tk = tn;
    }
    [q[0], q[1], q[2], q[3], q[4], q[5], y[ROWS]]
}

/// Φ [q t 1]: row i is Σ_j Φ_ij z_j summed as a tree,
/// ((Φ_i0 q0 + Φ_i1 q1) + (Φ_i2 q2 + Φ_i3 q3)) + ((Φ_i4 q4 + Φ_i5 q5) + (Φ_i6 t + Φ_i7)):
/// the state of the step before enters through one product and three sums
/// (the t and 1 terms do not wait for it). The six rows advance together,
/// which the compiler turns into products of row pairs without shuffles.
#[inline(always)]
fn step(phi: &Propagator, q: &[f64; ROWS], t: f64) -> [f64; ROWS] {
    std::array::from_fn(|i| {
        let forced = phi[TIME][i] * t + phi[ONE][i];
        let p = |j: usize| phi[j][i] * q[j];
        ((p(0) + p(1)) + (p(2) + p(3))) + ((p(4) + p(5)) + forced)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stiff decay to a constant (ẋ0 = −500 x0 + 3) and an undamped oscillator
    /// forced by a ramp (ẍ1 + 4 x1 = t) against their closed forms.
    #[test]
    fn expm_matches_closed_forms_of_a_stiff_decay_and_a_ramp_forced_oscillator() {
        let mut m = [[0.0; AUG]; AUG];
        // ẋ0 = −500 x0 + 3 (stiff decay to 3/500), x1' = x2, x2' = −4 x1 + t.
        m[0][0] = -500.0;
        m[0][ONE] = 3.0;
        m[1][2] = 1.0;
        m[2][1] = -4.0;
        m[2][TIME] = 1.0;
        m[TIME][ONE] = 1.0;
        let h = 0.37;
        let e = expm(&m, h);
        let z0 = [1.0, 0.5, -0.25, 0.0, 0.0, 0.0, 0.2, 1.0];
        let z: Vec<f64> = (0..AUG).map(|i| (0..AUG).map(|j| e[i][j] * z0[j]).sum()).collect();
        let x0 = 3.0 / 500.0 + (1.0 - 3.0 / 500.0) * (-500.0 * h).exp();
        assert!((z[0] - x0).abs() < 1e-15, "{} vs {x0}", z[0]);
        // x1'' + 4 x1 = t: particular t/4, homogeneous A cos 2τ + B sin 2τ around t0 = 0.2.
        let (t0, t1) = (0.2f64, 0.2 + h);
        let a = 0.5 - t0 / 4.0;
        let b = (-0.25 - 0.25) / 2.0;
        let x1 = t1 / 4.0 + a * (2.0 * h).cos() + b * (2.0 * h).sin();
        let x2 = 0.25 - 2.0 * a * (2.0 * h).sin() + 2.0 * b * (2.0 * h).cos();
        // ‖M h‖ = 185 takes 9 squarings, each of which may double the rounding error.
        assert!((z[1] - x1).abs() < 1e-13 && (z[2] - x2).abs() < 1e-13, "{z:?} vs {x1} {x2}");
        assert_eq!((z[TIME], z[ONE]), (t1, 1.0));
    }
}
