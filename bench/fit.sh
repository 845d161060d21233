#!/usr/bin/env bash
# mesh.fit alone on the synthetic room (docs/bench-fit.md): the scan, its
# normals and the low and high decimated meshes of the shipped workflows
# (bench/scaling.sh's scene, so its cache serves), made by running the
# workflows up to their fits, then `fit_bench` on each mesh: the fit's wall
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
# The shipped workflows themselves, run up to their fits (`--until` copies
# each named stage's outputs): point transfer's low mesh (LPM's too) and
# HPM's high mesh, the scan's points with normals, and each fit's output.
out="$work/fit-inputs-$n"
"$bin" run configs/workflows/point_transfer.yaml --scene "$work/scenes/room-$n.yaml" \
  --cache "$work/cache" --out "$out" -q --until normals --until low --until low_fit
"$bin" run configs/workflows/hpm.yaml --scene "$work/scenes/room-$n.yaml" \
  --cache "$work/cache" --out "$out" -q --until high --until high_fit
status=0
for mesh in low high; do
  echo "## $n points, $mesh mesh"
  args=("$out/$mesh.mesh.ply" "$out/normals.points.ply" 2 "$out/${mesh}_fit.mesh.ply")
  if [ -n "$other" ]; then
    echo "$other:"
    "$other" "${args[@]}" || status=1
    echo "$bench:"
  fi
  "$bench" "${args[@]}" || status=1
done
exit "$status"
