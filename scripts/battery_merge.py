#!/usr/bin/env python3
"""Merge a full-battery run with a rerun of some of its cases.

The full battery (crates/virtual-rig/tests/hidden_effects.rs::full_battery)
takes about 100 minutes; when the diagnosis changes in a way that can only
alter some cases (see docs/battery-full/README.md for the argument), those
cases are rerun with BATTERY_CASES=... and this script replaces them:

    python3 scripts/battery_merge.py FULL_DIR RERUN_DIR [RERUN_DIR ...] > merged.md

FULL_DIR holds the full run's progress log (log.txt, one "[ t s] case: verdict"
line per case) and its confusion-detection.csv / battery.md; each RERUN_DIR
the same for its subset (the last rerun of a case wins). A case is right
unless it is listed under "## Wrong answers" of its report. Writes the merged
per-group counts, the merged detection table (confusion-detection.csv in
FULL_DIR's format, to stdout's companion file merged-detection.csv in the
current directory) and the list of cases that were rerun.
"""
import csv
import re
import sys
from pathlib import Path

LINE = re.compile(r"^\[\s*\d+ s\] (\S+): (\S+)$")


def read_run(d):
    d = Path(d)
    verdicts = {}
    for line in (d / "log.txt").read_text().splitlines():
        m = LINE.match(line.strip())
        if m:
            verdicts[m.group(1)] = m.group(2)
    wrong = {}
    md = (d / "battery.md").read_text()
    if "## Wrong answers" in md:
        for row in md.split("## Wrong answers", 1)[1].splitlines():
            cells = [c.strip() for c in row.strip().strip("|").split("|")]
            if len(cells) == 5 and cells[0] not in ("case", "---"):
                wrong[cells[0]] = (cells[3], cells[4])
    return verdicts, wrong


def clopper_pearson(k, n):
    """Two-sided 95 % Clopper-Pearson interval (as rig_virtual_rig::battery::clopper_pearson)."""
    from math import comb

    def cdf(k, p):
        return sum(comb(n, i) * p**i * (1 - p) ** (n - i) for i in range(k + 1))

    def solve(f):
        lo, hi = 0.0, 1.0
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if f(mid) < 0 else (lo, mid)
        return 0.5 * (lo + hi)

    lower = 0.0 if k == 0 else solve(lambda p: (1 - cdf(k - 1, p)) - 0.025)
    upper = 1.0 if k >= n else solve(lambda p: 0.025 - cdf(k, p))
    return lower, upper


def group(case):
    return case.split("-", 1)[0]


def main():
    full_dir, reruns = sys.argv[1], sys.argv[2:]
    verdicts, wrong = read_run(full_dir)
    # Cases the full run could not diagnose (generation errors) have no log line.
    for case, (verdict, _) in wrong.items():
        verdicts.setdefault(case, verdict)
    rerun_cases = {}
    for d in reruns:
        v, w = read_run(d)
        for case, verdict in v.items():
            rerun_cases[case] = (verdicts.get(case, "?"), verdict, case not in w, w.get(case, ("", ""))[1])
            verdicts[case] = verdict
            wrong.pop(case, None)
            if case in w:
                wrong[case] = w[case]
    groups = {}
    for case in verdicts:
        g = groups.setdefault(group(case), [0, 0])
        g[0] += 1
        g[1] += case not in wrong
    out = ["| group | campaigns | right |", "|---|---|---|"]
    for g in ["null", "single", "compound", "mixed", "outside", "ladder"]:
        if g in groups:
            out.append(f"| {g} | {groups[g][0]} | {groups[g][1]} |")
    total = sum(v[0] for v in groups.values())
    right = sum(v[1] for v in groups.values())
    out.append(f"| all | {total} | {right} |")
    out.append("")
    out.append("Rerun with the final code (verdict in the full run → verdict now, right now):")
    out.append("")
    out.append("| case | full run | rerun | right | reason |")
    out.append("|---|---|---|---|---|")
    for case, (before, after, ok, reason) in sorted(rerun_cases.items()):
        out.append(f"| {case} | {before} | {after} | {'yes' if ok else 'no'} | {reason} |")
    out.append("")
    out.append("Wrong after the reruns:")
    out.append("")
    out.append("| case | verdict | reason |")
    out.append("|---|---|---|")
    for case, (verdict, reason) in sorted(wrong.items()):
        out.append(f"| {case} | {verdict} | {reason} |")
    print("\n".join(out))
    # Detection table with the rerun cases' judgements replaced (named: the full run's).
    rows = list(csv.DictReader(open(Path(full_dir) / "confusion-detection.csv")))
    for r in rows:
        cases = [c for c in verdicts if c.startswith(f"ladder-{r['effect']}-{r['step']}-")]
        r["right"] = str(sum(c not in wrong for c in cases))
        r["p_right"] = f"{int(r['right']) / int(r['n']):.2f}"
        lo, hi = clopper_pearson(int(r["right"]), int(r["n"]))
        r["ci95_low"], r["ci95_high"] = f"{lo:.3f}", f"{hi:.3f}"
    with open("merged-detection.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=rows[0].keys(), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
