#!/bin/sh
# ctest campaign_runs.scene_from_scan.statue: a statue as it is often
# delivered (photogrammetry, a fused RGB-D capture): one colored file without
# scanner stations, in millimetres, y up, the object on a plinth. synth.scan
# preset sculpture (800,000 points) is rewritten that way by
# tests/statue_file.py (about 244,000 points kept, 0.3 % of them moved into
# the air); `pointbake scene` reads
# it with --units mm --up 0,1,0 and picks the issue's statue budget itself
# (depth 9 / 8, 97,000 / 9,700 faces), and the four shipped workflows must
# hold issue 15's goals on it (tests/scene_from_scan.sh), about 3 minutes.
# It covers the path (units, up axis, no stations, the budget), not every
# failure found on it: at this size the LPM's hole pixels are 0.006 % (0.095 %
# with points.normals 3, whose plinth faced in; 0.082 % without the returns
# in the air), and were 0.107 % with mesh.fit along the normals only (version
# 3), which failed (0.214 %) only on the full-size stand-in (1,066,135
# points; docs/real-scans.md, "A statue delivered as one file"). Since
# points.normals 4 it also checks that the models face out.
# Usage: statue_file.sh POINTBAKE SOURCE_DIR PYTHON WORK_DIR
set -eu
bin=$1 src=$2 python=$3 dir=$4
rm -rf "$dir"
mkdir -p "$dir"
sh "$src/tests/sculpture_scan.sh" "$bin" "$dir" 800000
# 0.3 % of its points moved into the air, along their scanner's lines of
# sight: the workflows leave them out of their meshes (io.read_points ->
# points.outliers method air), or screened Poisson wraps the statue in a hull
# (docs/real-scans.md, "Points in the air").
"$python" "$src/tests/statue_file.py" "$dir/sculpture/scan.points.ply" "$dir/statue.ply" --air 0.003 | tee "$dir/statue.txt"
sh "$src/tests/scene_from_scan.sh" "$bin" "$src" "$python" "$dir/run" "$dir/statue.ply" --units mm --up 0,1,0
moved=$(sed -n 's/.*: \([0-9]*\) points moved into the air$/\1/p' "$dir/statue.txt")
"$python" - "$dir/run/out/runs" "$moved" <<'CHECK'
import glob, json, sys
runs, moved = sys.argv[1], int(sys.argv[2])
failed = False
for path in sorted(glob.glob(runs + '/*/*/run.jsonl')):
    removed = None
    for line in open(path):
        record = json.loads(line)
        if record.get('stage') == 'air':
            counters = (record.get('cached_run') or record).get('counters', {})
            removed = counters.get('removed')
    ok = removed is not None and 0.9 * moved <= removed <= 1.1 * moved
    failed |= not ok
    print(f"{'ok  ' if ok else 'FAIL'}  {path}: the air stage removed {removed} points, {moved} were moved into the air")
sys.exit(1 if failed else 0)
CHECK
# The models face out (a headset culls back faces): with points.normals 3
# the plinth and its ground faced in and down.
"$python" "$src/tests/statue_file.py" --check-sides "$dir"/run/out/runs/*/*/model.glb
# The budget is the point of this test: a statue's low mesh of about 10,000
# faces, where a rounded plinth edge costs a pixel column.
faces_low=$(sed -n 's/^ *faces_low: *\([0-9]*\).*/\1/p' "$dir/run/scene.yaml")
if [ -z "$faces_low" ] || [ "$faces_low" -gt 10000 ]; then
  echo "FAIL  pointbake scene chose faces_low '$faces_low' for the statue, not at most 10000 ($dir/run/scene.yaml)"
  exit 1
fi
echo "ok    the statue ran at faces_low $faces_low"
