#!/bin/sh
# ctest campaign_runs.scene_from_scan.*: a user's first run on their own scan.
# `pointbake scene` writes the scene (viewpoints and parameters read off the
# points, no hand-written values), the four shipped workflows run on it with
# their frames on magenta, and tools/check_real_campaign.py holds the result
# to issue 15's goals, as campaign_runs.real_* does for the hand-written
# scenes.
# Usage: scene_from_scan.sh POINTBAKE SOURCE_DIR PYTHON WORK_DIR SCAN [SCENE ARGS...]
set -eu
bin=$1 src=$2 python=$3 dir=$4 scan=$5
shift 5
rm -rf "$dir"
mkdir -p "$dir"
"$bin" scene "$scan" -o "$dir/scene.yaml" --name scene-from-scan "$@"
{
  echo "name: scene-from-scan"
  echo "scenes: [ scene.yaml ]"
  echo "workflows:"
  for workflow in hpm lpm remeshing point_transfer; do
    echo "  - file: $src/configs/workflows/$workflow.yaml"
    echo "    set: { render.background: \"255,0,255\" }"
  done
} > "$dir/campaign.yaml"
"$bin" campaign "$dir/campaign.yaml" --cache "$dir/cache" --out "$dir/out" -q --jobs 2
"$python" "$src/tools/check_real_campaign.py" "$dir/out" --max-holes 0.002 \
  --background 255,0,255 --max-background 0.002
