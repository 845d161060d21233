#!/usr/bin/env bash
# Slurm tests against real daemons: the one-node cluster that
# tools/slurm_local.sh started in CLUSTER_DIR (the ctest fixture slurm_cluster).
#
#   slurm_test.sh CASE POINTBAKE TEST_PLUGIN SOURCE_DIR WORK_DIR CLUSTER_DIR
#
# Cases:
#   workflow   a workflow through Slurm gives the local executor's output
#              bytes; the run record holds the figures measured in the job
#   campaign   the smoke campaign (the four workflows on a tiny room) through
#              Slurm, its runs submitted together: same outputs as locally,
#              shared stages computed once
#   oom        a stage over its --mem is killed, retried once with twice the
#              memory and succeeds; one that needs more still fails, with
#              Slurm's reason; nothing of either enters the cache
#   scancel    a stage job cancelled with scancel fails with Slurm's state;
#              --keep-going still runs the independent branch
#   interrupt  Ctrl-C (SIGINT) on pointbake cancels its running jobs
#   timeout    a stage over its --time fails with TIMEOUT (takes ~1.5 min)
#   nodefail   a job on a node set DOWN fails with NODE_FAIL (--no-requeue)
#   shared     two pointbake processes on one cache compute a shared stage once
# After each case `pointbake cache verify` must report 0 problems.
# Exit status 77 (skipped) when the cluster is not up.
set -uo pipefail

case_name=$1 pb=$2 plugin=$3 src=$4 work=$5 cluster=$6
export SLURM_CONF=$cluster/slurm.conf
if [ ! -f "$SLURM_CONF" ] || ! scontrol ping 2>/dev/null | grep -q UP; then
  echo "SKIP: no Slurm cluster in $cluster (the slurm.setup test says why)"
  exit 77
fi
dir=$work/$case_name
rm -rf "$dir"
mkdir -p "$dir"
cd "$dir" || exit 1

fail() {
  echo "FAIL ($case_name): $*" >&2
  exit 1
}
verify() {  # cache verify reports 0 problems
  "$pb" cache verify --cache "$1" > "$dir/verify.txt" 2>&1 || fail "cache verify failed: $(cat "$dir/verify.txt")"
  grep -q ", 0 problems" "$dir/verify.txt" || fail "cache verify: $(cat "$dir/verify.txt")"
}
# Digests of every output file of an output folder (records and logs aside),
# by path relative to it.
digests() {
  (cd "$1" && find . -type f ! -name 'run.json' ! -name 'run.jsonl' ! -name 'trace.json' \
     ! -path '*/logs/*' ! -path './report/*' ! -name 'campaign.json' -print0 |
     sort -z | xargs -0 sha256sum)
}
# The state of a stage in a run record.
stage_field() {  # RUN_JSON STAGE FIELD
  python3 -c 'import json,sys
r = json.load(open(sys.argv[1]))
for s in r["stages"]:
    if s["stage"] == sys.argv[2]: print(s.get(sys.argv[3], ""))' "$1" "$2" "$3"
}
no_jobs_left() {  # no pb: job of this case is pending or running
  for _ in $(seq 100); do
    [ -z "$(squeue -h -o '%i %j' | grep " pb:$case_name")" ] && return 0
    sleep 0.1
  done
  squeue >&2
  return 1
}
wait_running() {  # JOB_NAME: until a job of that name runs
  for _ in $(seq 300); do
    squeue -h -t RUNNING -o '%j' | grep -qx "$1" && return 0
    sleep 0.1
  done
  return 1
}

case "$case_name" in
workflow)
  cat > wf.yaml <<EOF
name: slurm-workflow
plugins: [$plugin]
stages:
  src: { uses: test.source, with: { text: "slurm", repeat: 1000 } }
  up: { uses: test.concat, in: { a: src.out }, with: { suffix: "!" } }
  len: { uses: test.length, in: { in: up.out } }
  mem: { uses: test.alloc, with: { mib: 96 } }
outputs: { up: up.out, len: len.out, mem: mem.out }
EOF
  "$pb" run wf.yaml --cache local-cache --out local-out -q > local.txt 2>&1 || fail "local run: $(cat local.txt)"
  "$pb" run wf.yaml --executor slurm --cache slurm-cache --out slurm-out --jobs 2 -q > slurm.txt 2>&1 ||
    fail "slurm run: $(cat slurm.txt)"
  grep -q "4 ran" slurm.txt || fail "expected 4 stages to run: $(cat slurm.txt)"
  diff <(digests local-out) <(digests slurm-out) || fail "outputs differ between the local and the Slurm executor"
  # Figures measured inside the job: 96 MiB touched shows in the peak RSS.
  peak=$(stage_field slurm-out/run.json mem peak_rss_bytes)
  [ "${peak:-0}" -gt $((96 << 20)) ] || fail "peak RSS of 'mem' is $peak, expected over 96 MiB"
  user=$(stage_field slurm-out/run.json mem user_s)
  python3 -c "import sys; sys.exit(0 if float('$user') + 0 >= 0 and float('$(stage_field slurm-out/run.json mem wall_s)') > 0 else 1)" ||
    fail "no wall time in the record"
  written=$(stage_field slurm-out/run.json mem write_bytes)
  [ "${written:-0}" -gt 0 ] || fail "no I/O figure in the record"
  grep -q "slurm job [0-9]* (attempt 1" slurm-out/logs/mem.log || fail "the log does not name the Slurm job"
  # A re-run finds everything in the cache and submits nothing.
  "$pb" run wf.yaml --executor slurm --cache slurm-cache --out slurm-out -q > rerun.txt 2>&1 || fail "re-run"
  grep -q "0 ran, 4 cached" rerun.txt || fail "re-run: $(cat rerun.txt)"
  verify slurm-cache
  ;;

campaign)
  campaign=$src/configs/campaigns/smoke.yaml
  "$pb" campaign "$campaign" --cache local-cache --out local-out --threads 1 -q > local.txt 2>&1 ||
    fail "local campaign: $(tail -n 20 local.txt)"
  "$pb" campaign "$campaign" --executor slurm --cache slurm-cache --out slurm-out --threads 1 -q > slurm.txt 2>&1 ||
    fail "slurm campaign: $(tail -n 20 slurm.txt)"
  diff <(digests local-out) <(digests slurm-out) || fail "campaign outputs differ between the local and the Slurm executor"
  # Shared stages (scan, normals, the HPM reference) ran once across runs that
  # went out together: as many entries as locally, where runs are sequential.
  n_local=$(find local-cache/entries -name '*.json' | wc -l)
  n_slurm=$(find slurm-cache/entries -name '*.json' | wc -l)
  [ "$n_local" = "$n_slurm" ] || fail "$n_slurm cache entries through Slurm, $n_local locally"
  ran=$(python3 -c 'import json,glob
print(sum(1 for f in glob.glob("slurm-out/runs/*/*/run.json") for s in json.load(open(f))["stages"] if s["status"] == "ran"))')
  [ "$ran" = "$n_slurm" ] || fail "$ran stages ran for $n_slurm entries: a shared stage ran twice"
  verify slurm-cache
  ;;

oom)
  cat > wf.yaml <<EOF
name: slurm-oom
plugins: [$plugin]
stages:
  fits_on_retry: { uses: test.alloc, with: { mib: 450, hold_ms: 4000 } }
EOF
  # 300 MiB asked first (a stage never run: --default-mem), 600 MiB on the retry.
  "$pb" run wf.yaml --executor slurm --default-mem 300M --cache cache --out out > run1.txt 2>&1 ||
    fail "the retry with twice the memory should have succeeded: $(cat run1.txt)"
  grep -q "attempt 1" out/logs/fits_on_retry.log || fail "no first attempt in the log"
  grep -q "attempt 2, --mem=600M" out/logs/fits_on_retry.log || fail "no retry with 600M: $(cat out/logs/fits_on_retry.log)"
  [ "$(stage_field out/run.json fits_on_retry status)" = ran ] || fail "fits_on_retry did not run"
  cat > wf2.yaml <<EOF
name: slurm-oom-twice
plugins: [$plugin]
stages:
  too_big: { uses: test.alloc, with: { mib: 900, hold_ms: 4000 } }
EOF
  "$pb" run wf2.yaml --executor slurm --default-mem 300M --cache cache --out out2 > run2.txt 2>&1 &&
    fail "a stage over twice its memory should fail"
  err=$(stage_field out2/run.json too_big error)
  grep -q "out of memory at --mem=600M" <<< "$err" || fail "error does not say out of memory: $err"
  grep -q "retried once with twice the memory" <<< "$err" || fail "error does not say it was retried: $err"
  echo "$err" | grep -Eq "OUT_OF_MEMORY|exceeded memory limit" || fail "error lacks Slurm's reason: $err"
  [ -z "$(ls cache/tmp)" ] || fail "staging leftovers in the cache: $(ls cache/tmp)"
  verify cache
  ;;

scancel)
  cat > wf.yaml <<EOF
name: slurm-scancel
plugins: [$plugin]
stages:
  slow: { uses: test.source, with: { text: slow, sleep_ms: 60000 } }
  a: { uses: test.source, with: { text: independent } }
  b: { uses: test.length, in: { in: a.out }, with: { sleep_ms: 2000 } }
EOF
  "$pb" run wf.yaml --executor slurm --sbatch-arg=--job-name=pb:scancel --jobs 2 --keep-going \
    --cache cache --out out > run.txt 2>&1 &
  pid=$!
  wait_running pb:scancel || { kill "$pid"; fail "no job started"; }
  # Cancel the slow stage's job (the one that is still running after b).
  sleep 0.5
  slow_job=$(grep -l "\"stage_id\":\"slow\"" "$dir"/cache/tmp/*/_slurm_job.json | head -n 1)
  [ -n "$slow_job" ] || fail "no job file of 'slow'"
  job_id=$(squeue -h -o '%i %Z' | awk -v d="$(dirname "$slow_job")" '$2 == d { print $1 }')
  [ -n "$job_id" ] || fail "no Slurm job for 'slow'"
  scancel "$job_id"
  wait "$pid" && fail "a cancelled stage should fail the run"
  err=$(stage_field out/run.json slow error)
  grep -q "CANCELLED" <<< "$err" || fail "error lacks Slurm's state: $err"
  [ "$(stage_field out/run.json b status)" = ran ] || fail "--keep-going: the independent branch did not run"
  no_jobs_left || fail "jobs left in the queue"
  [ -z "$(ls cache/tmp)" ] || fail "staging leftovers in the cache: $(ls cache/tmp)"
  verify cache
  ;;

interrupt)
  cat > wf.yaml <<EOF
name: slurm-interrupt
plugins: [$plugin]
stages:
  slow1: { uses: test.source, with: { text: one, sleep_ms: 60000 } }
  slow2: { uses: test.source, with: { text: two, sleep_ms: 60000 } }
EOF
  "$pb" run wf.yaml --executor slurm --sbatch-arg=--job-name=pb:interrupt --jobs 2 \
    --cache cache --out out > run.txt 2>&1 &
  pid=$!
  wait_running pb:interrupt || { kill "$pid"; fail "no job started"; }
  kill -INT "$pid"
  wait "$pid" && fail "an interrupted run should fail"
  no_jobs_left || fail "Ctrl-C left jobs in the queue"
  grep -q "interrupted" run.txt || fail "no word of the interruption: $(cat run.txt)"
  [ -z "$(ls cache/tmp)" ] || fail "staging leftovers in the cache: $(ls cache/tmp)"
  verify cache
  ;;

timeout)
  cat > wf.yaml <<EOF
name: slurm-timeout
plugins: [$plugin]
stages:
  endless: { uses: test.source, with: { text: late, sleep_ms: 300000 } }
EOF
  # Slurm's smallest limit is a minute; it checks limits every ~30 s.
  "$pb" run wf.yaml --executor slurm --time 1 --cache cache --out out > run.txt 2>&1 &&
    fail "a stage over its time limit should fail"
  err=$(stage_field out/run.json endless error)
  grep -q "TIMEOUT" <<< "$err" || fail "error lacks Slurm's state: $err"
  [ -z "$(ls cache/tmp)" ] || fail "staging leftovers in the cache: $(ls cache/tmp)"
  verify cache
  ;;

nodefail)
  cat > wf.yaml <<EOF
name: slurm-nodefail
plugins: [$plugin]
stages:
  doomed: { uses: test.source, with: { text: doomed, sleep_ms: 60000 } }
EOF
  # Without requeueing (Slurm's default requeues a batch job after a node
  # failure), the stage fails with NODE_FAIL.
  "$pb" run wf.yaml --executor slurm --sbatch-arg=--no-requeue --sbatch-arg=--job-name=pb:nodefail \
    --cache cache --out out > run.txt 2>&1 &
  pid=$!
  wait_running pb:nodefail || { kill "$pid"; fail "no job started"; }
  node=$(squeue -h -n pb:nodefail -o '%N')
  scontrol update nodename="$node" state=down reason="pointbake node failure test"
  wait "$pid"
  rc=$?
  # ReturnToService=2 may have brought it back already.
  scontrol update nodename="$node" state=resume 2>/dev/null || true
  [ "$rc" != 0 ] || fail "a stage on a failed node should fail"
  err=$(stage_field out/run.json doomed error)
  grep -q "NODE_FAIL" <<< "$err" || fail "error lacks Slurm's state: $err"
  for _ in $(seq 100); do
    scontrol show node "$node" | grep -q "State=IDLE" && break
    sleep 0.2
  done
  verify cache
  ;;

shared)
  cat > wf.yaml <<EOF
name: slurm-shared
plugins: [$plugin]
stages:
  shared: { uses: test.source, with: { text: once, sleep_ms: 3000 } }
  len: { uses: test.length, in: { in: shared.out } }
EOF
  "$pb" run wf.yaml --executor slurm --cache cache --out out1 -q > run1.txt 2>&1 &
  p1=$!
  "$pb" run wf.yaml --executor slurm --cache cache --out out2 -q > run2.txt 2>&1 &
  p2=$!
  wait "$p1" || fail "run 1: $(cat run1.txt)"
  wait "$p2" || fail "run 2: $(cat run2.txt)"
  states="$(stage_field out1/run.json shared status) $(stage_field out2/run.json shared status)"
  case "$states" in
    "ran hit"|"hit ran") ;;
    *) fail "the shared stage should run once and be a hit once, got: $states" ;;
  esac
  verify cache
  ;;

*)
  echo "unknown case $case_name" >&2
  exit 2
  ;;
esac
echo "ok: $case_name"
