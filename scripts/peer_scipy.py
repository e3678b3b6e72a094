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

With --criterion it first runs the criterion benches `simulate` (mimalloc as
the global allocator) and `simulate_system_alloc` (the system allocator) and
prints scipy's best wall time over criterion's mean wall time per case, so
the peer and the floor are measured in one run (issue 23: the plain call into
a fresh trajectory >= 300x LSODA).

Usage: scripts/peer_scipy.py [--repeat N] [--criterion]   (run from the workspace root)
"""
import argparse
import glob
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
    ap.add_argument("--criterion", action="store_true",
                    help="run the criterion benches simulate and simulate_system_alloc first and compare with them")
    args = ap.parse_args()
    if args.criterion:
        subprocess.run(
            ["cargo", "bench", "-q", "--workspace", "--bench", "simulate", "--bench", "simulate_system_alloc",
             "--", "--noplot"],
            cwd=ROOT, check=True, stdout=subprocess.DEVNULL,
        )
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
    lsoda_wall_ms = None
    w_rust = np.array(rust["rotor_speed_rad_s"])
    rel_rust = np.array(rust["release_times_s"])
    for method, rtol, atol in [("LSODA", 1e-8, 1e-10), ("DOP853", 1e-10, 1e-12)]:
        best_cpu, best_wall = float("inf"), float("inf")
        for _ in range(args.repeat):
            c0, w0 = time.process_time(), time.perf_counter()
            w, releases = simulate(case, method=method, rtol=rtol, atol=atol)
            best_cpu = min(best_cpu, time.process_time() - c0)
            best_wall = min(best_wall, time.perf_counter() - w0)
        if method == "LSODA":
            lsoda_wall_ms = best_wall * 1e3
        dw = np.nanmax(np.abs(w - w_rust))
        drel = np.max(np.abs(np.array(releases) - rel_rust)) if len(releases) == len(rel_rust) else float("nan")
        print(f"scipy {method:6s} rtol {rtol:.0e}: CPU {best_cpu * 1e3:9.1f} ms  wall {best_wall * 1e3:9.1f} ms per run"
              f"  ratio CPU {best_cpu * 1e3 / rust['cpu_ms_per_run']:5.0f}x fresh, {best_cpu * 1e3 / rust['cpu_ms_per_run_reused']:5.0f}x reused"
              f"  wall {best_wall * 1e3 / rust['wall_ms_per_run']:5.0f}x / {best_wall * 1e3 / rust['wall_ms_per_run_reused']:5.0f}x"
              f"  | max |dOmega1| {dw:.1e} rad/s, {len(releases)} break-aways, max |d release| {drel:.1e} s")
    if args.criterion:
        print_criterion(lsoda_wall_ms)


def print_criterion(lsoda_wall_ms):
    """scipy LSODA's best wall time over each rig-model criterion case's mean (and 95 % interval)."""
    print(f"criterion (this run, mean [95 % interval]) against scipy LSODA's best wall {lsoda_wall_ms:.1f} ms:")
    rows = []
    for bench in glob.glob(os.path.join(ROOT, "target", "criterion", "*", "*", "new", "benchmark.json")):
        with open(bench) as f:
            name = json.load(f)["full_id"]
        if name.split("/")[0] not in ("mimalloc", "system allocator") or "rig model 40 s" not in name:
            continue
        with open(os.path.join(os.path.dirname(bench), "estimates.json")) as f:
            mean = json.load(f)["mean"]
        lo, hi = mean["confidence_interval"]["lower_bound"], mean["confidence_interval"]["upper_bound"]
        rows.append((name, mean["point_estimate"] / 1e6, lo / 1e6, hi / 1e6))
    for name, ms, lo, hi in sorted(rows):
        print(f"  {name:88s} {ms:7.3f} ms [{lo:.3f}, {hi:.3f}]  LSODA / it {lsoda_wall_ms / ms:5.0f}x")


if __name__ == "__main__":
    main()
