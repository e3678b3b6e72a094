#!/usr/bin/env python3
"""Tabulate a streamed battery run (JSON lines of the `battery_stream`
example of rig-virtual-rig): right answers by group, the detection ladders'
P(right) per rung with its 95 % Clopper–Pearson interval, the CPU spent and
every wrong answer with the judge's reason. Markdown on stdout.
Usage: python3 scripts/battery_summary.py part0.jsonl part1.jsonl ...
"""
import json
import sys
from collections import defaultdict
from math import comb


def binom_cdf(k, n, p):
    return sum(comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(k + 1))


def clopper_pearson(k, n, alpha=0.05):
    """Exact binomial interval by bisection on the binomial tail (no scipy)."""
    def solve(f):
        lo, hi = 0.0, 1.0
        for _ in range(60):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if f(mid) else (lo, mid)
        return (lo + hi) / 2
    low = 0.0 if k == 0 else solve(lambda p: 1 - binom_cdf(k - 1, n, p) < alpha / 2)
    high = 1.0 if k == n else solve(lambda p: binom_cdf(k, n, p) > alpha / 2)
    return low, high


def main(paths):
    rows = [json.loads(line) for p in paths for line in open(p) if line.strip()]
    rows.sort(key=lambda r: r["k"])
    groups = defaultdict(lambda: [0, 0])
    rungs = defaultdict(lambda: [0, 0, 0])
    for r in rows:
        groups[r["group"]][0] += r["right"]
        groups[r["group"]][1] += 1
        if r["group"] == "ladder":
            _, effect, step, _ = r["case"].split("-")
            rungs[(effect, int(step))][0] += r["right"]
            rungs[(effect, int(step))][1] += 1
            rungs[(effect, int(step))][2] += r["verdict"] == "none" and not r["right"]
    cpu = sum(r["cpu_s"] for r in rows)
    right = sum(r["right"] for r in rows)
    print(f"{len(rows)} campaigns, {right} right; CPU {cpu:.0f} s ({cpu / len(rows):.2f} s per campaign)\n")
    print("| group | campaigns | right |\n|---|---|---|")
    for g, (k, n) in groups.items():
        print(f"| {g} | {n} | {k} |")
    print(f"| all | {len(rows)} | {right} |\n")
    if rungs:
        print("| ladder effect | rung (0 largest) | draws | right | P(right) | 95 % CP | missed (`none`) | other wrong |")
        print("|---|---|---|---|---|---|---|---|")
        for (effect, step), (k, n, miss) in sorted(rungs.items()):
            lo, hi = clopper_pearson(k, n)
            print(f"| {effect} | {step} | {n} | {k} | {k / n:.2f} | {lo:.2f}–{hi:.2f} | {miss} | {n - k - miss} |")
        print()
    print("Wrong answers (ladder rungs: a miss is the ladder's measure, listed for completeness):\n")
    for r in rows:
        if not r["right"]:
            print(f"- `{r['case']}`: {r['reason']}")


if __name__ == "__main__":
    main(sys.argv[1:])
