#!/usr/bin/env python3
"""Peer comparison for issue 12: scipy's solve_ivp on the criterion bench's problem.

The problem is the one `cargo bench -p rig-model` times ("rig model 40 s, 40 rpm,
15 N, default tol"): the rig model with Table 4.5, n = 8, a Coulomb brake
(mu_s 0.5 / mu_k 0.35), the PI drive ramping to 40 rpm over 2 s, N = 15 N,
40 s sampled at 500 Hz. `cargo run -p rig-model --example cpu_time -- --peer-case`
prints it as JSON together with rig-model's own CPU and wall time per run;
scipy integrates the same equations with the same event-handled stick/slip
(tests/scipy/rig_model_scipy.py, written from the crate docs, not the Rust code):

  - LSODA at rig-model's default tolerance (rtol 1e-8, atol 1e-10, max_step 0.01 s);
  - DOP853 at a tight tolerance (rtol 1e-10, atol 1e-12, max_step 0.01 s).

It prints CPU time (time.process_time) and wall time per run, the ratio to
rig-model (a fresh trajectory per run, and one reused trajectory), and how far each result is from rig-model's (rotor speed, break-aways).

Usage: scripts/peer_scipy.py [--repeat N]   (run from the workspace root)
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "crates", "model", "tests", "scipy"))
from rig_model_scipy import simulate  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="scipy runs per method (the best is reported)")
    args = ap.parse_args()
    out = subprocess.run(
        ["cargo", "run", "-q", "-p", "rig-model", "--example", "cpu_time", "--", "--peer-case"],
        cwd=ROOT, check=True, capture_output=True, text=True,
    ).stdout
    case = json.loads(out)
    rust = case["rust"]
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print(f"rig-model   default tol : CPU {rust['cpu_ms_per_run']:9.3f} ms  wall {rust['wall_ms_per_run']:9.3f} ms per run"
          f"  ({len(rust['release_times_s'])} break-aways; a fresh trajectory per run)")
    print(f"rig-model   default tol : CPU {rust['cpu_ms_per_run_reused']:9.3f} ms  wall {rust['wall_ms_per_run_reused']:9.3f} ms per run"
          f"  (into one reused trajectory, simulate_into)")
    w_rust = np.array(rust["rotor_speed_rad_s"])
    rel_rust = np.array(rust["release_times_s"])
    for method, rtol, atol in [("LSODA", 1e-8, 1e-10), ("DOP853", 1e-10, 1e-12)]:
        best_cpu, best_wall = float("inf"), float("inf")
        for _ in range(args.repeat):
            c0, w0 = time.process_time(), time.perf_counter()
            w, releases = simulate(case, method=method, rtol=rtol, atol=atol)
            best_cpu = min(best_cpu, time.process_time() - c0)
            best_wall = min(best_wall, time.perf_counter() - w0)
        dw = np.nanmax(np.abs(w - w_rust))
        drel = np.max(np.abs(np.array(releases) - rel_rust)) if len(releases) == len(rel_rust) else float("nan")
        print(f"scipy {method:6s} rtol {rtol:.0e}: CPU {best_cpu * 1e3:9.1f} ms  wall {best_wall * 1e3:9.1f} ms per run"
              f"  ratio CPU {best_cpu * 1e3 / rust['cpu_ms_per_run']:5.0f}x fresh, {best_cpu * 1e3 / rust['cpu_ms_per_run_reused']:5.0f}x reused"
              f"  wall {best_wall * 1e3 / rust['wall_ms_per_run']:5.0f}x / {best_wall * 1e3 / rust['wall_ms_per_run_reused']:5.0f}x"
              f"  | max |dOmega1| {dw:.1e} rad/s, {len(releases)} break-aways, max |d release| {drel:.1e} s")


if __name__ == "__main__":
    main()
