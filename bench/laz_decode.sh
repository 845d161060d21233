#!/usr/bin/env bash
# LAZ decoding figures for docs/laz.md: our decoder (bench/laz_bench, 1 and 2
# threads, every field and the io.read_points path) and the npm laz-perf
# decoder (tools/laz_oracle.mjs, one thread, WebAssembly in node) on the same
# files, and laz-perf's check that they hold the points of their .las twins.
# Prints a Markdown table; passes or fails on no time.
# Usage: bench/laz_decode.sh [POINTS] [OUT_MD]   (default 5000000)
set -euo pipefail
cd "$(dirname "$0")/.."
points=${1:-5000000}
out_md=${2:-}
[ -d build ] || { echo "configure first: cmake -S . -B build -DCMAKE_BUILD_TYPE=Release" >&2; exit 1; }
cmake --build build --target laz_bench >/dev/null
[ -d tools/node_modules/laz-perf ] || npm ci --prefix tools --no-audit --no-fund >/dev/null
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
{
  echo "$points points, $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)), load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo
  build/bench/laz_bench "$work" "$points"
  for name in layered_f7 pointwise_f3; do
    node tools/laz_oracle.mjs time "$work/laz_bench_$name.laz" 3
  done
  echo
  for name in layered_f7 pointwise_f3; do
    node tools/laz_oracle.mjs compare "$work/laz_bench_$name.laz" "$work/laz_bench_$name.las" | sed "s|$work/||g"
  done
} | tee ${out_md:+"$out_md"}
