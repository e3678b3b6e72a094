//! Teacher-forced drive channel: the PI speed loop of the rig model
//! (DriveParams: V = clamp(kp·e + ki·∫e, ±Vmax), e = Ω_ref − Ω2) driven by the
//! MEASURED motor speed predicts the recorded armature voltage. The baseline
//! saturates at the campaign's supply voltage; the `drive_voltage_limit`
//! candidate at a fitted Vmax. The PI gains are nuisance parameters fitted
//! here on the same data for both, so the comparison isolates the limit.
//! (The integral is driven by the measured error, so the prediction is a
//! one-step filter of the data, not a free-run simulation.)
//!
//! The law is rig-model's drive (its docs, "Drive": the thesis names the PI
//! loop in §4.1 and writes no equation for it), with back-calculation
//! anti-windup (`visit`). At a trial limit of the drive-limit search
//! (`drive/limit.rs`) the gains are the voltage RSS's minimum, found by
//! Levenberg–Marquardt on the clamped recursion's exact forward
//! sensitivities with a stated stop rule (`drive/gains.rs`); the baseline's gains
//! at the supply by [`fit_gains`].

use crate::prepare::RunSignals;
use rig_estimate::linear::Normal;
use rig_types::order::{from_total_key_u64, total_key_u64};

mod gains;
mod limit;

pub use limit::{fit_limit, fit_limit_gains};

/// The JSON key [`fit_limit`]'s limit is reported under (the drive term's
/// one parameter, [`crate::effects::Term::DriveLimit`]).
pub const LIMIT_PARAM: &str = "limit_v";

/// PI gains and limit of the teacher-forced drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pi {
    pub kp_v_s_rad: f64,
    pub ki_v_rad: f64,
    pub limit_v: f64,
}

/// What the PI recursion reads of one run, computed once per run (cached in
/// [`RunSignals::drive`] and shared by every fold, trial limit and selection
/// step): the error e = Ω_ref(t) − Ω2 of every sample (the measured speed
/// drives the loop, so e depends only on the recording) and the sample
/// steps; and the recursion's closed form where the clamp never acts.
///
/// # The closed form of an unclamped run
///
/// Where no sample of a run clamps, the back-calculation term is ±0 at every
/// sample, so ∫e is the running sum I₀(k) = Σ_{j<k} e_j·dt_j, the same for
/// every gain pair (computed here by the recursion's own additions, so the
/// same bits), and V̂ = kp·e + ki·I₀ is linear in the gains. Whether a run
/// clamps is then a question about the points (e_k, I₀(k)) alone: the largest
/// |kp·e + ki·I₀| over them is reached at a vertex of their convex hull
/// (`hull`, a few dozen of 20 000 points), so one look at the vertices
/// decides it, with a margin of 10⁻⁹ of the terms' scale for rounding (a run
/// within it of the limit is treated as clamping: the recursion, exact, runs
/// then). The hull is built only when a cheaper bound cannot decide
/// ([`Prepared::idle`]): its sort of 20 000 keys was a third of this
/// preparation's CPU, and most questions are asked far below the limit. For an unclamped run a pass's normal equations are sums of e², e·I₀,
/// I₀², e·V, I₀·V over the samples the fit keeps (|V| < 0.999·Vmax), which
/// are the first samples in the order of |V|: prefix sums in that order
/// (`cum`) give them for any limit, and its RSS is the quadratic form of the
/// totals. So a pass costs a run O(hull) instead of O(samples) unless the
/// run clamps. Not bit-identical to the per-sample sums (other order of the
/// same additions; the RSS as a quadratic form cancels ≈ 10⁻¹⁰ of it).
#[derive(Debug, Clone)]
pub struct Prepared {
    e_rad_s: Vec<f64>,
    dt_s: Vec<f64>,
    /// The convex hull's vertices of the points (e_k, I₀(k)), built on the
    /// first question the bound |kp|·e_max + |ki|·i_max cannot answer
    /// ([`Prepared::hull`]).
    hull: std::sync::OnceLock<Vec<[f64; 2]>>,
    /// max |e|, max |I₀|: the scale of the rounding margin.
    e_max: f64,
    i_max: f64,
    /// |V| in ascending order, and the prefix sums in that order of
    /// (e², e·I₀, I₀², e·V, I₀·V, V²): `cum[m]` sums the first m samples.
    v_abs_sorted: Vec<f64>,
    cum: Vec<[f64; 6]>,
}

impl Prepared {
    /// The error and the steps alone: what [`visit`] reads (no closed form).
    fn bare(s: &RunSignals) -> Self {
        Prepared {
            e_rad_s: s.time_s.iter().zip(&s.motor_speed_rad_s).map(|(&t, &w)| s.reference_rad_s(t) - w).collect(),
            dt_s: s.time_s.windows(2).map(|w| w[1] - w[0]).collect(),
            hull: std::sync::OnceLock::new(),
            e_max: 0.0,
            i_max: 0.0,
            v_abs_sorted: Vec::new(),
            cum: vec![[0.0; 6]],
        }
    }

    fn of(s: &RunSignals) -> Self {
        let Prepared { e_rad_s, dt_s, .. } = Prepared::bare(s);
        let n = e_rad_s.len();
        assert_eq!(s.voltage_v.len(), n, "run {}: a voltage sample per time sample", s.id);
        let i0_rad = running_integral(&e_rad_s, &dt_s);
        let e_max = e_rad_s.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let i_max = i0_rad.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        // Ascending |V| (total_cmp), ties by index: one order whichever stable
        // sort (the prefix sums' bits depend on it); a radix sort of the
        // integer keys is linear in n.
        let keys: Vec<u64> = s.voltage_v.iter().map(|v| total_key_u64(v.abs())).collect();
        let order = rig_types::order::argsort_u64(&keys);
        let v_abs_sorted = order.iter().map(|&k| s.voltage_v[k].abs()).collect();
        let mut cum = Vec::with_capacity(n + 1);
        let mut acc = [0.0; 6];
        cum.push(acc);
        for &k in &order {
            let (e, i, v) = (e_rad_s[k], i0_rad[k], s.voltage_v[k]);
            for (a, x) in acc.iter_mut().zip([e * e, e * i, i * i, e * v, i * v, v * v]) {
                *a += x;
            }
            cum.push(acc);
        }
        Prepared { e_rad_s, dt_s, hull: std::sync::OnceLock::new(), e_max, i_max, v_abs_sorted, cum }
    }

    /// The convex hull's vertices of the points (e_k, I₀(k)), built on first
    /// use (I₀ by the same additions as [`Prepared::of`]'s, so the same points).
    fn hull(&self) -> &[[f64; 2]] {
        self.hull.get_or_init(|| {
            let i0_rad = running_integral(&self.e_rad_s, &self.dt_s);
            let mut pts: Vec<[f64; 2]> = self.e_rad_s.iter().zip(&i0_rad).map(|(&e, &i)| [e, i]).collect();
            convex_hull(&mut pts)
        })
    }

    /// The largest |kp·e + ki·I₀| over the run (at the hull's vertices) and
    /// the rounding margin of its terms.
    fn max_abs_unclamped(&self, pi: &Pi) -> (f64, f64) {
        let m = self.hull().iter().fold(0.0f64, |m, p| m.max((pi.kp_v_s_rad * p[0] + pi.ki_v_rad * p[1]).abs()));
        (m, 1e-9 * (pi.kp_v_s_rad.abs() * self.e_max + pi.ki_v_rad.abs() * self.i_max))
    }

    /// An upper bound of [`Prepared::max_abs_unclamped`]'s maximum without
    /// the hull, in floating point and not only in exact arithmetic:
    /// B = fl(fl(|kp|·e_max) + fl(|ki|·i_max)). Every hull vertex (x, y) is a
    /// sample, so |x| ≤ e_max and |y| ≤ i_max; rounding to nearest is
    /// monotone and odd, so |fl(kp·x)| = fl(|kp|·|x|) ≤ fl(|kp|·e_max), the
    /// same for ki·y, and |fl(a + b)| ≤ fl(|a| + |b|) ≤ B (the triangle
    /// inequality under a monotone rounding). NaN when a term is (0·∞).
    fn max_abs_bound(&self, pi: &Pi) -> f64 {
        pi.kp_v_s_rad.abs() * self.e_max + pi.ki_v_rad.abs() * self.i_max
    }

    /// Whether no sample of the run clamps under `pi` (false when in doubt).
    ///
    /// The hull's maximum m ≤ B ([`Prepared::max_abs_bound`]) and the margin
    /// is the same, so B + tol < limit implies m + tol < limit (a rounded
    /// sum is monotone in each term): where the bound decides, the answer
    /// is the hull's, and the hull is built only where it does not.
    fn idle(&self, pi: &Pi) -> bool {
        if !(pi.kp_v_s_rad.is_finite() && pi.ki_v_rad.is_finite()) {
            return false;
        }
        // The margin is the one `max_abs_unclamped` returns: the same expression.
        let bound = self.max_abs_bound(pi);
        if bound + 1e-9 * bound < pi.limit_v {
            return true;
        }
        self.idle_by_hull(pi)
    }

    /// [`Prepared::idle`] by the hull alone.
    fn idle_by_hull(&self, pi: &Pi) -> bool {
        if !(pi.kp_v_s_rad.is_finite() && pi.ki_v_rad.is_finite()) {
            return false;
        }
        let (m, tol) = self.max_abs_unclamped(pi);
        m + tol < pi.limit_v
    }

    /// The prefix sums of the samples with |V| < 0.999·`limit_v`.
    fn kept_sums(&self, limit_v: f64) -> &[f64; 6] {
        &self.cum[self.v_abs_sorted.partition_point(|&v| v < 0.999 * limit_v)]
    }
}

/// I₀(k) = Σ_{j<k} e_j·dt_j: the recursion's additions with the clamp idle
/// ([`visit`]: rate = e).
fn running_integral(e_rad_s: &[f64], dt_s: &[f64]) -> Vec<f64> {
    let n = e_rad_s.len();
    let mut i0_rad = Vec::with_capacity(n);
    let mut i_acc = 0.0;
    for k in 0..n {
        i0_rad.push(i_acc);
        if k + 1 < n {
            i_acc += e_rad_s[k] * dt_s[k];
        }
    }
    i0_rad
}

/// Andrew's monotone chain: the convex hull's vertices of `pts` (sorted in
/// place by x, then y, in total_cmp's order: as (x, y) pairs of
/// [`rig_types::order`] keys, which sort as the comparator does and give
/// the same sequence, since equal keys are equal points; the comparator
/// sort of 20 000 points per run was 1.2 % of a ladder rung's CPU in
/// `perf`, issue 23).
fn convex_hull(pts: &mut [[f64; 2]]) -> Vec<[f64; 2]> {
    let mut keys: Vec<u128> =
        pts.iter().map(|p| (u128::from(total_key_u64(p[0])) << 64) | u128::from(total_key_u64(p[1]))).collect();
    keys.sort_unstable();
    for (p, k) in pts.iter_mut().zip(keys) {
        *p = [from_total_key_u64((k >> 64) as u64), from_total_key_u64(k as u64)];
    }
    if pts.len() < 3 {
        return pts.to_vec();
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut h: Vec<[f64; 2]> = Vec::with_capacity(64);
    for pass in 0..2 {
        let start = h.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> =
            if pass == 0 { Box::new(pts.iter()) } else { Box::new(pts.iter().rev()) };
        for &p in iter {
            while h.len() >= start + 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
                h.pop();
            }
            h.push(p);
        }
        h.pop();
    }
    h
}

/// A run as the fits read it: its [`Prepared`] closed form (built on first
/// use) with the recorded voltage and its noise.
struct Recording<'a> {
    p: &'a Prepared,
    voltage_v: &'a [f64],
    voltage_noise_v: f64,
}

impl<'a> Recording<'a> {
    fn of(s: &'a RunSignals) -> Self {
        Recording {
            p: s.drive.get_or_init(|| Prepared::of(s)),
            voltage_v: &s.voltage_v,
            voltage_noise_v: s.voltage_noise_v,
        }
    }

    fn all(runs: &[&'a RunSignals]) -> Vec<Self> {
        runs.iter().map(|s| Recording::of(s)).collect()
    }
}

/// Visits every sample of the teacher-forced PI loop with (k, e, V̂, ∫e,
/// clamped): no allocation, so the fits below can call it thousands of times.
/// Anti-windup by back-calculation exactly as rig-model's drive:
/// d(∫e)/dt = e + (V − V_raw)/(ki·T_t), T_t = rig_model::ANTI_WINDUP_TRACKING_S
/// (explicit Euler at the sample step; dt/T_t = 0.2 at 500 Hz is stable).
/// Where the clamp is idle (V = V_raw, finite) the back-calculation term is
/// exactly ±0, so the rate is e without the division: the same ∫e to the bit
/// (∫e starts at +0 and a sum of finite terms is −0 only if both are, so the
/// sign of a zero rate cannot reach it), and the loop's serial chain is one
/// addition per sample instead of a division and four more operations.
#[inline]
fn visit(pi: &Pi, r: &Recording, mut f: impl FnMut(usize, f64, f64, f64, bool)) {
    let (e_rad_s, dt_s) = (&r.p.e_rad_s, &r.p.dt_s);
    let n = e_rad_s.len();
    let mut i_acc = 0.0;
    let tt = rig_model::ANTI_WINDUP_TRACKING_S;
    let no_windup = pi.ki_v_rad.abs() < 1e-9;
    for k in 0..n {
        let e = e_rad_s[k];
        let u = pi.kp_v_s_rad * e + pi.ki_v_rad * i_acc;
        let clamped = u.clamp(-pi.limit_v, pi.limit_v);
        f(k, e, clamped, i_acc, clamped != u);
        if k + 1 < n {
            let rate =
                if no_windup || (clamped == u && u.is_finite()) { e } else { e + (clamped - u) / (pi.ki_v_rad * tt) };
            i_acc += rate * dt_s[k];
        }
    }
}

/// Predicted voltage, the PI integral ∫e and whether the clamp was active,
/// sample by sample (see [`visit`] for the anti-windup).
pub fn predict_voltage(pi: &Pi, s: &RunSignals) -> (Vec<f64>, Vec<f64>, Vec<bool>) {
    let n = s.time_s.len();
    let p = Prepared::bare(s);
    let r = Recording { p: &p, voltage_v: &s.voltage_v, voltage_noise_v: s.voltage_noise_v };
    let mut v = Vec::with_capacity(n);
    let mut integ = Vec::with_capacity(n);
    let mut sat = Vec::with_capacity(n);
    visit(pi, &r, |_, _, vk, ik, sk| {
        v.push(vk);
        integ.push(ik);
        sat.push(sk);
    });
    (v, integ, sat)
}

/// Sum of squared voltage errors of one run, V.
fn run_sse(pi: &Pi, r: &Recording) -> f64 {
    let mut sse = 0.0;
    visit(pi, r, |k, _, vk, _, _| sse += (vk - r.voltage_v[k]).powi(2));
    sse
}

/// Voltage RSS in noise units (each run weighted by 1/σ_V²) and sample count.
pub fn voltage_rss(pi: &Pi, runs: &[&RunSignals]) -> (f64, usize) {
    rss_of(pi, &Recording::all(runs))
}

/// [`voltage_rss`] of recordings already prepared: a run the gains do not
/// clamp by its closed form ([`Prepared`]), the others by the recursion.
fn rss_of(pi: &Pi, runs: &[Recording]) -> (f64, usize) {
    let mut rss = 0.0;
    let mut n = 0;
    for r in runs {
        let w = 1.0 / r.voltage_noise_v.max(1e-6).powi(2);
        rss += w * if r.p.idle(pi) { idle_sse(pi, r.p.cum.last().expect("cum[0]")) } else { run_sse(pi, r) };
        n += r.p.e_rad_s.len();
    }
    (rss, n)
}

/// Σ (kp·e + ki·I₀ − V)² from the sums (e², e·I₀, I₀², e·V, I₀·V, V²): the
/// SSE of a run the gains do not clamp, never below 0.
fn idle_sse(pi: &Pi, s: &[f64; 6]) -> f64 {
    let (kp, ki) = (pi.kp_v_s_rad, pi.ki_v_rad);
    (kp * kp * s[0] + 2.0 * kp * ki * s[1] + ki * ki * s[2] - 2.0 * (kp * s[3] + ki * s[4]) + s[5]).max(0.0)
}

/// Fits kp, ki for a fixed limit: alternate (clamp pattern and integral from
/// the current gains) → (linear least squares on the unclamped samples),
/// up to eight passes. The baseline drive's gains, at the supply: where
/// those gains clamp no run and no sample reaches 0.999 of the supply (every
/// campaign but a drive clipped near the supply), the first pass is the
/// least squares of a model linear in the gains, the second confirms it, and
/// that is the RSS minimum `drive/gains.rs` would reach. Not a descent of the RSS
/// where the clamp acts (docs/findings.md, issue 23): the drive-limit
/// search fits its gains by `drive/gains.rs` instead.
pub fn fit_gains(runs: &[&RunSignals], limit_v: f64) -> Option<Pi> {
    fit_gains_from(&Recording::all(runs), limit_v, None)
}

/// [`fit_gains`] started from `start`'s gains; `None` starts unclamped from zero.
fn fit_gains_from(runs: &[Recording], limit_v: f64, start: Option<&Pi>) -> Option<Pi> {
    let mut pi = match start {
        Some(p) => Pi { limit_v, ..*p },
        None => Pi { kp_v_s_rad: 0.0, ki_v_rad: 0.0, limit_v: f64::INFINITY },
    };
    for it in 0..8 {
        // The normal equations of (kp, ki) on the unclamped samples whose
        // |V| < 0.999·Vmax, each run weighted by 1/σ_V²: a run the gains do
        // not clamp from its prefix sums ([`Prepared`]), the others sample by sample.
        let mut sums = [0.0; 5];
        for r in runs {
            let w2 = 1.0 / r.voltage_noise_v.max(1e-6).powi(2);
            let mut run_sums = [0.0; 5];
            if r.p.idle(&pi) {
                run_sums.copy_from_slice(&r.p.kept_sums(limit_v)[..5]);
            } else {
                visit(&pi, r, |k, e, _, integ, sat| {
                    let v = r.voltage_v[k];
                    if !(sat || v.abs() >= 0.999 * limit_v) {
                        for (a, x) in run_sums.iter_mut().zip([e * e, e * integ, integ * integ, e * v, integ * v]) {
                            *a += x;
                        }
                    }
                });
            }
            for (a, x) in sums.iter_mut().zip(run_sums) {
                *a += w2 * x;
            }
        }
        let p = Normal::from_row_major(2, &[sums[0], sums[1], sums[1], sums[2]], vec![sums[3], sums[4]]).solve()?;
        let next = Pi { kp_v_s_rad: p[0], ki_v_rad: p[1], limit_v };
        let done = it > 0 && (next.kp_v_s_rad - pi.kp_v_s_rad).abs() < 1e-9 * (1.0 + pi.kp_v_s_rad.abs());
        pi = next;
        if done {
            break;
        }
    }
    Some(pi)
}

/// Relative RMS voltage error of one run: sqrt(mean((V̂ − V)²)) / V_supply.
pub fn relative_voltage_error(pi: &Pi, s: &RunSignals, supply_v: f64) -> f64 {
    let ms = run_sse(pi, &Recording::of(s)) / s.time_s.len().max(1) as f64;
    ms.sqrt() / supply_v
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Runs whose voltage is the PI of `truth` (limit included) on a motor speed
    /// that lags the ramp and wobbles, plus a small deterministic noise.
    pub(crate) fn runs(truth: Pi, setpoints_rad_s: &[f64]) -> Vec<RunSignals> {
        setpoints_rad_s
            .iter()
            .enumerate()
            .map(|(r, &sp)| {
                let time_s: Vec<f64> = (0..4000).map(|k| k as f64 * 0.002).collect();
                let motor_speed_rad_s: Vec<f64> = time_s
                    .iter()
                    .map(|&t| {
                        sp * (1.0 - (-t / 0.8).exp()) * (1.0 + 0.1 * (2.0 * std::f64::consts::PI * 0.7 * t).sin())
                    })
                    .collect();
                let mut s = RunSignals {
                    id: format!("r{r}"),
                    fold: r,
                    setpoint_rad_s: sp,
                    normal_force_n: 10.0,
                    ramp_s: 2.0,
                    time_s,
                    rotor_angle_rad: vec![],
                    rotor_speed_rad_s: vec![],
                    motor_angle_rad: vec![],
                    motor_speed_rad_s,
                    voltage_v: vec![],
                    friction_force_n: vec![],
                    slip_idx: vec![],
                    mu_obs: vec![],
                    force_noise_n: 0.0,
                    voltage_noise_v: 0.01,
                    steady_from: 0,
                    drive: Default::default(),
                };
                let (v, _, _) = predict_voltage(&truth, &s);
                s.voltage_v =
                    v.iter().enumerate().map(|(k, v)| v + 0.01 * ((k * 7919 % 101) as f64 / 50.0 - 1.0)).collect();
                s
            })
            .collect()
    }

    /// The recursion with the recording's error and steps prepared once and
    /// the division skipped where the clamp is idle gives, sample by sample,
    /// the bits of the per-sample formula (e from the reference at t, the
    /// back-calculation always divided), clamped stretches included.
    #[test]
    fn the_prepared_recursion_is_the_per_sample_formula_bit_for_bit() {
        let limited = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 3.0]);
        for pi in
            [Pi { kp_v_s_rad: 2.5, ki_v_rad: 7.0, limit_v: 0.1 }, Pi { kp_v_s_rad: 1.0, ki_v_rad: 0.0, limit_v: 0.05 }]
        {
            let mut clamped = 0;
            for s in &limited {
                let mut got = Vec::new();
                visit(&pi, &Recording::of(s), |_, e, v, i, sat| got.push((e, v, i, sat)));
                let mut i_acc = 0.0;
                for (k, g) in got.iter().enumerate() {
                    let e = s.reference_rad_s(s.time_s[k]) - s.motor_speed_rad_s[k];
                    let u = pi.kp_v_s_rad * e + pi.ki_v_rad * i_acc;
                    let v = u.clamp(-pi.limit_v, pi.limit_v);
                    assert_eq!(
                        (g.0.to_bits(), g.1.to_bits(), g.2.to_bits(), g.3),
                        (e.to_bits(), v.to_bits(), i_acc.to_bits(), v != u),
                        "{k}"
                    );
                    clamped += usize::from(v != u);
                    if k + 1 < s.time_s.len() {
                        let tt = rig_model::ANTI_WINDUP_TRACKING_S;
                        let rate = if pi.ki_v_rad.abs() < 1e-9 { e } else { e + (v - u) / (pi.ki_v_rad * tt) };
                        i_acc += rate * (s.time_s[k + 1] - s.time_s[k]);
                    }
                }
            }
            assert!(clamped > 100, "{clamped} clamped samples");
        }
    }

    /// The closed form of an unclamped run ([`Prepared`]) is the recursion:
    /// where the hull says no sample clamps, none does, and the kept samples'
    /// normal-equation sums and the SSE equal the per-sample ones to 10⁻⁹;
    /// where a sample clamps, the hull says so.
    #[test]
    fn the_closed_form_of_an_unclamped_run_is_the_recursion() {
        let rs = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 2.0, 3.0]);
        let (mut idle_seen, mut clamped_seen) = (0, 0);
        for s in &rs {
            let r = Recording::of(s);
            for (kp, ki, limit_v) in
                [(2.0, 10.0, 24.0), (1.5, 8.0, 6.0), (2.0, 10.0, 5.0), (2.5, 12.0, 3.0), (0.0, 0.0, f64::INFINITY)]
            {
                let pi = Pi { kp_v_s_rad: kp, ki_v_rad: ki, limit_v };
                let (mut sums, mut sse, mut any_clamped) = ([0.0; 5], 0.0, false);
                visit(&pi, &r, |k, e, v_hat, i, sat| {
                    let v = r.voltage_v[k];
                    any_clamped |= sat;
                    sse += (v_hat - v).powi(2);
                    if !(sat || v.abs() >= 0.999 * limit_v) {
                        for (a, x) in sums.iter_mut().zip([e * e, e * i, i * i, e * v, i * v]) {
                            *a += x;
                        }
                    }
                });
                if !r.p.idle(&pi) {
                    clamped_seen += usize::from(any_clamped);
                    continue;
                }
                assert!(!any_clamped, "{pi:?}: a sample clamps where the hull says none does");
                idle_seen += 1;
                let closed = r.p.kept_sums(limit_v);
                for (a, b) in sums.iter().zip(closed) {
                    assert!((a - b).abs() <= 1e-9 * a.abs().max(1e-300), "{pi:?}: {a} vs {b}");
                }
                let q = idle_sse(&pi, r.p.cum.last().expect("cum"));
                assert!((q - sse).abs() <= 1e-9 * r.p.cum.last().expect("cum")[5], "{pi:?}: {q} vs {sse}");
            }
        }
        assert!(idle_seen >= 6 && clamped_seen >= 3, "{idle_seen} idle, {clamped_seen} clamped");
    }

    /// The bound without the hull decides `idle` as the hull does: over
    /// gains of both signs and scales on clamping and unclamped synthetic
    /// runs, the bound is never below the hull's maximum (to the bit, not
    /// within a margin), and at limits around both the bound and the hull's
    /// maximum (a few ulps to 10⁻⁶ either side) `idle` and the hull alone
    /// answer alike; a run whose every question the bound answers builds no hull.
    #[test]
    fn the_bound_without_the_hull_decides_idle_as_the_hull_does() {
        let mut rs = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 3.0]);
        rs.extend(runs(Pi { kp_v_s_rad: 1.5, ki_v_rad: 6.0, limit_v: 24.0 }, &[2.0]));
        let (mut by_bound, mut by_hull_only, mut seed) = (0, 0, 11u64);
        for s in &rs {
            let fresh = Prepared::of(s);
            assert!(fresh.idle(&Pi { kp_v_s_rad: 1e-3, ki_v_rad: 1e-3, limit_v: 1e6 }));
            assert!(fresh.hull.get().is_none(), "{}: hull built where the bound decides", s.id);
            let p = Recording::of(s).p;
            for _ in 0..400 {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let u = |sh: u32| ((seed >> sh) & 0xffff) as f64 / 65535.0;
                let kp = (u(8) - 0.5) * 10f64.powf(4.0 * u(24) - 2.0);
                let ki = (u(40) - 0.3) * 10f64.powf(4.0 * u(48) - 2.0);
                let pi = Pi { kp_v_s_rad: kp, ki_v_rad: ki, limit_v: 1.0 };
                let (m, tol) = p.max_abs_unclamped(&pi);
                let bound = p.max_abs_bound(&pi);
                assert!(m <= bound, "{pi:?}: hull max {m} above the bound {bound}");
                for base in [m + tol, bound + tol] {
                    for rel in [-1e-6, -1e-12, -1e-15, 0.0, 1e-15, 1e-12, 1e-6, 0.5] {
                        for limit_v in [base * (1.0 + rel), f64::from_bits(base.to_bits() + 1), base] {
                            let pi = Pi { limit_v, ..pi };
                            let fast = p.idle(&pi);
                            assert_eq!(fast, p.idle_by_hull(&pi), "{pi:?}");
                            by_bound += usize::from(bound + 1e-9 * bound < limit_v);
                            by_hull_only += usize::from(fast && bound + 1e-9 * bound >= limit_v);
                        }
                    }
                }
            }
        }
        assert!(by_bound > 1000 && by_hull_only > 1000, "{by_bound} by the bound, {by_hull_only} by the hull alone");
    }

    /// The hull's key sort ([`rig_types::order`]'s keys of (x, y)) is the
    /// comparator sort, point for point, signed zeros, NaNs, infinities and
    /// repeated points included.
    #[test]
    fn the_hulls_key_sort_is_the_comparator_sort() {
        let mut xs = vec![0.0, -0.0, 1.0, -1.0, f64::INFINITY, f64::NEG_INFINITY, f64::NAN, -f64::NAN];
        let mut seed = 7u64;
        for _ in 0..2000 {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            xs.push(f64::from_bits(seed));
            xs.push((seed >> 40) as f64 * if seed & 1 == 0 { 1e-3 } else { -1e-3 });
        }
        // Points with repeated coordinates: the same sequence as the comparator's sort.
        let mut pts: Vec<[f64; 2]> = xs.iter().zip(xs.iter().rev()).map(|(&x, &y)| [(x * 4.0).round(), y]).collect();
        pts.extend(pts.clone());
        let mut by_cmp = pts.clone();
        by_cmp.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        convex_hull(&mut pts);
        let bits = |v: &[[f64; 2]]| v.iter().map(|p| p.map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&pts), bits(&by_cmp));
    }
}
