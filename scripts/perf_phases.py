#!/usr/bin/env python3
"""Where a battery case's CPU goes, by phase: reads `perf script` of a
`perf record --call-graph dwarf` of the `battery_cost` example (rig-virtual-rig)
on stdin and attributes every sample to the outermost phase on its call chain
(the battery's construction, generation, calibration, estimation, structure,
selection with its drive and friction folds, free-run checks, …) and, across
them, to page faults. Percent of all samples on stdout (docs/performance.md,
issue 23).

    RAYON_NUM_THREADS=1 perf record -F 250 --call-graph dwarf,32768 -o case.data \
        target/debug/examples/battery_cost full 1000 K
    perf script -i case.data | python3 scripts/perf_phases.py
"""
import sys, re, collections
TOP = [  # (label, regex) checked from the root of the chain down; first hit wins
    ("battery construction (stick-slip draws)", r"rig_virtual_rig::stick::|Battery::full|Battery::named"),
    ("generation", r"rig_virtual_rig::"),
    ("calibration", r"rig_calibrate::"),
    ("estimation (baseline)", r"rig_estimate::"),
    ("structure", r"rig_diagnose::structure::"),
    ("selection", r"rig_diagnose::select::select_effects"),
    ("second look", r"rig_diagnose::second_look"),
    ("break-away / extension", r"rig_diagnose::breakaway|rig_diagnose::extension"),
    ("free-run checks", r"rig_diagnose::channels::free_run|rig_diagnose::channels::"),
    ("conclusion/reporting", r"Selection::conclude|rig_diagnose::render|rig_diagnose::result|serde|signature"),
    ("prepare/lines/signals", r"rig_diagnose::prepare|rig_diagnose::lines"),
]
SUB = [
    ("drive folds", r"select::Cv::drive"),
    ("friction folds", r"select::Cv::fold_friction|select::Cv::friction_many"),
    ("fold data", r"fold_data"),
]
def classify(frames):
    top = "other diagnose"
    for f in reversed(frames):
        for lab, rx in TOP:
            if re.search(rx, f):
                top = lab; break
        else:
            continue
        break
    sub = ""
    if top == "selection":
        sub = "other selection"
        for f in reversed(frames):
            for lab, rx in SUB:
                if re.search(rx, f):
                    sub = lab; break
            else: continue
            break
    return top, sub
cnt = collections.Counter(); sub = collections.Counter(); pf = collections.Counter(); n = 0
frames = []
def flush():
    global n
    if not frames: return
    n += 1
    t, s = classify(frames)
    cnt[t] += 1
    if s: sub[s] += 1
    if any("page_fault" in f for f in frames): pf[t] += 1
for line in sys.stdin:
    if not line.strip():
        flush(); frames = []; continue
    if line[0] not in " \t":
        flush(); frames = []; continue
    parts = line.strip().split(" ", 1)
    if len(parts) == 2: frames.append(parts[1])
flush()
for k, v in cnt.most_common():
    print(f"{100*v/n:5.1f} %  {k}  (page faults {100*pf[k]/n:.1f} %)")
for k, v in sub.most_common():
    print(f"      {100*v/n:5.1f} %  selection: {k}")
print("samples", n, "page faults total", f"{100*sum(pf.values())/n:.1f} %")
