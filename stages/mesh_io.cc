#include "stages/mesh_io.h"

#include <utility>

#include "stages/geometry/io/ply.h"
#include "stages/params.h"

namespace pb {

Expected<InputMesh> ReadInputMesh(StageContext& ctx, std::string_view stage_id,
                                  double progress_end) {
  InputMesh input;
  PB_ASSIGN_OR_RETURN(input.path, InputFilePath(ctx, stage_id, "mesh", "mesh.ply"));
  PB_PHASE(ctx, "io");
  PlyReadOptions options;
  options.progress = [&ctx, progress_end](double fraction) {
    ctx.progress(progress_end * fraction);
  };
  PB_ASSIGN_OR_RETURN(PlyMesh ply, ReadPlyMesh(input.path, options));
  input.mesh = std::move(ply.mesh);
  return input;
}

nlohmann::json InputMeshMetaWith(const StageContext& ctx, const Mesh& mesh,
                                 const nlohmann::json& changes) {
  const nlohmann::json& input_meta = ctx.input("mesh").meta;
  nlohmann::json meta = input_meta.is_object() ? input_meta : nlohmann::json::object();
  meta.update({{"origin", mesh.origin},
               {"vertices", mesh.vertex_count()},
               {"faces", mesh.face_count()},
               {"has_normals", mesh.has_normals()},
               {"has_colors", mesh.has_colors()},
               {"has_uvs", mesh.has_uvs()}});
  meta.update(changes);
  return meta;
}

Status WriteOutputMesh(StageContext& ctx, const Mesh& mesh, nlohmann::json meta) {
  {
    PB_PHASE(ctx, "io");
    PB_RETURN_IF_ERROR(WritePlyMesh(ctx.output_path("mesh", "mesh.ply"), mesh));
  }
  ctx.set_output_meta("mesh", std::move(meta));
  return Status::Ok();
}

}  // namespace pb
