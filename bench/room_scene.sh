# Sourced by bench/scaling.sh and bench/fit.sh: write_room_scene N FILE writes
# the synthetic room scanned with N points as a scene, meshes in the paper's
# proportions (low: one face per ~120 points, at least 8,000; high: one per
# ~6.5; Poisson depth 9 up to 3·10^6 points, 10 above; low depth 8), maps
# 4096², frames 512². Both scripts write the same file for the same N, so
# their caches serve each other.
write_room_scene() {
  local n=$1 file=$2
  local low=$(( n / 120 > 8000 ? n / 120 : 8000 ))
  local high=$(( n * 2 / 13 ))
  local depth_high=$(( n > 3000000 ? 10 : 9 ))
  cat > "$file" <<YAML
name: room-$n
description: synthetic room, $n points (bench/scaling.sh)
units: m
truth: true
source:
  uses: synth.scan
  with: { preset: room, points: $n, stations: 3, noise_mm: 2 }
viewpoints:
  - { name: door, eye: [-1.2, -1.9, 1.6], target: [1.5, 1.5, 1.2], fov_deg: 75 }
params: { depth_high: $depth_high, faces_high: $high, depth_low: 8, faces_low: $low, texture: 4096, frame_size: 512 }
YAML
}
