#!/usr/bin/env python3
"""Independent reference for rig-model's rig model (ModelKind::Rig, Coulomb brake).

Reads a JSON case (RigParams as serialised by rig-types, the operating point,
t_end_s, sample times and the two model constants) on stdin, integrates the
same equations with scipy's solve_ivp (DOP853, rtol 1e-10) using terminal
events for stick->slip (|T_s| = mu_s N r) and slip->stick (Omega1 = 0), and
writes JSON: rotor speed at the sample times, stick->slip event times.
Written from the equations in crates/model/src/lib.rs docs, not from the Rust code.
`simulate(case, method, rtol, atol)` is also imported by scripts/peer_scipy.py,
which times it on the criterion bench's problem.
"""
import json
import math
import sys

import numpy as np
from scipy.integrate import solve_ivp


def simulate(case, method="DOP853", rtol=1e-10, atol=1e-12):
    """Rotor speed at the case's sample times and the stick->slip times."""
    p = case["params"]
    m = p["motor"]
    d = p["drive"]
    fr = p["friction"]
    assert p["kind"] == "rig" and fr["law"] == "coulomb", "the reference covers the rig model with Coulomb friction"
    n = m["gear_ratio"]
    j1, jm = p["rotor_inertia_kgm2"], n * n * m["inertia_kgm2"]
    k, c = p["shaft_stiffness_nm_rad"], p["shaft_damping_nm_s_rad"]
    nr = case["normal_force_n"] * p["brake_disc_radius_m"]
    mus, muk = fr["mu_static"], fr["mu_kinetic"]
    w_ref = case["motor_rpm_setpoint"] * 2 * math.pi / 60
    ramp = case["ramp_s"]
    tt = case["anti_windup_tracking_s"]
    wf = case["motor_friction_speed_rad_s"]

    def reference(t):
        return w_ref if ramp <= 0 or t >= ramp else w_ref * t / ramp

    def shaft(y):
        return k * (y[1] - y[0]) + c * (y[3] - y[2])

    def rhs(t, y, mode):
        phi1, phi2, w1, w2, i, z = y
        e = reference(t) - w2
        raw = d["kp_v_s_rad"] * e + d["ki_v_rad"] * z
        v = min(max(raw, -d["limit_v"]), d["limit_v"])
        dz = e if d["ki_v_rad"] == 0 else e + (v - raw) / (d["ki_v_rad"] * tt)
        di = (v - m["resistance_ohm"] * i - m["voltage_constant_v_s_rad"] * n * w2) / m["inductance_h"]
        drive = n * (m["torque_constant_nm_a"] * i - m["friction_torque_nm"] * math.tanh(n * w2 / wf)
                     - m["speed_regulation_nm_s_rad"] * n * w2)
        ts = shaft(y)
        dw2 = (drive - ts) / jm
        if mode == 0:
            return [0.0, w2, 0.0, dw2, di, dz]
        dw1 = (ts - mode * muk * nr) / j1
        return [w1, w2, dw1, dw2, di, dz]

    def stick_event(t, y, mode):
        return abs(shaft(y)) - mus * nr
    stick_event.terminal = True
    stick_event.direction = 1

    def slip_event(t, y, mode):
        return mode * y[2]
    slip_event.terminal = True
    slip_event.direction = -1

    samples = np.array(case["sample_times_s"])
    out = np.full(len(samples), np.nan)
    y = np.zeros(6)
    mode = 0 if nr > 0 else None
    t = 0.0
    t_end = samples[-1]
    breaks = [b for b in [ramp] if 0 < b < t_end] + [t_end]
    releases = []
    while t < t_end:
        t_stop = min(b for b in breaks if b > t)
        events = [stick_event] if mode == 0 else [slip_event]
        mask = (samples > t) & (samples <= t_stop)
        sol = solve_ivp(rhs, (t, t_stop), y, method=method, rtol=rtol, atol=atol, max_step=0.01,
                        events=events, args=(mode,), dense_output=True)
        if sol.status == -1:
            raise SystemExit(sol.message)
        t_new = sol.t[-1]
        sel = mask & (samples <= t_new)
        out[sel] = sol.sol(samples[sel])[2]
        if mode == 0:
            out[sel] = 0.0
        y = sol.y[:, -1].copy()
        if sol.status == 1:  # an event ended the segment
            if mode == 0:
                mode = 1.0 if shaft(y) > 0 else -1.0
                releases.append(t_new)
            else:
                y[2] = 0.0
                ts = shaft(y)
                mode = 0 if abs(ts) <= mus * nr else (1.0 if ts > 0 else -1.0)
        if t <= 0.0 and (samples == 0.0).any():
            out[samples == 0.0] = 0.0
        t = t_new
    return out, releases


def main():
    out, releases = simulate(json.load(sys.stdin))
    json.dump({"rotor_speed_rad_s": out.tolist(), "release_times_s": releases}, sys.stdout)


if __name__ == "__main__":
    main()
