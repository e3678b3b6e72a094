#!/usr/bin/env bash
# CI check (run by .ci/run): a single-node Slurm on this machine runs a
# 4-task array of the smoke battery and of a small severity map, each with
# its dependent merge job, and the merged outputs must equal a local
# unsharded run byte for byte. Skips with a message when Slurm or munge is
# not installed (like the Chromium check). Needs root (it starts the daemons).
# About 3-4 minutes on 2 cores. WORK (default /tmp/riglab-slurm-ci) keeps the
# runs and the daemons' logs.
set -euo pipefail
cd "$(dirname "$0")/../.."
for tool in sbatch squeue slurmctld slurmd munged; do
    if ! command -v "$tool" >/dev/null 2>&1; then
        echo "ci: slurm unavailable ($tool missing); the Slurm check skips"
        exit 0
    fi
done
work=${WORK:-/tmp/riglab-slurm-ci}
rm -rf "$work" && mkdir -p "$work"
cargo build --workspace --quiet
export XTASK=$PWD/target/debug/xtask
# A machine whose kernel or container refuses the daemons is like one
# without Slurm: the check skips with a message (the comparison below is what
# can fail).
if ! cluster_env=$(bash scripts/slurm/local-cluster.sh start "$work/cluster"); then
    echo "ci: the Slurm daemons did not start here (logs in $work/cluster); the Slurm check skips"
    bash scripts/slurm/local-cluster.sh stop "$work/cluster" || true
    exit 0
fi
eval "$cluster_env"
trap 'bash scripts/slurm/local-cluster.sh stop "$work/cluster"' EXIT
export BATTERY=smoke
map_sets="sweeps.map_rpm_points=4 sweeps.map_force_points=3 sweeps.diagram_points=4"

# Both arrays queued at once (1 CPU per task: two tasks run side by side).
read -r _ battery_merge < <(RIGLAB_SET="" bash scripts/slurm/submit.sh battery 4 "$work/battery" --cpus-per-task=1)
read -r _ maps_merge < <(RIGLAB_SET="$map_sets" bash scripts/slurm/submit.sh maps 4 "$work/maps" --cpus-per-task=1)

# The local, unsharded runs meanwhile.
sets=()
for s in $map_sets; do sets+=(--set "$s"); done
"$XTASK" reproduce --jobs 1 --only sweeps "${sets[@]}" --out "$work/local-maps" 2>"$work/local-maps.log"
"$XTASK" reproduce --jobs 1 --only confusion --set confusion.battery=smoke --out "$work/local-battery" \
    2>"$work/local-battery.log"

for job in "$battery_merge" "$maps_merge"; do
    for _ in $(seq 1 900); do
        [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break
        sleep 1
    done
done
status=0
compare() { # merged dir, local dir
    local n=0
    while IFS= read -r -d '' f; do
        rel=${f#"$1"/}
        if cmp -s "$f" "$2/$rel"; then n=$((n + 1)); else
            echo "ci: slurm: $rel differs from the local run"
            status=1
        fi
    done < <(find "$1" -type f ! -name '.*' -print0)
    [ "$n" -gt 0 ] || { echo "ci: slurm: nothing merged in $1 (see $work/*/*.out)"; status=1; }
    echo "ci: slurm: $n merged files of $1 equal the local run"
}
compare "$work/battery/merged" "$work/local-battery"
compare "$work/maps/merged" "$work/local-maps"
if [ "$status" -ne 0 ]; then
    tail -n 20 "$work"/battery/*.out "$work"/maps/*.out "$work"/cluster/slurmctld.log || true
fi
exit "$status"
