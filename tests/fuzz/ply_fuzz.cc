// libFuzzer target for the PLY reader (pb::ReadPlyPoints, pb::ReadPlyMesh).
//
// Seeds: the shared files bunny/bun_zipper.ply (ascii, with faces) and
// pump_e57/pumpA.ply (binary) (run.sh). The input is handed over through a
// memfd, as /proc/self/fd/N, because the reader takes a path. Besides
// sanitizer findings, an accepted file must give consistent arrays, and a
// mesh's triangle indices must refer to existing vertices.
#include <cstddef>
#include <cstdint>

#include "stages/geometry/io/ply.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const pb::fuzz::FuzzInput input("ply_fuzz", data, size);
  if (!input.ok()) return 0;
  pb::PlyReadOptions options;
  options.drop_invalid_points = (size & 1) != 0;  // exercise both NaN paths
  auto points = pb::ReadPlyPoints(input.path(), options);
  if (points.ok() && !pb::Validate(points->points).ok()) __builtin_trap();
  auto mesh = pb::ReadPlyMesh(input.path(), options);
  if (mesh.ok()) {
    if (!pb::Validate(mesh->mesh).ok()) __builtin_trap();
    const size_t vertices = mesh->mesh.positions.size() / 3;
    if (mesh->mesh.indices.size() % 3 != 0) __builtin_trap();
    for (uint32_t index : mesh->mesh.indices) {
      if (index >= vertices) __builtin_trap();
    }
  }
  return 0;
}
