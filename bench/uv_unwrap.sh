#!/usr/bin/env bash
# uv.unwrap figures for issue 5: our `charts` (and `per_triangle`) unwrapper
# and Blender 3.4's Smart UV Project on the same PLY meshes, one at a time.
# Our times come from build/bench/uv_unwrap_tool (unwrap + measuring, PLY
# reading excluded); Blender's from bench/uv_blender.py
# (smart_project only, import excluded). Prints what each run prints.
# Usage: bench/uv_unwrap.sh [BUILD_DIR] MESH.ply...
# Env: SIZE (default 4096), THREADS (0 = all cores), BLENDER=0 skips Blender,
#      SYNTH_CELLS="0.05 0.007" also unwraps SynthTruthMesh(room, cell)
#      (0.05 m: ~9.4e4 faces, 0.007 m: ~4.8e6 faces).
# Meshes: build/pointbake run configs/workflows/meshes.yaml writes
# out/meshes/low.ply (2.4e5 faces); --set low.target_faces=100000 gives the
# 1e5-face one; --set scan.points=3000000 --set high_poisson.depth=10
# --set high.target_faces=6000000 a ~5e6-face high mesh.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
tool="$build/bench/uv_unwrap_tool"
[ -x "$tool" ] || { echo "no $tool: build uv_unwrap_tool (Release) first" >&2; exit 1; }
run_tool() {
  "$tool" 2>&1 | grep -E '^faces|^overlap'
}
for cell in ${SYNTH_CELLS:-}; do
  echo "== SynthTruthMesh(room, $cell)"
  PB_UV_SYNTH_CELL=$cell PB_UV_SIZE=${SIZE:-4096} PB_UV_THREADS=${THREADS:-0} run_tool
done
for mesh in "$@"; do
  echo "== $mesh"
  PB_UV_MESH=$mesh PB_UV_SIZE=${SIZE:-4096} PB_UV_THREADS=${THREADS:-0} run_tool
  PB_UV_MESH=$mesh PB_UV_SIZE=${SIZE:-4096} PB_UV_THREADS=${THREADS:-0} PB_UV_METHOD=per_triangle \
    run_tool || echo "per_triangle: does not fit at SIZE=${SIZE:-4096}"
  if [ "${BLENDER:-1}" != 0 ] && command -v blender >/dev/null; then
    blender -b --factory-startup --python bench/uv_blender.py -- "$mesh" 2>&1 | grep '^blender'
  fi
done
