// The campaign's 3-D viewer, written beside report.html (report.h):
//
//   <report_dir>/viewer/index.html, viewer.js   the page (from
//                 cli/report/viewer/ in the source tree; docs/viewer.md)
//   <report_dir>/viewer/models.json
//     {"format": "pointbake-viewer", "version": 1, "campaign": NAME,
//      "scenes": [{"name": SCENE,
//                  "viewpoints": [{"name", "eye", "target", "up", "fov_deg"}]
//                                 (scene coordinates: z up, meters; from the
//                                  first run's frames/frames.json),
//                  "frame_size": [width, height],
//                  "models": [{"run", "workflow", "variant", "title",
//                              "glb": "../../runs/.../model.glb",
//                              "glb_ktx2": ".../model_ktx2.glb" or null,
//                              "frames": ".../frames" or null,
//                              "figures": {faces, texture_width,
//                                texture_height, texture_bytes, fps, device,
//                                flip_truth, ms_ssim_truth, flip_hpm}}]}]}
//     paths relative to the viewer folder; only runs with a model.glb.
//   <report_dir>/viewer/lib/   three.js (npm `three`, pinned in
//                 tools/package-lock.json): build/three.module.js as
//                 three.module.js and the addons the page imports under
//                 addons/, with the Basis Universal transcoder for KTX2.
#include <filesystem>
#include <string>
#include <vector>

#include "base/env.h"
#include "cli/report/report_internal.h"
#include "stages/geometry/io/frames.h"

namespace pb::report_internal {
namespace {

// Files of npm `three` the page needs, relative to its package folder, and
// where they go under lib/.
struct LibFile {
  const char* from;
  const char* to;
};
constexpr LibFile kThreeFiles[] = {
    {"LICENSE", "LICENSE"},
    {"build/three.module.js", "three.module.js"},
    {"examples/jsm/controls/OrbitControls.js", "addons/controls/OrbitControls.js"},
    {"examples/jsm/loaders/GLTFLoader.js", "addons/loaders/GLTFLoader.js"},
    {"examples/jsm/loaders/KTX2Loader.js", "addons/loaders/KTX2Loader.js"},
    {"examples/jsm/utils/BufferGeometryUtils.js", "addons/utils/BufferGeometryUtils.js"},
    {"examples/jsm/utils/WorkerPool.js", "addons/utils/WorkerPool.js"},
    {"examples/jsm/libs/ktx-parse.module.js", "addons/libs/ktx-parse.module.js"},
    {"examples/jsm/libs/zstddec.module.js", "addons/libs/zstddec.module.js"},
    {"examples/jsm/libs/basis/basis_transcoder.js", "addons/libs/basis/basis_transcoder.js"},
    {"examples/jsm/libs/basis/basis_transcoder.wasm", "addons/libs/basis/basis_transcoder.wasm"},
    {"examples/jsm/math/ColorSpaces.js", "addons/math/ColorSpaces.js"},
    {"examples/jsm/webxr/VRButton.js", "addons/webxr/VRButton.js"},
};

std::string ToolsDir() {
  if (const char* dir = std::getenv("POINTBAKE_TOOLS_DIR"); dir && *dir) return dir;
  return std::string(PB_SOURCE_DIR) + "/tools";
}

// `path` relative to `base`, with '/' separators (both made absolute).
std::string RelativeUrl(const std::string& path, const std::string& base) {
  const auto absolute = [](const std::string& p) {
    return std::filesystem::weakly_canonical(std::filesystem::absolute(p));
  };
  return absolute(path).lexically_relative(absolute(base)).generic_string();
}

Json Figures(const Row& r) {
  auto number = [](const Opt& v) { return v ? Json(*v) : Json(nullptr); };
  return Json{{"faces", number(r.faces)},
              {"texture_width", number(r.texture_width)},
              {"texture_height", number(r.texture_height)},
              {"texture_bytes", number(r.texture_bytes)},
              {"fps", number(r.fps)},
              {"device", r.device},
              {"flip_truth", number(r.vs_truth[4])},
              {"ms_ssim_truth", number(r.vs_truth[3])},
              {"flip_hpm", number(r.vs_hpm[4])}};
}

Status CopyFile(Env* env, const std::string& from, const std::string& to) {
  PB_ASSIGN_OR_RETURN(const std::string bytes, env->ReadFile(from));
  PB_RETURN_IF_ERROR(env->CreateDirs(std::filesystem::path(to).parent_path().string()));
  return env->WriteFileAtomic(to, bytes);
}

}  // namespace

Status WriteViewer(const Campaign& c, const std::string& report_dir) {
  Env* env = Env::Default();
  const std::string viewer_dir = JoinPath(report_dir, "viewer");
  PB_RETURN_IF_ERROR(env->CreateDirs(JoinPath(viewer_dir, "lib")));
  Json scenes = Json::array();
  for (const std::string& scene : c.scenes) {
    Json models = Json::array(), viewpoints = Json::array(), frame_size = nullptr;
    for (const Row& r : c.rows) {
      if (r.scene != scene) continue;
      const std::string glb = JoinPath(r.run_dir, "model.glb");
      if (!std::filesystem::exists(glb)) continue;
      const std::string ktx2 = JoinPath(r.run_dir, "model_ktx2.glb");
      const std::string frames = JoinPath(r.run_dir, "frames");
      const bool has_frames = std::filesystem::exists(JoinPath(frames, kFramesIndexFile));
      if (has_frames && viewpoints.empty()) {
        const std::string index_path = JoinPath(frames, kFramesIndexFile);
        PB_ASSIGN_OR_RETURN(const std::string text, env->ReadFile(index_path));
        PB_ASSIGN_OR_RETURN(const FramesIndex index, FramesIndexFromJson(text, index_path));
        frame_size = Json::array({index.width, index.height});
        for (const FrameEntry& frame : index.frames) {
          if (!frame.viewpoint) continue;
          const FrameViewpoint& v = *frame.viewpoint;
          Json entry = {{"name", frame.name}, {"file", frame.file}, {"eye", v.eye}, {"target", v.target}};
          entry["up"] = v.up ? Json(*v.up) : Json(nullptr);
          entry["fov_deg"] = v.fov_deg ? Json(*v.fov_deg) : Json(nullptr);
          viewpoints.push_back(entry);
        }
      }
      models.push_back({{"run", r.name},
                        {"workflow", r.workflow},
                        {"variant", r.variant},
                        {"title", DisplayName(r)},
                        {"glb", RelativeUrl(glb, viewer_dir)},
                        {"glb_ktx2", std::filesystem::exists(ktx2) ? Json(RelativeUrl(ktx2, viewer_dir)) : Json(nullptr)},
                        {"frames", has_frames ? Json(RelativeUrl(frames, viewer_dir)) : Json(nullptr)},
                        {"figures", Figures(r)}});
    }
    if (models.empty()) continue;
    scenes.push_back({{"name", scene}, {"viewpoints", viewpoints}, {"frame_size", frame_size}, {"models", models}});
  }
  const Json index = {{"format", "pointbake-viewer"}, {"version", 1}, {"campaign", c.name}, {"scenes", scenes}};
  PB_RETURN_IF_ERROR(env->WriteFileAtomic(JoinPath(viewer_dir, "models.json"), index.dump(1) + "\n"));
  const std::string page_dir = std::string(PB_SOURCE_DIR) + "/cli/report/viewer";
  for (const char* file : {"index.html", "viewer.js"}) {
    PB_RETURN_IF_ERROR(CopyFile(env, JoinPath(page_dir, file), JoinPath(viewer_dir, file)));
  }
  const std::string three = JoinPath(ToolsDir(), "node_modules/three");
  if (!std::filesystem::exists(JoinPath(three, "build/three.module.js"))) {
    return Status::NotFound("the viewer needs three.js: " + three +
                            "/build/three.module.js is missing (npm ci --prefix tools, or set "
                            "POINTBAKE_TOOLS_DIR); the report itself is written");
  }
  for (const LibFile& file : kThreeFiles) {
    PB_RETURN_IF_ERROR(CopyFile(env, JoinPath(three, file.from), JoinPath(JoinPath(viewer_dir, "lib"), file.to)));
  }
  return Status::Ok();
}

}  // namespace pb::report_internal
