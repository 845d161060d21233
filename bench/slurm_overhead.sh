#!/usr/bin/env bash
# Measures what running stages through Slurm costs against the local
# executor: a chain of N trivial stages (each waits for the one before, so
# nothing overlaps) and the quickstart workflow, each from an empty cache,
# both ways. Prints figures; passes or fails on nothing.
# Needs a build in build/ and a running cluster: SLURM_CONF set, or
# `tools/slurm_local.sh start DIR` first (as root) and SLURM_CONF=DIR/slurm.conf.
# Usage: bench/slurm_overhead.sh [stages in the chain, default 10]
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-10}
bin=build/pointbake
plugin=$(pwd)/build/tests/libpb_test_stages.so
[ -x "$bin" ] && [ -f "$plugin" ] || { echo "build first: .ci/setup" >&2; exit 1; }
scontrol ping 2>/dev/null | grep -q UP || { echo "no Slurm cluster answers (SLURM_CONF=${SLURM_CONF:-unset})" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

{
  echo "name: chain$n"
  echo "plugins: [$plugin]"
  echo "stages:"
  echo "  s0: { uses: test.source, with: { text: \"bench\", repeat: 1000 } }"
  for i in $(seq 1 $((n - 1))); do
    echo "  s$i: { uses: test.concat, in: { a: s$((i-1)).out }, with: { suffix: \"$i\" } }"
  done
} > "$work/chain.yaml"

now() { date +%s.%N; }
# Seconds for one run from an empty cache.
timed() {  # NAME WORKFLOW [options]
  local name=$1 wf=$2
  shift 2
  rm -rf "$work/$name"
  local t0
  t0=$(now)
  "$bin" run "$wf" --cache "$work/$name/cache" --out "$work/$name/out" -q "$@" > "$work/$name.txt" 2>&1
  awk -v a="$t0" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'
}
# Per stage: seconds from sbatch to result, minus the stage's own wall time
# (measured inside the job): the scheduler's and the polling's share.
per_stage_overhead() {  # OUT_DIR
  python3 - "$1" <<'EOF'
import json, re, sys, glob, os
out = sys.argv[1]
run = json.load(open(os.path.join(out, "run.json")))
walls = {s["stage"]: s["wall_s"] for s in run["stages"] if s["status"] == "ran"}
over = []
for stage, wall in walls.items():
    text = open(os.path.join(out, "logs", stage + ".log")).read()
    m = re.findall(r"--- slurm job \d+ \(attempt \d+, --mem=\d+M\), ([0-9.]+) s from submission", text)
    if m:
        over.append(float(m[-1]) - wall)
over.sort()
print("%d stages: median %.2f s, min %.2f s, max %.2f s" % (len(over), over[len(over) // 2], over[0], over[-1]))
EOF
}

echo "chain of $n stages (one at a time):"
local_s=$(timed local "$work/chain.yaml")
slurm_s=$(timed slurm "$work/chain.yaml" --executor slurm)
echo "  local $local_s s, slurm $slurm_s s: $(awk -v l="$local_s" -v s="$slurm_s" -v n="$n" 'BEGIN { printf "%.2f", (s - l) / n }') s more per stage"
echo "  slurm, submission to result minus the stage's wall time: $(per_stage_overhead "$work/slurm/out")"
echo "quickstart (7 stages, --jobs 2):"
local_s=$(timed qlocal configs/workflows/quickstart.yaml --jobs 2 --threads 1)
slurm_s=$(timed qslurm configs/workflows/quickstart.yaml --jobs 2 --threads 1 --executor slurm)
echo "  local $local_s s, slurm $slurm_s s"
echo "  slurm, submission to result minus the stage's wall time: $(per_stage_overhead "$work/qslurm/out")"
