#!/usr/bin/env bash
# uv.unwrap figures (issue 16): our `conformal` and `charts` unwrappers and
# Blender 3.4's Smart UV Project on the same PLY meshes, one at a time, all
# measured by the same code (MeasureAtlas: charts, coverage, L2/Linf stretch,
# seam length). Our times come from build/bench/uv_unwrap_tool (unwrap +
# measuring, PLY reading excluded); Blender's from
# bench/uv_blender.py (smart_project only, import excluded); cpu is the
# tool's whole task-clock (PLY reading included).
# Usage: bench/uv_unwrap.sh [BUILD_DIR] NAME=MESH.ply...
# Prints a Markdown table; with DOC=docs/uv.md it also replaces the table
# between the lines "<!-- bench/uv_unwrap.sh -->" and "<!-- end -->" there.
# Env: SIZE (default 4096), THREADS (0 = all cores), BLENDER=0 skips Blender,
#      METHODS (default "conformal charts"), SYNTH_CELLS="0.05 0.007" also
#      unwraps SynthTruthMesh(room, cell) (0.007 m: ~4.8e6 faces; no Blender).
# Meshes: build/pointbake run bench/uv_meshes.yaml (bunny, and the pump with
# --set scan.path=...) and bench/uv_meshes_room.yaml.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
tool="$build/bench/uv_unwrap_tool"
[ -x "$tool" ] || { echo "no $tool: build uv_unwrap_tool (Release) first" >&2; exit 1; }
size=${SIZE:-4096}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
run_tool() {  # env passed through; prints the tool's report line
  "$tool" 2>&1 | grep -E '^faces'
}
# "faces F vertices a->b: T s (...), charts C, coverage X, stretch L2 Y Linf Z, seams S m, ..."
row() {  # name method time line
  python3 - "$1" "$2" "$3" "$4" <<'PY'
import re, sys
name, method, seconds, line = sys.argv[1:]
m = re.search(r"faces (\d+).*charts (\d+), coverage ([\d.]+), stretch L2 ([\d.]+) Linf ([\d.]+), seams ([\d.]+) m", line)
faces, charts, cov, l2, linf, seams = m.groups()
print(f"| {name} | {int(faces):,} | {method} | {seconds} | {int(charts):,} | {cov[:5]} | {l2} | {linf} | {float(seams):,.1f} m |")
PY
}
out="$tmp/table.md"
{
  echo "| mesh | faces | method | time | charts | coverage | L2 | L∞ | seams |"
  echo "|---|---:|---|---:|---:|---:|---:|---:|---:|"
} > "$out"
for cell in ${SYNTH_CELLS:-}; do
  for method in ${METHODS:-conformal charts}; do
    line=$(PB_UV_SYNTH_CELL=$cell PB_UV_SIZE=$size PB_UV_THREADS=${THREADS:-0} PB_UV_METHOD=$method run_tool)
    seconds=$(echo "$line" | sed -E 's/.*: ([0-9.]+) s \(incl.*/\1 s/')
    row "room truth, cell $cell m" "$method" "$seconds" "$line" >> "$out"
  done
done
for spec in "$@"; do
  name=${spec%%=*}
  mesh=${spec#*=}
  for method in ${METHODS:-conformal charts}; do
    line=$(PB_UV_MESH=$mesh PB_UV_SIZE=$size PB_UV_THREADS=${THREADS:-0} PB_UV_METHOD=$method run_tool)
    seconds=$(echo "$line" | sed -E 's/.*: ([0-9.]+) s \(incl.*/\1 s/')
    row "$name" "$method" "$seconds" "$line" >> "$out"
  done
  if [ "${BLENDER:-1}" != 0 ] && command -v blender >/dev/null; then
    blender -b --factory-startup --python bench/uv_blender.py -- "$mesh" 66 0.001 "$tmp/blender.ply" \
      > "$tmp/blender.log" 2>&1 || true
    seconds=$(grep '^blender' "$tmp/blender.log" | sed -E 's/.*unwrap ([0-9.]+) s.*/\1 s/')
    line=$(PB_UV_MESH=$tmp/blender.ply PB_UV_SIZE=$size PB_UV_MEASURE_ONLY=1 run_tool)
    row "$name" "Blender Smart UV Project" "$seconds" "$line" >> "$out"
  fi
done
cat "$out"
if [ -n "${DOC:-}" ]; then
  python3 - "$DOC" "$out" <<'PY'
import sys
doc, table = sys.argv[1], open(sys.argv[2]).read()
text = open(doc).read()
start, end = "<!-- bench/uv_unwrap.sh -->\n", "<!-- end -->\n"
i, j = text.index(start) + len(start), text.index(end)
open(doc, "w").write(text[:i] + table + text[j:])
PY
fi
