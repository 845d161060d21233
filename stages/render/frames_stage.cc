// render.frames: draws a mesh (or the ground truth) from the scene's
// viewpoints with the reference renderer (stages/geometry/render/render.h) and
// writes a `frames` artifact (stages/geometry/io/frames.h).
#include <tbb/task_arena.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "engine/stage.h"
#include "stages/geometry/io/frames.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/render/render.h"
#include "stages/geometry/synth/scene.h"
#include "stages/params.h"
#include "stages/render/viewpoints.h"
#include "stages/builtin.h"

namespace pb {
namespace {

// Over this share of faces seen from behind, a warning (tools/check_real_campaign.py
// holds the shipped workflows to the same bound).
constexpr double kMaxBackShare = 0.1;

constexpr const char* kId = "render.frames";

constexpr const char* kSchema = R"({
  "type": "object",
  "additionalProperties": false,
  "required": ["viewpoints"],
  "properties": {
    "viewpoints": VIEWPOINTS_SCHEMA,
    "depth": {
      "type": "boolean",
      "default": false,
      "description": "Also write each frame's depth map (<frame>.depth.exr: per pixel the view depth in meters of the nearest surface hit, 0 where none), so metrics.image can tell a surface in front of or behind the reference's apart from a texture difference."
    },
    "size": {
      "type": "integer",
      "minimum": 16,
      "maximum": 8192,
      "default": 1024,
      "description": "Width and height of every frame, pixels."
    },
    "supersample": {
      "type": "integer",
      "minimum": 1,
      "maximum": 8,
      "default": 2,
      "description": "Samples per pixel along each axis for a mesh (2: 4 samples, box-averaged in linear light), the 4x anti-aliasing of a mobile GPU."
    },
    "truth_supersample": {
      "type": "integer",
      "minimum": 1,
      "maximum": 8,
      "default": 4,
      "description": "Samples per pixel along each axis for `truth` (4: 16 samples). The analytic albedo is point-sampled, not mip-filtered like a texture, and mortar joints are 10 mm (1 to 5 pixels at 1024 px): more samples make the reference the pixel's area average rather than an aliased pattern."
    },
    "lighting": {
      "type": "string",
      "enum": ["lambert", "unlit"],
      "default": "lambert",
      "description": "lambert: albedo * (ambient + diffuse * max(0, N.L)) with a headlight fixed to the viewer; unlit: albedo only."
    },
    "ambient": {
      "type": "number",
      "minimum": 0,
      "default": 0.25,
      "description": "Lambert: the ambient term (fraction of the albedo seen where the light does not reach)."
    },
    "diffuse": {
      "type": "number",
      "minimum": 0,
      "default": 0.75,
      "description": "Lambert: the weight of max(0, N.L). ambient + diffuse = 1 shows a surface facing the light at its albedo."
    },
    "background": {
      "anyOf": [
        { "type": "array", "items": { "type": "integer", "minimum": 0, "maximum": 255 }, "minItems": 3, "maxItems": 3 },
        { "type": "string", "pattern": "^[0-9]{1,3},[0-9]{1,3},[0-9]{1,3}$" }
      ],
      "default": [0, 0, 0],
      "description": "sRGB color where no geometry is (alpha 0 there). [R, G, B] or \"R,G,B\" (the form --set and a campaign's set: can give). A non-black background tells missing faces from dark texels."
    }
  }
})";

struct Options {
  RenderOptions render;
  int size = 1024;
  int truth_supersample = 4;
  bool depth = false;
};

Expected<Options> ReadOptions(const StageContext& ctx) {
  Options options;
  PB_ASSIGN_OR_RETURN(const int64_t size, IntegerParam(ctx, kId, "size", {16, 8192}));
  PB_ASSIGN_OR_RETURN(const int64_t supersample, IntegerParam(ctx, kId, "supersample", {1, 8}));
  PB_ASSIGN_OR_RETURN(const int64_t truth_supersample, IntegerParam(ctx, kId, "truth_supersample", {1, 8}));
  PB_ASSIGN_OR_RETURN(const std::string lighting, StringParam(ctx, kId, "lighting"));
  PB_ASSIGN_OR_RETURN(options.depth, BoolParam(ctx, kId, "depth"));
  PB_ASSIGN_OR_RETURN(options.render.ambient, NumberParam(ctx, kId, "ambient"));
  PB_ASSIGN_OR_RETURN(options.render.diffuse, NumberParam(ctx, kId, "diffuse"));
  if (lighting != "lambert" && lighting != "unlit")
    return Status::Invalid(std::string(kId) + ": parameter 'lighting' must be 'lambert' or 'unlit', got '" +
                           lighting + "'");
  if (!(options.render.ambient >= 0) || !(options.render.diffuse >= 0))
    return Status::Invalid(std::string(kId) + ": 'ambient' and 'diffuse' must be >= 0");
  PB_RETURN_IF_ERROR(ReadBackground(ctx, kId, &options.render.background));
  options.size = int(size);
  options.render.supersample = int(supersample);
  options.truth_supersample = int(truth_supersample);
  options.render.lighting = lighting == "unlit" ? RenderLighting::kUnlit : RenderLighting::kLambert;
  return options;
}

Expected<Mesh> ReadMesh(StageContext& ctx, const char* port) {
  PB_ASSIGN_OR_RETURN(const std::string path, InputFilePath(ctx, kId, port, "mesh.ply"));
  Expected<PlyMesh> read = ReadPlyMesh(path);
  if (!read.ok()) return read.status().WithContext(std::string(kId) + ": input '" + port + "'");
  return std::move(read->mesh);
}

Expected<MipTexture> ReadTexture(StageContext& ctx, const char* port, bool normal) {
  PB_ASSIGN_OR_RETURN(const Image image, ReadInputImage(ctx, kId, port));
  Expected<MipTexture> texture = normal ? BuildNormalTexture(image) : BuildColorTexture(image);
  if (!texture.ok())
    return texture.status().WithContext(std::string(kId) + ": input '" + port + "'");
  return texture;
}

Status Run(StageContext& ctx) {
  PB_ASSIGN_OR_RETURN(const Options options, ReadOptions(ctx));
  PB_ASSIGN_OR_RETURN(const std::vector<View> views, ReadViewpoints(ctx, kId, options.size));
  const bool has_mesh = ctx.has_input("mesh"), has_truth = ctx.has_input("truth");
  if (has_mesh == has_truth)
    return Status::Invalid(std::string(kId) + ": connect exactly one of 'mesh' and 'truth' (got " +
                           (has_mesh ? "both" : "neither") + ")");
  if (options.depth && has_truth)
    return Status::Invalid(std::string(kId) + ": 'depth' is written for a mesh, not for 'truth'");
  if (has_truth && (ctx.has_input("color") || ctx.has_input("normal")))
    return Status::Invalid(std::string(kId) + ": 'color' and 'normal' go with 'mesh', not 'truth'");
  if (ctx.has_input("normal") && !ctx.has_input("color"))
    return Status::Invalid(std::string(kId) + ": input 'normal' needs input 'color' (the mesh's uvs)");

  Mesh mesh;
  std::optional<SynthScene> scene;
  std::optional<MipTexture> color, normal;
  {
    PB_PHASE(ctx, "io");
    if (has_truth) {
      const ArtifactView& truth = ctx.input("truth");
      if (auto it = truth.files.find("scene.json"); it != truth.files.end()) {
        Expected<SynthScene> read = ReadSynthScene(it->second);
        if (!read.ok()) return read.status().WithContext(std::string(kId) + ": input 'truth'");
        scene = std::move(*read);
      }
    }
    // The analytic truth needs no mesh (a paper-size truth mesh.ply is large).
    if (!scene) {
      PB_ASSIGN_OR_RETURN(mesh, ReadMesh(ctx, has_mesh ? "mesh" : "truth"));
    }
    if (ctx.has_input("color")) {
      if (!mesh.has_uvs()) return Status::Invalid(std::string(kId) + ": input 'color' needs a mesh with uvs");
      PB_ASSIGN_OR_RETURN(color, ReadTexture(ctx, "color", false));
    }
    if (ctx.has_input("normal")) {
      if (!mesh.has_tangents())
        return Status::Invalid(std::string(kId) + ": input 'normal' needs a mesh with tangents (a bake's mesh output)");
      PB_ASSIGN_OR_RETURN(normal, ReadTexture(ctx, "normal", true));
    }
  }
  ctx.progress(0.1);

  RenderOptions render = options.render;
  if (has_truth) render.supersample = options.truth_supersample;
  const RenderMaterial material{color ? &*color : nullptr, normal ? &*normal : nullptr};
  FrameSet frames;
  frames.width = frames.height = options.size;
  size_t covered_samples = 0, back_samples = 0;
  {
    PB_PHASE(ctx, "compute");
    tbb::task_arena arena(std::max(1, ctx.threads()));
    for (size_t i = 0; i < views.size(); ++i) {
      Expected<Image> image = Status::Internal("not run");
      RenderStats stats;
      Image depth;
      arena.execute([&] {
        image = scene ? RenderSynthScene(*scene, views[i].camera, render, &stats)
                      : RenderMesh(mesh, material, views[i].camera, render, &stats, options.depth ? &depth : nullptr);
      });
      if (!image.ok())
        return image.status().WithContext(std::string(kId) + ": viewpoint '" + views[i].entry.name + "'");
      covered_samples += stats.covered_samples;
      back_samples += stats.back_samples;
      FrameEntry entry = views[i].entry;
      if (options.depth) entry.depth_file = DepthFileName(entry.file);
      frames.frames.push_back(Frame{std::move(entry), std::move(*image), std::move(depth)});
      ctx.progress(0.1 + 0.8 * double(i + 1) / double(views.size()));
    }
  }
  PB_RETURN_IF_ERROR(WriteFramesOutput(ctx, frames));
  const char* source = has_mesh ? "mesh" : scene ? "truth_analytic" : "truth_mesh";
  const double pixels = double(views.size()) * options.size * options.size;
  nlohmann::json meta = ctx.input(has_mesh ? "mesh" : "truth").meta;
  if (!meta.is_object()) meta = nlohmann::json::object();
  meta["kind"] = "frames";
  meta["render"] = {{"source", source},
                    {"size", options.size},
                    {"supersample", render.supersample},
                    {"lighting", render.lighting == RenderLighting::kUnlit ? "unlit" : "lambert"},
                    {"ambient", render.ambient},
                    {"diffuse", render.diffuse},
                    {"textured", bool(color)},
                    {"normal_mapped", bool(normal)},
                    {"coverage", covered_samples / (pixels * render.supersample * render.supersample)}};
  // The share of what the frames show that is a face's back: a headset,
  // culling back faces, shows what lies behind there (a mesh's inside, or
  // nothing). 0 for the truth, which has no sides.
  const double back_share = covered_samples > 0 ? double(back_samples) / double(covered_samples) : 0.0;
  if (has_mesh) meta["render"]["back_share"] = back_share;
  ctx.set_output_meta("frames", std::move(meta));
  ctx.counter("frames", double(views.size()));
  ctx.counter("triangles", scene ? 0.0 : double(mesh.face_count()));
  ctx.counter("pixels", pixels);
  if (has_mesh) ctx.counter("back_share", back_share);
  if (has_mesh && back_share > kMaxBackShare) {
    char share[32];
    std::snprintf(share, sizeof share, "%.1f", 100.0 * back_share);
    ctx.warning(std::string(kId) + ": " + share +
                " % of what the frames show are faces seen from behind (over 10 %): a headset, culling "
                "back faces, shows what lies behind them. Either the model is turned inside out, or "
                "the viewpoints look at the scan from a side the scanner never saw. A scan without its "
                "scanner stations cannot say which side was scanned, and an open scene scanned from "
                "one station (neither a room nor an object) is oriented only by propagation: declare "
                "where the scanner stood (io.read_points `station`; `pointbake scene SCAN` finds it in "
                "the points of one scan), keep the file's own normals, or "
                "move the viewpoints to the scanned side (docs/real-scans.md, \"Faces seen from "
                "behind\")");
  }
  ctx.progress(1.0);
  return Status::Ok();
}

}  // namespace

StageType FramesStage() {
  StageType type;
  type.id = kId;
  // 2: meta render.back_share and counter back_share (frames unchanged);
  // 3: a warning when back_share is over kMaxBackShare (frames unchanged);
  // 4: the warning says that pointbake scene finds a lost station.
  type.version = 4;
  type.summary = "Deterministic reference renders of a mesh or the ground truth from the scene's viewpoints";
  type.doc =
      "Draws `mesh` (with its color map `color` and tangent-space normal map `normal` when given; "
      "else its vertex colors; else gray) or the ground truth `truth` from every viewpoint, as a "
      "mobile GPU would (docs/render.md): perspective-correct UVs, trilinear mip-mapped sampling "
      "of sRGB-decoded textures, tangent-space normal mapping with the mesh's tangents, no "
      "back-face culling, a z-buffer with ties to the lower face index, `supersample`^2 samples "
      "per pixel averaged in linear light, sRGB 8-bit RGBA output (alpha 255 where geometry "
      "covers any sample). `lambert` lights with a headlight fixed to the viewer (slightly above "
      "and left of the eye, behind it): albedo * (ambient + diffuse * max(0, N.L)), two-sided; "
      "`unlit` shows the albedo. The bytes are the same for any thread count.\n\n"
      "With `truth` holding scene.json (synth.scan), the analytic scene is ray cast through the "
      "same sample grid with `truth_supersample`^2 samples (true albedo and true normal at each "
      "hit, the same light and encoding); without scene.json the truth mesh is drawn with its "
      "vertex colors. Exactly one of `mesh` and `truth`; `normal` needs `color`, `color` needs "
      "uvs, `normal` needs tangents.\n\n"
      "Output `frames`: frames.json and one PNG per viewpoint (name or view<N>); with `depth`, "
      "also <name>.depth.exr (view depth in meters of the nearest surface per pixel, 0 on "
      "background; a mesh only).\n\n"
      "Counters: `frames`, `triangles` (faces drawn per frame; 0 for the analytic truth), "
      "`pixels` (over all frames), `back_share` (a mesh only: of the samples that hit it, the "
      "share that sees a face's back; drawn here, but a headset, culling back faces as glTF's "
      "single-sided materials make it, shows what lies behind there; also meta "
      "`render.back_share`; over 0.1, version 3, a warning says what it means and what to do). "
      "Phases: `io`, `compute`.";
  type.params_schema = WithViewpointsSchema(kSchema);
  type.inputs = {
      {"mesh", "mesh", "The mesh to draw (mesh.ply; uvs and tangents for the maps).", true},
      {"color", "image", "Color map, sRGB (color.png), addressed by the mesh's uvs.", true},
      {"normal", "image", "Tangent-space normal map (normal.png 8-bit or normal.exr float).", true},
      {"truth", "mesh", "Ground truth of synth.scan (mesh.ply + scene.json) instead of `mesh`.", true}};
  type.outputs = {{"frames", "frames", "One 8-bit sRGB RGBA PNG per viewpoint, and frames.json.", false}};
  type.run = &Run;
  return type;
}

}  // namespace pb
