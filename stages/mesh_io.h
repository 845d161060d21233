// The `mesh` artifact as stage adapters read and write it: one binary PLY
// file, mesh.ply (stages/geometry/io/ply.h), plus the artifact's JSON meta
// (origin, counts, which attributes it has, and what earlier stages
// recorded). The mesh counterpart of stages/points_io.h.
#pragma once

#include <string>
#include <string_view>

#include "base/status.h"
#include "engine/stage.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

struct InputMesh {
  std::string path;  // the input file, for error context
  Mesh mesh;
};

// Reads mesh.ply of input port "mesh" (any one-file artifact works too)
// inside an "io" phase, reporting the read as stage progress
// 0..`progress_end`. Errors name `stage_id` when the input is missing, else
// the file and place.
Expected<InputMesh> ReadInputMesh(StageContext& ctx, std::string_view stage_id,
                                  double progress_end);

// The meta of input "mesh" with the mesh's own facts (origin, vertices,
// faces, has_normals/colors/uvs) and then the top-level keys of `changes`
// set over it: what a stage that transforms a mesh passes on.
nlohmann::json InputMeshMetaWith(const StageContext& ctx, const Mesh& mesh,
                                 const nlohmann::json& changes);

// Writes `mesh` as output "mesh" (mesh.ply) inside an "io" phase, then sets
// that output's meta.
Status WriteOutputMesh(StageContext& ctx, const Mesh& mesh, nlohmann::json meta);

}  // namespace pb
