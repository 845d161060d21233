#!/usr/bin/env bash
# mesh.fit alone on the synthetic room (docs/bench-fit.md): the scan, its
# normals and the low and high decimated meshes of the shipped workflows
# (the same stages and parameters as bench/scaling.sh, so its cache serves),
# made by one `pointbake run`, then `fit_bench` on each mesh: the fit's wall
# and CPU seconds and peak RSS, whether its output is bit-identical to the
# workflow's own `mesh.fit` output, and TriangleBvh's two search engines
# side by side. Asserts nothing but exits non-zero when an output differs.
#
# Usage: bench/fit.sh [POINTS=3000000] [FIT_BENCH]
#   FIT_BENCH: another build's fit_bench to time beside this one (before /
#   after a change, in one run; the cached stage outputs are the reference).
# Env: PB_BENCH_DIR (default a temporary folder, removed at the end) keeps
#   the scene, the cache and the inputs; pointing it at bench/scaling.sh's
#   folder reuses that cache.
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-3000000}
other=${2:-}
bin=build/pointbake
bench=build/bench/fit_bench
for b in "$bin" "$bench"; do
  [ -x "$b" ] || { echo "build first: .ci/setup, then cmake --build build --target fit_bench" >&2; exit 1; }
done
work=${PB_BENCH_DIR:-$(mktemp -d)}
[ -n "${PB_BENCH_DIR:-}" ] || trap 'rm -rf "$work"' EXIT
mkdir -p "$work/scenes"
# The scene exactly as bench/scaling.sh writes it (same cache keys).
# shellcheck source=bench/room_scene.sh
source bench/room_scene.sh
[ -f "$work/scenes/room-$n.yaml" ] || write_room_scene "$n" "$work/scenes/room-$n.yaml"
# The stages of configs/workflows/point_transfer.yaml (low) and hpm.yaml
# (high) up to their fits.
cat > "$work/fit-inputs-$n.yaml" <<YAML
name: fit-inputs
description: the inputs and outputs of the shipped workflows' mesh.fit stages
scene: scenes/room-$n.yaml
stages:
  scan: { uses: "\${scene.source.uses}", with: "\${scene.source.with}" }
  normals: { uses: points.normals, in: { points: scan.points }, with: { k: 16, orientation: auto } }
  low_poisson: { uses: mesh.poisson, in: { points: normals.points }, with: { depth: "\${scene.params.depth_low}", trim: 0 } }
  low_trim: { uses: mesh.trim, in: { mesh: low_poisson.mesh, points: normals.points } }
  low_clean: { uses: mesh.clean, in: { mesh: low_trim.mesh } }
  low: { uses: mesh.decimate, in: { mesh: low_clean.mesh, points: normals.points }, with: { target_faces: "\${scene.params.faces_low}" } }
  low_fit: { uses: mesh.fit, in: { mesh: low.mesh, points: normals.points } }
  high_poisson: { uses: mesh.poisson, in: { points: normals.points }, with: { depth: "\${scene.params.depth_high}", trim: 0 } }
  high_trim: { uses: mesh.trim, in: { mesh: high_poisson.mesh, points: normals.points } }
  high_clean: { uses: mesh.clean, in: { mesh: high_trim.mesh } }
  high: { uses: mesh.decimate, in: { mesh: high_clean.mesh, points: normals.points }, with: { target_faces: "\${scene.params.faces_high}" } }
  high_fit: { uses: mesh.fit, in: { mesh: high.mesh, points: normals.points } }
outputs:
  points: normals.points
  low: low.mesh
  low_fitted: low_fit.mesh
  high: high.mesh
  high_fitted: high_fit.mesh
YAML
out="$work/fit-inputs-$n"
"$bin" run "$work/fit-inputs-$n.yaml" --cache "$work/cache" --out "$out" -q
status=0
for mesh in low high; do
  echo "## $n points, $mesh mesh"
  if [ -n "$other" ]; then
    echo "$other:"
    "$other" "$out/$mesh.ply" "$out/points.ply" 2 "$out/${mesh}_fitted.ply" || status=1
    echo "$bench:"
  fi
  "$bench" "$out/$mesh.ply" "$out/points.ply" 2 "$out/${mesh}_fitted.ply" || status=1
done
exit "$status"
