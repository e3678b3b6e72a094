#!/usr/bin/env bash
# Submits a rig-lab job array and its dependent merge job:
#   scripts/slurm/submit.sh battery|maps N OUT [sbatch options...]
# N array tasks (one shard each) write OUT/shard-1..N; the merge job runs
# when all succeeded (afterok) and writes OUT/merged. Prints "ARRAY_ID MERGE_ID".
# The environment (BATTERY, RIGLAB_SET, XTASK) is passed on to the jobs.
set -euo pipefail
kind=${1:?battery or maps}
n=${2:?number of shards}
out=${3:?out dir on shared storage}
shift 3
case "$kind" in battery | maps) ;; *) echo "submit.sh: kind must be battery or maps, not $kind" >&2; exit 2 ;; esac
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(mkdir -p "$out" && cd "$out" && pwd)
array=$(RIGLAB_OUT=$out sbatch --parsable --array="1-$n" --chdir="$root" --output="$out/$kind-%A_%a.out" \
    --export=ALL,RIGLAB_OUT="$out" "$@" "$root/scripts/slurm/$kind.sbatch")
array=${array%%;*}
merge=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes --chdir="$root" \
    --output="$out/merge-%j.out" --export=ALL,RIGLAB_OUT="$out" "$root/scripts/slurm/merge.sbatch")
echo "${array} ${merge%%;*}"
