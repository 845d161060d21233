#!/usr/bin/env bash
# Runs every fuzz target for SECONDS each, seeded with the shared sample files.
# Usage: tests/fuzz/run.sh BUILD_DIR [SECONDS]
set -euo pipefail
build=${1:?usage: run.sh BUILD_DIR [SECONDS]}
seconds=${2:-60}
here=$(cd "$(dirname "$0")" && pwd)
data=$(cd "$here/../../../shared/data" 2>/dev/null && pwd || echo /work/shared/data)
declare -A seeds=(
  [ply]="$data/bunny/bun_zipper.ply $data/pump_e57/pumpA.ply"
  [pcd]="$data/livingroom_fragment/fragment.pcd $data/office_kinect/office1.pcd"
  [ptx]="$data/ptx/1.2-with-color.ptx $data/ptx/no-color.ptx $data/ptx/multiple-and-transform.ptx $data/ptx/complex-transform.ptx"
  [e57]="$data/bunny/bunnyDouble.e57 $data/pump_e57/pumpAVisualReferenceImage.e57"
)
for format in ply pcd ptx e57; do
  corpus=$(mktemp -d)
  for f in ${seeds[$format]}; do cp "$f" "$corpus/"; done
  echo "== $format: ${seconds}s"
  "$build/tests/fuzz/${format}_fuzz" -max_total_time="$seconds" -max_len=4194304 \
    -rss_limit_mb=4096 "$corpus"
  rm -rf "$corpus"
done
