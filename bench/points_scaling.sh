#!/usr/bin/env bash
# Point-cloud figures for issue 3, in one run on this machine: generating a
# synthetic scan, writing it, reading it back (binary PLY throughput and peak
# RSS against the decoded cloud), and k-NN normals. Prints a Markdown table;
# passes or fails on nothing.
# Usage: bench/points_scaling.sh [POINTS] [OUT_MD]   (default 10000000)
set -euo pipefail
cd "$(dirname "$0")/.."
points=${1:-10000000}
out_md=${2:-}
bin=build/pointbake
[ -x "$bin" ] || { echo "build first: .ci/setup" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cat > "$work/gen.yaml" <<YAML
name: bench_gen
stages:
  scan: { uses: synth.scan, with: { preset: room, points: $points, seed: 1, truth_cell_mm: 50 } }
outputs: { scan: scan.points }
YAML
"$bin" run "$work/gen.yaml" --cache "$work/cache" --out "$work/gen" -q >/dev/null
cat > "$work/read.yaml" <<YAML
name: bench_read
stages:
  read: { uses: io.read_points, with: { path: $work/gen/scan.ply } }
  normals: { uses: points.normals, in: { points: read.points }, with: { k: 16 } }
YAML
"$bin" run "$work/read.yaml" --cache "$work/cache" --out "$work/read" -q >/dev/null

python3 - "$work" "$points" <<'PY' | tee ${out_md:+"$out_md"}
import json, os, sys
work, points = sys.argv[1], int(sys.argv[2])
gen = {s["stage"]: s for s in json.load(open(f"{work}/gen/run.json"))["stages"]}
rd = {s["stage"]: s for s in json.load(open(f"{work}/read/run.json"))["stages"]}
size = os.path.getsize(f"{work}/gen/scan.ply")
n = int(rd["read"]["counters"].get("points", points))
cloud_bytes = n * (12 + 3 + 2)  # xyz float32, rgb, station id (as decoded)
def row(what, s, extra=""):
    return f"| {what} | {s['wall_s']:.2f} s | {s['user_s'] + s['sys_s']:.2f} s | {s['peak_rss_bytes'] / 2**20:.0f} MiB | {extra} |"
print(f"Machine: {os.cpu_count()} cores, {os.uname().machine}; {n:,} points; PLY {size / 2**20:.0f} MiB\n")
print("| step | wall | cpu | peak RSS | notes |\n|---|---|---|---|---|")
print(row("synth.scan (generate + write)", gen["scan"]))
io = [p for p in rd["read"]["phases"] if p["name"] == "read"]
io_s = io[0]["dur_s"] if io else rd["read"]["wall_s"]
print(row("io.read_points (binary PLY)", rd["read"],
          f"{size / 1e6 / io_s:.0f} MB/s (10^6 B/s) in its read phase; peak / decoded cloud "
          f"{rd['read']['peak_rss_bytes'] / cloud_bytes:.2f}"))
print(row("points.normals (k = 16)", rd["normals"]))
PY
