#!/bin/sh
# ctest campaign_runs.scene_from_scan.statue: a statue as it is often
# delivered (photogrammetry, a fused RGB-D capture): one colored file without
# scanner stations, in millimetres, y up, the object on a plinth. synth.scan
# preset sculpture (800,000 points) is rewritten that way by
# tests/statue_file.py (about 244,000 points kept); `pointbake scene` reads
# it with --units mm --up 0,1,0 and picks the issue's statue budget itself
# (depth 9 / 8, 97,000 / 9,700 faces), and the four shipped workflows must
# hold issue 15's goals on it (tests/scene_from_scan.sh), about 3 minutes.
# It covers the path (units, up axis, no stations, the budget), not every
# failure found on it: at this size the LPM's hole pixels are 0.082 %, and
# 0.107 % with mesh.fit along the normals only (version 3), which failed
# (0.214 %) only on the full-size stand-in (1,066,135 points;
# docs/real-scans.md, "A statue delivered as one file").
# Usage: statue_file.sh POINTBAKE SOURCE_DIR PYTHON WORK_DIR
set -eu
bin=$1 src=$2 python=$3 dir=$4
rm -rf "$dir"
mkdir -p "$dir"
cat > "$dir/sculpture.yaml" <<WORKFLOW
name: sculpture-points
stages:
  scan:
    uses: synth.scan
    with: { preset: sculpture, points: 800000, stations: 6, noise_mm: 3, seed: 7 }
WORKFLOW
"$bin" run "$dir/sculpture.yaml" --cache "$dir/cache" --out "$dir/sculpture" -q
"$python" "$src/tests/statue_file.py" "$dir/sculpture/scan.points.ply" "$dir/statue.ply"
sh "$src/tests/scene_from_scan.sh" "$bin" "$src" "$python" "$dir/run" "$dir/statue.ply" --units mm --up 0,1,0
# The budget is the point of this test: a statue's low mesh of about 10,000
# faces, where a rounded plinth edge costs a pixel column.
faces_low=$(sed -n 's/^ *faces_low: *\([0-9]*\).*/\1/p' "$dir/run/scene.yaml")
if [ -z "$faces_low" ] || [ "$faces_low" -gt 10000 ]; then
  echo "FAIL  pointbake scene chose faces_low '$faces_low' for the statue, not at most 10000 ($dir/run/scene.yaml)"
  exit 1
fi
echo "ok    the statue ran at faces_low $faces_low"
