#!/usr/bin/env bash
# Baking figures for issue 6, in one run on this machine: a synthetic room
# scanned with POINTS points (default 3·10^7, the paper's scale), normals,
# a low mesh (Poisson depth 8, trimmed, cleaned, decimated to FACES, default
# 250,000; unwrapped at SIZE, default 4096), then the same low mesh baked
# from its vertex colors (LPM) and from the points (the paper's transfer,
# each interpolation mode). Prints a Markdown table of the bake stages (wall,
# CPU, peak RSS against the budget "cloud in memory + 2x the textures");
# passes or fails on nothing.
# Usage: bench/bake.sh [POINTS] [SIZE] [FACES] [MODES]   (MODES e.g. "delaunay splat";
#        "delaunay-paper": without the neighbours' points, as the paper)
set -euo pipefail
cd "$(dirname "$0")/.."
points=${1:-30000000}
size=${2:-4096}
faces=${3:-250000}
modes=${4:-delaunay nearest idw splat}
bin=build/pointbake
[ -x "$bin" ] || { echo "build first: .ci/setup" >&2; exit 1; }
work=${PB_BENCH_DIR:-$(mktemp -d)}
mkdir -p "$work"
[ -n "${PB_BENCH_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
{
  cat <<YAML
name: bench_bake
stages:
  scan: { uses: synth.scan, with: { preset: room, points: $points } }
  normals: { uses: points.normals, in: { points: scan.points }, with: { k: 16 } }
  poisson: { uses: mesh.poisson, in: { points: normals.points }, with: { depth: 8, trim: 0.01 } }
  clean: { uses: mesh.clean, in: { mesh: poisson.mesh } }
  low: { uses: mesh.decimate, in: { mesh: clean.mesh }, with: { target_faces: $faces } }
  uv: { uses: uv.unwrap, in: { mesh: low.mesh }, with: { size: $size } }
  vertex_colors: { uses: bake.vertex_colors, in: { mesh: uv.mesh }, with: { size: $size } }
YAML
  for mode in $modes; do
    # MODE-paper: without the neighbours' points (bake.from_points version 1).
    neighbors=true
    [ "${mode%-paper}" = "$mode" ] || neighbors=false
    echo "  points_${mode//-/_}: { uses: bake.from_points, in: { mesh: uv.mesh, points: normals.points }, with: { size: $size, interpolation: ${mode%-paper}, neighbors: $neighbors } }"
  done
  echo "outputs: { lpm: vertex_colors.color }"
} > "$work/bake.yaml"
"$bin" run "$work/bake.yaml" --cache "$work/cache" --out "$work/out" -q >/dev/null
python3 - "$work/out/run.json" "$points" "$size" <<'PY'
import json, sys
run = json.load(open(sys.argv[1]))
points, size = int(sys.argv[2]), int(sys.argv[3])
# A cache hit (PB_BENCH_DIR reused) carries the figures of the run that made
# the entry in "cached_run"; use those.
stages = {s["stage"]: {**s, **s.get("cached_run", {})} for s in run["stages"]}
# In memory: positions and normals (3 floats each), colors (3 bytes) and the
# scanner station id (2 bytes) per point; color + normal maps 3 bytes/texel.
cloud = points * (12 + 12 + 3 + 2)
textures = size * size * 3 * 2
budget = cloud + 2 * textures
n = stages["normals"]["counters"]
print(f"{points:,} points (cloud in memory {cloud / 2**20:,.0f} MiB), low mesh "
      f"{int(stages['low']['counters']['faces_out']):,} faces, {size}² maps "
      f"(2 x {textures / 2 / 2**20:.0f} MiB); budget cloud + 2 x textures = {budget / 2**20:,.0f} MiB")
print()
print("| stage | wall | CPU | peak RSS | / budget | points assigned |")
print("|---|---:|---:|---:|---:|---:|")
for name, s in stages.items():
    if not name.startswith(("vertex_colors", "points_")):
        continue
    c = s.get("counters", {})
    assigned = f"{int(c['points_assigned']):,}" if "points_assigned" in c else ""
    print(f"| {name} | {s['wall_s']:.1f} s | {s['user_s'] + s['sys_s']:.1f} s | "
          f"{s['peak_rss_bytes'] / 2**20:,.0f} MiB | {s['peak_rss_bytes'] / budget:.2f} | {assigned} |")
print()
print("upstream:", ", ".join(f"{k} {stages[k]['wall_s']:.1f} s" for k in
                             ("scan", "normals", "poisson", "clean", "low", "uv")))
PY
