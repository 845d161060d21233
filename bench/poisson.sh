#!/usr/bin/env bash
# Screened Poisson figures for issue 4, in one run on this machine: Open3D
# 0.16 (what mesh.poisson uses) and PCL 1.13 (the alternative) on the same
# synthetic room scans with normals, depths 8/9/10, 10^6 and 10^7 points:
# time, peak RSS, faces, manifoldness, distance to the analytic truth.
# Needs libpcl-dev (apt install libpcl-dev) besides the project's packages;
# builds into build-bench/. Prints a Markdown table and keeps the JSON lines
# in OUT_DIR/results.jsonl; passes or fails on nothing.
# Usage: bench/poisson.sh [OUT_DIR] [POINTS...]   (default out/bench/poisson 1000000 10000000)
# Env: DEPTHS (default "8 9 10"), BACKENDS (default "open3d pcl"), THREADS (2),
#      TRIMS (density quantiles for Open3D, default "0 0.02"),
#      PCL_MAX_POINTS (default 1000000: PCL runs only on clouds up to this size),
#      APPEND=1 keeps earlier lines of results.jsonl (to add rows to a run),
#      TABLE_ONLY=1 prints the table of an earlier run's results.jsonl
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/bench/poisson}
shift || true

[ $# -gt 0 ] && sizes=("$@") || sizes=(1000000 10000000)
depths=${DEPTHS:-8 9 10}
backends=${BACKENDS:-open3d pcl}
threads=${THREADS:-2}
pcl_max=${PCL_MAX_POINTS:-1000000}
trims=${TRIMS:-0 0.02}
mkdir -p "$out"

results="$out/results.jsonl"
if [ "${TABLE_ONLY:-0}" != 1 ]; then
cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DPB_BUILD_TESTS=OFF >/dev/null
cmake --build build-bench -j"$(nproc)" --target pointbake poisson_bench >/dev/null

[ "${APPEND:-0}" = 1 ] || : > "$results"
for n in "${sizes[@]}"; do
  cat > "$out/gen-$n.yaml" <<YAML
name: bench_poisson_gen
stages:
  scan: { uses: synth.scan, with: { preset: room, points: $n, stations: 3, noise_mm: 2, seed: 1 } }
  normals: { uses: points.normals, in: { points: scan.points }, with: { k: 16 } }
outputs: { points: normals.points, truth: scan.truth }
YAML
  build-bench/pointbake run "$out/gen-$n.yaml" --cache "$out/cache" --out "$out/gen-$n" -q >/dev/null
  for d in $depths; do
    for b in $backends; do
      if [ "$b" = pcl ] && [ "$n" -gt "$pcl_max" ]; then continue; fi
      for t in $([ "$b" = open3d ] && echo "$trims" || echo 0); do
        echo "poisson: $b depth $d trim $t on $n points..." >&2
        # PCL prints "Vertex pair not in list" where its iso-surface cracks.
        build-bench/bench/poisson_bench --backend "$b" --depth "$d" --threads "$threads" \
          --trim "$t" --points "$out/gen-$n/points.ply" --truth "$out/gen-$n/truth" \
          > "$out/last.txt"
        line=$(grep '^{' "$out/last.txt")
        cracks=$(grep -c 'Vertex pair not in list' "$out/last.txt" || true)
        echo "${line%\}}, \"crack_messages\": $cracks}" | tee -a "$results" >&2
      done
    done
  done
done
fi

python3 - "$results" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
print("| implementation | points | depth | trim | time | peak RSS | faces | boundary edges / cracks | non-manifold edge faces / small components | mesh→truth mean / p95 | truth→mesh mean / p95 | Hausdorff |")
print("|---|---:|---:|---:|---:|---:|---:|---|---|---|---|---:|")
for r in rows:
    name = {"open3d": "Open3D 0.16", "pcl": "PCL 1.13"}[r["backend"]]
    print(f"| {name} | {r['points']:,} | {r['depth']} | {r.get('trim', 0):g} | {r['seconds']:.1f} s | {r['peak_rss_mib']:,.0f} MiB | "
          f"{r['faces']:,} | {r['boundary_edges']:,} / {r.get('crack_messages', 0)} | "
          f"{r['nonmanifold_edge_faces']} / {r['small_components']} | "
          f"{r['mesh_to_truth_mean_mm']:.2f} / {r['mesh_to_truth_p95_mm']:.2f} mm | "
          f"{r['truth_to_mesh_mean_mm']:.2f} / {r['truth_to_mesh_p95_mm']:.2f} mm | {r['hausdorff_mm']:.0f} mm |")
PY
