#!/usr/bin/env python3
"""Independent check of rig_slider's `rate_state_slip` integration (issue 26).

The spring-slider m x'' = k (V t - x) - m g mu(v, theta) with rate-and-state
friction and Ruina's slip law (Ruina, J. Geophys. Res. 88, 10359, 1983),
written from the crate docs of `rig_slider::slip`, not from its Rust code:

    mu = a asinh(v / (2 v*) exp(psi / a)),  psi = mu0 + b ln(v* theta / Dc),
    d theta/dt = -(v theta / Dc) ln(v theta / Dc),   v* = 100 um/s,

integrated by scipy's Radau (rtol 1e-9, atol 1e-12 on the scaled states)
in (spring extension phi = V t - x, slider speed v, ln theta), from the
crate's start: slider at rest, the spring preloaded to mu0 m g, theta = Dc/V.

At k2254-v42 (k = 2254 N/m, V = 42 um/s, m = 30.7 g) on the run's Hopf start
(a = 0.035, Dc = 1 um) with the quasi-static critical stiffness
k_c = m g (b - a)/Dc at RATIO x k, it prints, over the second half of
DURATION s sampled at 2 kHz: the mean spacing of the force's maxima (s), the
force's mean and its range (max - min, F/(m g)), and the fraction of samples
with v < V/2 ("stuck"). `crates/slider/src/slip.rs`'s test
`the_integration_agrees_with_scipy_radau` compares the crate's run of the
same case with the numbers printed here.

Usage: scripts/slip_law_scipy.py [RATIO ...]   (default 1.02 1.04)
"""
import sys

import numpy as np
from scipy.integrate import solve_ivp

M, G, K, V = 0.0307, 9.81, 2254.0, 42e-6
A, DC, VREF, DURATION, FS = 0.035, 1e-6, 1e-4, 20.0, 2000.0


def run(ratio):
    b = A + ratio * K * DC / (M * G)
    mu0 = 0.367  # the run's mean force over weight (slider.md); the limit cycle does not depend on it
    w = M * G

    def mu(v, lt):
        psi = mu0 + b * (np.log(VREF) + lt - np.log(DC))
        return A * np.arcsinh(v / (2 * VREF) * np.exp(psi / A))

    def rhs(_t, y):
        phi, v, lt = y
        av = max(abs(v), 1e-300)
        return [V - v, (K * phi - w * mu(v, lt)) / M, -(av / DC) * (np.log(av / DC) + lt)]

    y0 = [mu0 * w / K, 0.0, np.log(DC / V)]
    t = np.arange(0.0, DURATION, 1.0 / FS)
    sol = solve_ivp(rhs, (0.0, t[-1]), y0, method="Radau", t_eval=t, rtol=1e-9,
                    atol=[1e-14, 1e-12, 1e-9])
    assert sol.success, sol.message
    f = K * sol.y[0] / w
    v = sol.y[1]
    half = len(t) // 2
    fh, vh = f[half:], v[half:]
    peaks = [i for i in range(1, len(fh) - 1) if fh[i] >= fh[i - 1] and fh[i] > fh[i + 1]]
    # Maxima of the oscillation, not of the ripple: above the mean.
    peaks = [i for i in peaks if fh[i] > fh.mean()]
    period = (peaks[-1] - peaks[0]) / (len(peaks) - 1) / FS if len(peaks) > 1 else float("nan")
    return period, fh.mean(), fh.max() - fh.min(), float(np.mean(vh < V / 2))


if __name__ == "__main__":
    ratios = [float(x) for x in sys.argv[1:]] or [1.02, 1.04]
    for r in ratios:
        p, mean, rng, stuck = run(r)
        print(f"k_c = {r:.3f} k: period {p:.4f} s, mean force {mean:.5f}, range {rng:.5f}, stuck {stuck:.3f}")
