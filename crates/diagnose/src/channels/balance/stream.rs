//! The balance rows of channels that arrive one sample at a time (a
//! sensor grid's filters): [`super::rows`]' running box sums kept over a
//! ring of the last samples instead of stored channels.

use super::rows::row_at;
use super::{EVENT_ROWS, Row};

/// [`super::rows`]' rows of `L` lanes that read one rotor angle φ1 (the
/// recorded one) and each its own motor angle φ2 and force, handed over
/// sample by sample ([`StreamRows::push`]; the encoder coupling's grid
/// points, whose φ2 and force are filter outputs, `crate::structure`), and
/// their event-locked rows.
///
/// Every lane performs the same operations in the same order as
/// `rows_lanes` does on the stored channels (the box sums B(s) started as
/// the sum of the first w samples, then one sample in and one out; their
/// sum over a boundary's w starts; the row's differences a window apart),
/// and the event-locked rows are [`row_at`] of the same samples, so each
/// lane's rows and events are those of its stored channels to the bit. What
/// changes is where the samples are read from: a ring of the last
/// (EVENT_ROWS + 1)·w + 1 motor angles and forces per lane (the rows read
/// 2w back, an event's rows 3w back), so a grid point's channels are
/// never written out whole and read back (20 000 samples × 2 channels × 5
/// lanes per run and natural frequency).
pub struct StreamRows<'a, const L: usize> {
    phi1: &'a [f64],
    dt: f64,
    w: usize,
    r_m: f64,
    /// The first box's start, `first + 1 − w` with the first boundary
    /// `first = max(from, w)`.
    s0: usize,
    /// The next boundary whose row is summed.
    b: usize,
    /// Samples pushed so far.
    k: usize,
    ring_len: usize,
    /// The motor angle and the force of the last `ring_len` samples, at
    /// `k % ring_len`.
    phi2: Vec<[f64; L]>,
    f: Vec<[f64; L]>,
    /// The running box sums and their sum over the boundary's starts.
    b_tw: [f64; L],
    b_f: [f64; L],
    t_tw: [f64; L],
    t_f: [f64; L],
    out: [Vec<Row>; L],
    /// The transitions (kind, sample) and, per transition in their order,
    /// each lane's event-locked rows once its window has passed.
    transitions: &'a [(usize, usize)],
    events: Vec<Option<[Vec<Row>; L]>>,
    /// The transitions' indices by sample, and the next one whose window
    /// has not passed.
    by_sample: Vec<usize>,
    next_event: usize,
}

impl<'a, const L: usize> StreamRows<'a, L> {
    /// Rows every `w` samples from `from` on, of a run whose rotor angle is
    /// `phi1` (the run's length: later samples are ignored), with the
    /// event-locked rows of `transitions`.
    pub fn new(phi1: &'a [f64], dt: f64, w: usize, r_m: f64, from: usize, transitions: &'a [(usize, usize)]) -> Self {
        let first = from.max(w);
        let ring_len = (EVENT_ROWS + 1) * w + 1;
        StreamRows {
            phi1,
            dt,
            w,
            r_m,
            s0: first + 1 - w,
            b: first,
            k: 0,
            ring_len,
            phi2: vec![[0.0; L]; ring_len],
            f: vec![[0.0; L]; ring_len],
            b_tw: [0.0; L],
            b_f: [0.0; L],
            t_tw: [0.0; L],
            t_f: [0.0; L],
            out: std::array::from_fn(|_| Vec::with_capacity(phi1.len().saturating_sub(first) / w + 1)),
            transitions,
            events: vec![None; transitions.len()],
            by_sample: {
                let mut by: Vec<usize> = (0..transitions.len()).collect();
                by.sort_by_key(|&i| transitions[i].1);
                by
            },
            next_event: 0,
        }
    }

    /// The next sample's (φ2, force) of every lane, rad and N.
    #[inline]
    pub fn push(&mut self, sample: [(f64, f64); L]) {
        let (k, w) = (self.k, self.w);
        if k >= self.phi1.len() {
            return;
        }
        self.k += 1;
        let at = |j: usize| j % self.ring_len;
        let pk = at(k);
        for l in 0..L {
            self.phi2[pk][l] = sample[l].0;
            self.f[pk][l] = sample[l].1;
        }
        let phi1 = self.phi1;
        if k + 1 == self.s0 + w {
            // The first boxes, B(s0) = Σ x[s0..s0+w] (rows_lanes' sums).
            let s0 = self.s0;
            self.b_tw = std::array::from_fn(|l| (s0..s0 + w).map(|j| self.phi2[at(j)][l] - phi1[j]).sum::<f64>());
            self.b_f = std::array::from_fn(|l| (s0..s0 + w).map(|j| self.f[at(j)][l]).sum::<f64>());
        } else if k >= self.s0 + w {
            let s = k - w;
            let ps = at(s);
            for l in 0..L {
                self.t_tw[l] += self.b_tw[l];
                self.b_tw[l] += (self.phi2[pk][l] - phi1[k]) - (self.phi2[ps][l] - phi1[s]);
                self.t_f[l] += self.b_f[l];
                self.b_f[l] += self.f[pk][l] - self.f[ps][l];
            }
            if s == self.b {
                self.row(k);
            }
        }
        while let Some(&i) = self.by_sample.get(self.next_event) {
            let e = self.transitions[i].1;
            if e + EVENT_ROWS * w > k {
                break;
            }
            if e + EVENT_ROWS * w == k && e >= w {
                self.events[i] = Some(self.event_rows(e));
            }
            self.next_event += 1;
        }
    }

    /// The row of boundary b = k − w, its last sample k just pushed.
    fn row(&mut self, k: usize) {
        let (w, b) = (self.w, self.b);
        let big_t = w as f64 * self.dt;
        let s_k = (w * w) as f64;
        let phi1 = self.phi1;
        let (p_prev, p_b, p_next) = ((b - w) % self.ring_len, b % self.ring_len, k % self.ring_len);
        for l in 0..L {
            let tw = |p: usize, j: usize| self.phi2[p][l] - phi1[j];
            let w1_prev = (phi1[b] - phi1[b - w]) / big_t;
            let w1_next = (phi1[b + w] - phi1[b]) / big_t;
            let tw_prev = (tw(p_b, b) - tw(p_prev, b - w)) / big_t;
            let tw_next = (tw(p_next, k) - tw(p_b, b)) / big_t;
            self.out[l].push((
                [
                    (w1_next - w1_prev) / big_t,
                    self.t_tw[l] / s_k,
                    0.5 * (tw_prev + tw_next),
                    0.5 * (w1_prev + w1_next),
                    1.0,
                ],
                self.r_m * self.t_f[l] / s_k,
            ));
        }
        (self.t_tw, self.t_f) = ([0.0; L], [0.0; L]);
        self.b += w;
    }

    /// Each lane's event-locked rows of the transition at sample `e`,
    /// whose window [e − w, e + EVENT_ROWS·w] ends at the sample just
    /// pushed: [`row_at`] of the window's samples, copied out of the ring.
    fn event_rows(&self, e: usize) -> [Vec<Row>; L] {
        let w = self.w;
        let (start, end) = (e - w, e + EVENT_ROWS * w);
        let phi1 = &self.phi1[start..=end];
        std::array::from_fn(|l| {
            let (phi2, f): (Vec<f64>, Vec<f64>) = (start..=end)
                .map(|j| {
                    let p = j % self.ring_len;
                    (self.phi2[p][l], self.f[p][l])
                })
                .unzip();
            (0..EVENT_ROWS)
                .map(|j| row_at(phi1, &phi2, &f, self.dt, w, self.r_m, w + j * w).expect("the window holds the rows"))
                .collect()
        })
    }

    /// Each lane's rows and, per transition in their order, its
    /// event-locked rows (`None` where the record ends before its window
    /// does, or the transition comes before sample w).
    pub fn finish(self) -> ([Vec<Row>; L], Vec<Option<[Vec<Row>; L]>>) {
        (self.out, self.events)
    }
}
