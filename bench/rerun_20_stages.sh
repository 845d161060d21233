#!/usr/bin/env bash
# Measures re-running an unchanged 20-stage workflow (all cache hits) against
# its first run, in one run on this machine. Prints figures; passes or fails
# on nothing. Needs a build in build/ (the README's commands make one).
# Usage: bench/rerun_20_stages.sh [repeats]
set -euo pipefail
cd "$(dirname "$0")/.."
repeats=${1:-5}
bin=build/pointbake
plugin=$(pwd)/build/tests/libpb_test_stages.so
[ -x "$bin" ] && [ -f "$plugin" ] || { echo "build first: .ci/setup" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

{
  echo "name: bench20"
  echo "plugins: [$plugin]"
  echo "stages:"
  echo "  s0: { uses: test.source, with: { text: \"bench\", repeat: 1000, sleep_ms: 20 } }"
  for i in $(seq 1 19); do
    if (( i % 4 == 0 )); then
      echo "  s$i: { uses: test.concat, in: { a: s$((i-1)).out, b: s$((i-2)).out }, with: { sleep_ms: 20 } }"
    else
      echo "  s$i: { uses: test.concat, in: { a: s$((i-1)).out }, with: { suffix: \"$i\", sleep_ms: 20 } }"
    fi
  done
} > "$work/bench20.yaml"

now() { date +%s.%N; }
run() { "$bin" run "$work/bench20.yaml" --cache "$work/cache" --out "$work/out" -q >/dev/null; }

t0=$(now); run; t1=$(now)
cold=$(awk "BEGIN{print $t1 - $t0}")
best=999
for _ in $(seq "$repeats"); do
  t0=$(now); run; t1=$(now)
  best=$(awk "BEGIN{t = $t1 - $t0; print (t < $best) ? t : $best}")
done
hits=$(grep -c '"status":"hit"' "$work/out/run.jsonl")
printf 'machine: %s, %s cores\n' "$(uname -m)" "$(nproc)"
printf 'first run (20 stages executed as child processes): %.3f s\n' "$cold"
printf 'unchanged re-run (%s/20 hits), best of %s:          %.3f s\n' "$hits" "$repeats" "$best"
printf 'ratio first/re-run: %.1fx\n' "$(awk "BEGIN{print $cold / $best}")"
