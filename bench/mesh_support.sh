#!/usr/bin/env bash
# The figures of docs/mesh-real-scans.md (issue 15) on this machine: a scene's
# low mesh (depth_low -> faces_low), high mesh (depth_high -> faces_high) and
# Remeshing mesh (high -> faces_low), meshed the old way (mesh.poisson's
# density trim 0.01, mesh.clean without hole filling) and the shipped way
# (mesh.trim, mesh.clean filling small holes), each measured by
# build/bench/mesh_support (invented area, boundary edges, pin-holes) with
# its stage times, and rendered from the scene's viewpoints (frames in
# OUT/{before,after}/r_*/). Passes or fails on nothing.
# Usage: bench/mesh_support.sh [SCENE] [OUT]     default configs/scenes/pump.yaml, /tmp/mesh_support
# "Before" keeps this version's other mesh.clean fixes (faces at misoriented
# edges are dropped), so it is close to, not exactly, the old pipeline.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=$(realpath "${1:-configs/scenes/pump.yaml}")
out=${2:-/tmp/mesh_support}
bin=build/pointbake
measure=build/bench/mesh_support
[ -x "$bin" ] && [ -x "$measure" ] || { echo "build first: cmake --build build --target pointbake mesh_support" >&2; exit 1; }
mkdir -p "$out"
for variant in before after; do
  if [ $variant = before ]; then
    poisson_trim=0.01; fill="fill_hole_edges: 0, fill_hole_spacings: 0"
    high_in=high_poisson; low_in=low_poisson; trims=""
  else
    poisson_trim=0; fill=""
    high_in=high_trim; low_in=low_trim
    trims="  high_trim: { uses: mesh.trim, in: { mesh: high_poisson.mesh, points: normals.points } }
  low_trim: { uses: mesh.trim, in: { mesh: low_poisson.mesh, points: normals.points } }"
  fi
  frames='with: { viewpoints: "${scene.viewpoints}", size: 512, background: [255, 0, 255] }'
  cat > "$out/$variant.yaml" <<YAML
name: mesh_support_$variant
scene: $scene
stages:
  scan: { uses: "\${scene.source.uses}", with: "\${scene.source.with}" }
  normals: { uses: points.normals, in: { points: scan.points }, with: { k: 16, orientation: auto } }
  high_poisson: { uses: mesh.poisson, in: { points: normals.points }, with: { depth: "\${scene.params.depth_high}", trim: $poisson_trim } }
  low_poisson: { uses: mesh.poisson, in: { points: normals.points }, with: { depth: "\${scene.params.depth_low}", trim: $poisson_trim } }
$trims
  high_clean: { uses: mesh.clean, in: { mesh: $high_in.mesh }, with: { $fill } }
  low_clean: { uses: mesh.clean, in: { mesh: $low_in.mesh }, with: { $fill } }
  high: { uses: mesh.decimate, in: { mesh: high_clean.mesh }, with: { target_faces: "\${scene.params.faces_high}" } }
  remesh: { uses: mesh.decimate, in: { mesh: high_clean.mesh }, with: { target_faces: "\${scene.params.faces_low}" } }
  low: { uses: mesh.decimate, in: { mesh: low_clean.mesh }, with: { target_faces: "\${scene.params.faces_low}" } }
  r_low: { uses: render.frames, in: { mesh: low.mesh }, $frames }
  r_high: { uses: render.frames, in: { mesh: high.mesh }, $frames }
  r_remesh: { uses: render.frames, in: { mesh: remesh.mesh }, $frames }
outputs: { points: normals.points, low: low.mesh, high: high.mesh, remesh: remesh.mesh,
           r_low: r_low.frames, r_high: r_high.frames, r_remesh: r_remesh.frames }
YAML
  "$bin" run "$out/$variant.yaml" --cache "$out/cache" --out "$out/$variant" --jobs 1 --threads 1 -q >/dev/null
  echo "== $variant"
  "$measure" "$out/$variant/points.ply" "$out/$variant/low.ply" "$out/$variant/high.ply" "$out/$variant/remesh.ply"
  python3 - "$out/$variant/run.json" <<'PY'
import json, sys
wall = {s["stage"]: s.get("wall_s") or s.get("cached_run", {}).get("wall_s", 0)
        for s in json.load(open(sys.argv[1]))["stages"]}
for mesh, chain in (("low", ["low_poisson", "low_trim", "low_clean", "low"]),
                    ("high", ["high_poisson", "high_trim", "high_clean", "high"]),
                    ("remesh", ["high_poisson", "high_trim", "high_clean", "remesh"])):
    parts = [(s, wall[s]) for s in chain if s in wall]
    print(f"{mesh}: {sum(w for _, w in parts):.1f} s (" +
          ", ".join(f"{s} {w:.1f}" for s, w in parts) + ")")
PY
done
