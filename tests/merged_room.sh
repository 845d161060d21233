#!/bin/sh
# ctest campaign_runs.scene_from_scan.merged_room: a room registered and
# exported as one cloud without its scanner stations (tests/merged_room.py
# writes one), as a user brings it. `pointbake scene` must view it from
# inside, the four shipped workflows must hold issue 15's goals on it
# (tests/scene_from_scan.sh), and every model must face into the room: an
# inside-out room looks right in our two-sided frames but shows nothing in a
# headset, which culls back faces. With KIND corridor, the same for a
# corridor open at both ends (ctest campaign_runs.scene_from_scan.corridor).
# Usage: merged_room.sh POINTBAKE SOURCE_DIR PYTHON WORK_DIR [corridor]
set -eu
bin=$1 src=$2 python=$3 dir=$4 kind=${5:-}
rm -rf "$dir"
mkdir -p "$dir"
"$python" "$src/tests/merged_room.py" make "$dir/room.ply" $kind
sh "$src/tests/scene_from_scan.sh" "$bin" "$src" "$python" "$dir/run" "$dir/room.ply"
if ! grep -q "name: inside1" "$dir/run/scene.yaml"; then
  echo "FAIL  pointbake scene did not view the room from inside ($dir/run/scene.yaml)"
  exit 1
fi
"$python" "$src/tests/merged_room.py" check "$dir"/run/out/runs/*/*/model.glb
