#!/bin/sh
# synth.scan preset sculpture with six stations, 3 mm of noise and seed 7 (the
# stand-in the statue and floaters ctests start from), written to
# DIR/sculpture/scan.points.ply (binary PLY: meters, z up, colors, a station
# per point and the stations in comments).
# Usage: sculpture_scan.sh POINTBAKE DIR POINTS
set -eu
bin=$1 dir=$2 points=$3
cat > "$dir/sculpture.yaml" <<WORKFLOW
name: sculpture-points
stages:
  scan:
    uses: synth.scan
    with: { preset: sculpture, points: $points, stations: 6, noise_mm: 3, seed: 7 }
WORKFLOW
"$bin" run "$dir/sculpture.yaml" --cache "$dir/cache" --out "$dir/sculpture" -q
