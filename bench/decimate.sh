#!/usr/bin/env bash
# Decimation figure for issue 4, in one run on this machine: the synthetic
# room's true surface tessellated at CELL_MM (7 mm: ~4.8·10^6 faces) through
# mesh.decimate to TARGET faces (default 250,000), then mesh.clean as a
# manifold check (it must remove nothing). Prints a Markdown table; passes
# or fails on nothing.
# Usage: bench/decimate.sh [TARGET] [CELL_MM]
set -euo pipefail
cd "$(dirname "$0")/.."
target=${1:-250000}
cell=${2:-7}
bin=build/pointbake
[ -x "$bin" ] || { echo "build first: .ci/setup" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/decimate.yaml" <<YAML
name: bench_decimate
stages:
  scan: { uses: synth.scan, with: { preset: room, points: 10000, truth_cell_mm: $cell } }
  low: { uses: mesh.decimate, in: { mesh: scan.truth }, with: { target_faces: $target } }
  check: { uses: mesh.clean, in: { mesh: low.mesh } }
outputs: { check: check.mesh }
YAML
"$bin" run "$work/decimate.yaml" --cache "$work/cache" --out "$work/out" -q >/dev/null
python3 - "$work/out/run.json" <<'PY'
import json, sys
stages = {s["stage"]: s for s in json.load(open(sys.argv[1]))["stages"]}
d, c = stages["low"], stages["check"]
dc, cc = d["counters"], c["counters"]
removed = int(cc["faces_in"] - cc["faces_out"]) + int(cc.get("split_vertices", 0))
print("| step | faces in | faces out | wall | CPU | peak RSS |")
print("|---|---:|---:|---:|---:|---:|")
print(f"| mesh.decimate | {int(dc['faces_in']):,} | {int(dc['faces_out']):,} | {d['wall_s']:.1f} s | "
      f"{d['user_s'] + d['sys_s']:.1f} s | {d['peak_rss_bytes'] / 2**20:.0f} MiB |")
print(f"| mesh.clean (check) | {int(cc['faces_in']):,} | {int(cc['faces_out']):,} | {c['wall_s']:.1f} s | "
      f"{c['user_s'] + c['sys_s']:.1f} s | {c['peak_rss_bytes'] / 2**20:.0f} MiB |")
print()
print("manifold after decimation:", "yes (mesh.clean changed nothing)" if removed == 0 else f"no: clean removed/split {removed}")
PY
