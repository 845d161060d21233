// render.frames through the fake context: the frames artifact it writes,
// ground truth with and without scene.json, and its errors.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "stages/builtin.h"
#include "stages/geometry/io/frames.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/io/ply.h"
#include "stages/geometry/render/render.h"
#include "stages/geometry/synth/scene.h"
#include "stages/geometry/core/tangents.h"
#include "stages/stage_test_util.h"

namespace pb {
namespace {

class RenderStagesTest : public StageTest {
 protected:
  void SetUp() override {
    StageTest::SetUp();
    RegisterBuiltinStages(registry_);
  }

  // A 2 x 2 m quad in the plane y = 5 facing -y, at a georeferenced origin,
  // with uvs, normals and tangents.
  Mesh Quad() {
    Mesh mesh;
    mesh.origin = {300000.0, 5000000.0, 100.0};
    mesh.positions = {-1, 5, -1, 1, 5, -1, 1, 5, 1, -1, 5, 1};
    mesh.uvs = {0, 0, 1, 0, 1, 1, 0, 1};
    mesh.indices = {0, 1, 2, 0, 2, 3};
    mesh.normals = ComputeVertexNormals(mesh);
    mesh.tangents = ComputeTangents(mesh).value();
    return mesh;
  }

  std::string WriteImage(const std::string& name, const Image& image) {
    std::filesystem::create_directories(dir_ / "input");
    const std::string path = (dir_ / "input" / name).string();
    EXPECT_TRUE(WritePng(path, image).ok());
    return path;
  }

  // Viewpoints around the quad's origin: one named, one not.
  nlohmann::json Viewpoints() {
    return nlohmann::json::array(
        {{{"name", "front"}, {"eye", {300000.0, 5000000.0, 100.0}}, {"target", {300000.0, 5000005.0, 100.0}}},
         {{"eye", {300000.5, 5000001.0, 100.2}}, {"target", {300000.0, 5000005.0, 100.0}}, {"fov_deg", 40}}});
  }

  nlohmann::json Params(nlohmann::json viewpoints) {
    return {{"viewpoints", std::move(viewpoints)}, {"size", 32}};
  }

  Expected<FrameSet> Frames(FakeContext& ctx) {
    return ReadFrames(ctx.files_.at("frames/frames.json"));
  }
};

Image Checker(int size) {
  Image image = Image::Make(size, size, 3, Image::PixelType::kU8);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 3; ++c) image.at_u8(x, y, c) = ((x / 4 + y / 4) % 2) ? 220 : uint8_t(40 + 60 * c);
  return image;
}

TEST_F(RenderStagesTest, IsWellFormed) {
  const StageType* type = registry_.Find("render.frames");
  ASSERT_NE(type, nullptr);
  const nlohmann::json schema = CheckedSchema(*type);
  EXPECT_EQ(schema["properties"]["size"]["default"], 1024);
  EXPECT_EQ(schema["properties"]["supersample"]["default"], 2);
  ASSERT_EQ(type->inputs.size(), 4u);
  for (const PortSpec& port : type->inputs) EXPECT_TRUE(port.optional) << port.name;
  ASSERT_EQ(type->outputs.size(), 1u);
  EXPECT_EQ(type->outputs[0].type, "frames");
}

TEST_F(RenderStagesTest, SaysHowMuchOfWhatItShowsIsAFacesBack) {
  // The quad faces the viewpoints: no back. Wound the other way round, all
  // of it is its back (drawn the same, but a headset culls it).
  for (const bool flipped : {false, true}) {
    Mesh quad = Quad();
    if (flipped)
      for (size_t f = 0; f < quad.indices.size(); f += 3) std::swap(quad.indices[f + 1], quad.indices[f + 2]);
    FakeContext ctx(dir_ / (flipped ? "flipped" : "front"), Params(Viewpoints()));
    ctx.AddInput("mesh", "mesh", WriteInputMesh(flipped ? "flipped" : "front", quad),
                 {{"origin", {300000.0, 5000000.0, 100.0}}});
    ASSERT_TRUE(Run("render.frames", ctx).ok());
    EXPECT_EQ(ctx.counters_["back_share"], flipped ? 1.0 : 0.0);
    EXPECT_EQ(ctx.meta_["frames"]["render"]["back_share"], flipped ? 1.0 : 0.0);
    // Over 10 %, a warning says what it means and what to do.
    ASSERT_EQ(ctx.warnings_.size(), flipped ? 1u : 0u);
    if (flipped) {
      EXPECT_NE(ctx.warnings_[0].find("100.0 % of what the frames show are faces seen from behind"), std::string::npos)
          << ctx.warnings_[0];
      EXPECT_NE(ctx.warnings_[0].find("io.read_points `station`; `pointbake scene SCAN` finds it"), std::string::npos)
          << ctx.warnings_[0];
    }
  }
}

TEST_F(RenderStagesTest, WritesFramesOfATexturedMesh) {
  FakeContext ctx(dir_, Params(Viewpoints()));
  ctx.AddInput("mesh", "mesh", WriteInputMesh("quad", Quad()), {{"origin", {300000.0, 5000000.0, 100.0}}});
  ctx.AddInput("color", "image", WriteImage("color.png", Checker(16)));
  ASSERT_TRUE(Run("render.frames", ctx).ok());
  Expected<FrameSet> frames = Frames(ctx);
  ASSERT_TRUE(frames.ok()) << frames.status().message();
  ASSERT_EQ(frames->frames.size(), 2u);
  EXPECT_EQ(frames->width, 32);
  EXPECT_EQ(frames->frames[0].entry.name, "front");
  EXPECT_EQ(frames->frames[1].entry.name, "view2");
  EXPECT_EQ(frames->frames[1].entry.file, "view2.png");
  ASSERT_TRUE(frames->frames[1].entry.viewpoint.has_value());
  EXPECT_EQ(frames->frames[1].entry.viewpoint->fov_deg, 40.0);
  EXPECT_EQ(frames->frames[1].entry.viewpoint->eye[0], 300000.5);
  // The quad fills the middle of the front view: opaque and checkered there.
  const Image& front = frames->frames[0].image;
  EXPECT_EQ(front.channels, 4);
  EXPECT_EQ(front.at_u8(16, 16, 3), 255);
  EXPECT_EQ(front.at_u8(0, 0, 3), 0);
  EXPECT_NE(front.at_u8(13, 16, 0), front.at_u8(19, 16, 0));
  EXPECT_EQ(ctx.counters_["frames"], 2);
  EXPECT_EQ(ctx.counters_["triangles"], 2);
  EXPECT_EQ(ctx.counters_["pixels"], 2 * 32 * 32);
  EXPECT_TRUE(ctx.phases_.count("io") && ctx.phases_.count("compute"));
  EXPECT_EQ(ctx.meta_["frames"]["render"]["source"], "mesh");
  EXPECT_EQ(ctx.meta_["frames"]["render"]["textured"], true);
  EXPECT_EQ(ctx.last_progress_, 1.0);
}

TEST_F(RenderStagesTest, BackgroundAsArrayOrString) {
  // "R,G,B" is what --set and a campaign's set: can give (scalars only).
  auto corner = [&](const nlohmann::json& background, const std::string& out) -> std::array<int, 4> {
    std::filesystem::create_directories(dir_ / out);
    nlohmann::json params = Params(Viewpoints());
    params["background"] = background;
    FakeContext ctx(dir_ / out, params);
    ctx.AddInput("mesh", "mesh", WriteInputMesh("quad", Quad()), {{"origin", {300000.0, 5000000.0, 100.0}}});
    const Status status = Run("render.frames", ctx);
    if (!status.ok()) return {-1, -1, -1, -1};
    const Expected<FrameSet> frames = Frames(ctx);
    const Image& front = frames->frames[0].image;
    return {front.at_u8(0, 0, 0), front.at_u8(0, 0, 1), front.at_u8(0, 0, 2), front.at_u8(0, 0, 3)};
  };
  EXPECT_EQ(corner(nlohmann::json::array({255, 0, 255}), "array"), (std::array<int, 4>{255, 0, 255, 0}));
  EXPECT_EQ(corner("255,0,255", "string"), (std::array<int, 4>{255, 0, 255, 0}));
  EXPECT_EQ(corner("16,160,192", "string2"), (std::array<int, 4>{16, 160, 192, 0}));
  EXPECT_EQ(corner("16,160", "two")[0], -1);
  EXPECT_EQ(corner("16,160,256", "big")[0], -1);
  EXPECT_EQ(corner("#ff00ff", "hex")[0], -1);
}

TEST_F(RenderStagesTest, SameBytesForAnyThreadCountAndNormalMapIsUsed) {
  auto render = [&](int threads, const std::string& out, bool tilted) {
    std::filesystem::create_directories(dir_ / out);
    FakeContext ctx(dir_ / out, Params(Viewpoints()), threads);
    ctx.AddInput("mesh", "mesh", WriteInputMesh("quad", Quad()));
    ctx.AddInput("color", "image", WriteImage("color.png", Checker(16)));
    Image normal = Image::Make(8, 8, 3, Image::PixelType::kU8);
    for (size_t i = 0; i < normal.data.size(); i += 3) {
      normal.data[i] = tilted ? 191 : 128;
      normal.data[i + 1] = 128;
      normal.data[i + 2] = tilted ? 238 : 255;
    }
    ctx.AddInput("normal", "image", WriteImage(tilted ? "tilted.png" : "flat.png", normal));
    EXPECT_TRUE(Run("render.frames", ctx).ok());
    return Frames(ctx).value();
  };
  const FrameSet one = render(1, "a", false), two = render(2, "b", false), tilted = render(2, "c", true);
  for (size_t i = 0; i < one.frames.size(); ++i) {
    EXPECT_EQ(one.frames[i].image.data, two.frames[i].image.data);
    EXPECT_NE(one.frames[i].image.data, tilted.frames[i].image.data);
  }
}

TEST_F(RenderStagesTest, RendersTruthAnalyticallyOrAsMesh) {
  const SynthScene scene = MakeSynthScene("room", 1, Vec3{3.0, 2.4, 2.0}).value();
  const std::string mesh_path = WriteInputMesh("truth", SynthTruthMesh(scene, 0.05));
  const std::string scene_path = (std::filesystem::path(mesh_path).parent_path() / "scene.json").string();
  std::ofstream(scene_path) << ToJson(scene).dump();
  const nlohmann::json views = nlohmann::json::array(
      {{{"name", "wall"}, {"eye", {-0.5, 0.0, 1.0}}, {"target", {1.5, 0.2, 1.0}}}});
  FakeContext analytic(dir_, Params(views));
  analytic.AddInput("truth", "mesh", {{"mesh.ply", mesh_path}, {"scene.json", scene_path}});
  ASSERT_TRUE(Run("render.frames", analytic).ok());
  EXPECT_EQ(analytic.meta_["frames"]["render"]["source"], "truth_analytic");
  EXPECT_EQ(analytic.meta_["frames"]["render"]["supersample"], 4);
  EXPECT_EQ(analytic.counters_["triangles"], 0);
  const FrameSet a = Frames(analytic).value();

  std::filesystem::create_directories(dir_ / "m");
  FakeContext as_mesh(dir_ / "m", Params(views));
  as_mesh.AddInput("truth", "mesh", {{"mesh.ply", mesh_path}});
  ASSERT_TRUE(Run("render.frames", as_mesh).ok());
  EXPECT_EQ(as_mesh.meta_["frames"]["render"]["source"], "truth_mesh");
  const FrameSet m = Frames(as_mesh).value();
  // Each frame is what the library draws with the stage's defaults (the
  // truth at 4 x 4 samples); the two differ (a 5 cm truth mesh aliases the
  // 10 mm joints: render_test compares the renderers at 5 mm).
  RenderCamera camera;
  camera.eye = {-0.5, 0.0, 1.0};
  camera.target = {1.5, 0.2, 1.0};
  camera.size = 32;
  RenderOptions options;
  options.supersample = 4;
  EXPECT_EQ(a.frames[0].image.data, RenderSynthScene(scene, camera, options).value().data);
  const Mesh read_back = ReadPlyMesh(mesh_path).value().mesh;
  EXPECT_EQ(m.frames[0].image.data, RenderMesh(read_back, {}, camera, options).value().data);
  EXPECT_NE(a.frames[0].image.data, m.frames[0].image.data);
}

TEST_F(RenderStagesTest, ClearErrors) {
  const std::string mesh_path = WriteInputMesh("quad", Quad());
  auto error = [&](nlohmann::json params, auto connect) {
    FakeContext ctx(dir_, std::move(params));
    connect(ctx);
    const Status status = Run("render.frames", ctx);
    EXPECT_FALSE(status.ok());
    return status.message();
  };
  auto mesh_only = [&](FakeContext& ctx) { ctx.AddInput("mesh", "mesh", mesh_path); };
  EXPECT_NE(error(Params(Viewpoints()), [&](FakeContext& ctx) {
              ctx.AddInput("mesh", "mesh", mesh_path);
              ctx.AddInput("truth", "mesh", mesh_path);
            }).find("exactly one of 'mesh' and 'truth' (got both)"),
            std::string::npos);
  EXPECT_NE(error(Params(Viewpoints()), [](FakeContext&) {}).find("(got neither)"), std::string::npos);
  EXPECT_NE(error(Params(Viewpoints()), [&](FakeContext& ctx) {
              mesh_only(ctx);
              ctx.AddInput("normal", "image", WriteImage("n.png", Checker(4)));
            }).find("'normal' needs input 'color'"),
            std::string::npos);
  Mesh bare = Quad();
  bare.uvs.clear();
  bare.tangents.clear();
  const std::string bare_path = WriteInputMesh("bare", bare);
  EXPECT_NE(error(Params(Viewpoints()), [&](FakeContext& ctx) {
              ctx.AddInput("mesh", "mesh", bare_path);
              ctx.AddInput("color", "image", WriteImage("c.png", Checker(4)));
            }).find("'color' needs a mesh with uvs"),
            std::string::npos);
  EXPECT_NE(error(Params(Viewpoints()), [&](FakeContext& ctx) {
              ctx.AddInput("truth", "mesh", mesh_path);
              ctx.AddInput("color", "image", WriteImage("c.png", Checker(4)));
            }).find("go with 'mesh', not 'truth'"),
            std::string::npos);
  nlohmann::json short_eye = Viewpoints();
  short_eye[1]["eye"] = {1.0, 2.0};
  EXPECT_NE(error(Params(short_eye), mesh_only).find("viewpoints[1].eye: must be an array of 3 numbers"),
            std::string::npos);
  nlohmann::json duplicate = Viewpoints();
  duplicate[1]["name"] = "front";
  EXPECT_NE(error(Params(duplicate), mesh_only).find("duplicate name 'front'"), std::string::npos);
  nlohmann::json same_point = Viewpoints();
  same_point[0]["target"] = same_point[0]["eye"];
  EXPECT_NE(error(Params(same_point), mesh_only).find("viewpoint 'front'"), std::string::npos);
  nlohmann::json unknown = Viewpoints();
  unknown[0]["zoom"] = 2;
  EXPECT_NE(error(Params(unknown), mesh_only).find("unknown key 'zoom'"), std::string::npos);
  EXPECT_NE(error(Params(nlohmann::json::array()), mesh_only).find("non-empty array"), std::string::npos);
  EXPECT_NE(error(nlohmann::json{{"size", 32}}, mesh_only).find("'viewpoints' is missing"), std::string::npos);
}

// render.splats: a grid of colored points where the quad of Quad() is, at
// the same georeferenced origin.
PointCloud QuadPoints() {
  PointCloud cloud;
  cloud.origin = {300000.0, 5000000.0, 100.0};
  for (int j = 0; j <= 40; ++j)
    for (int i = 0; i <= 40; ++i) {
      cloud.positions.insert(cloud.positions.end(), {-1.0f + 0.05f * i, 5.0f, -1.0f + 0.05f * j});
      cloud.colors.insert(cloud.colors.end(), {uint8_t(i * 6), 90, uint8_t(j * 6)});
    }
  return cloud;
}

TEST_F(RenderStagesTest, SplatsIsWellFormed) {
  const StageType* type = registry_.Find("render.splats");
  ASSERT_NE(type, nullptr);
  const nlohmann::json schema = CheckedSchema(*type);
  EXPECT_EQ(schema["properties"]["size"]["default"], 1024);
  EXPECT_EQ(schema["properties"]["supersample"]["default"], 2);
  EXPECT_EQ(schema["properties"]["k"]["default"], 8);
  EXPECT_EQ(schema["properties"]["viewpoints"]["items"]["required"], nlohmann::json::array({"eye", "target"}));
  ASSERT_EQ(type->inputs.size(), 1u);
  EXPECT_FALSE(type->inputs[0].optional);
  ASSERT_EQ(type->outputs.size(), 1u);
  EXPECT_EQ(type->outputs[0].type, "frames");
}

TEST_F(RenderStagesTest, SplatsWriteTheSameFramesAsRenderFramesWouldNameThem) {
  auto render = [&](int threads, const std::string& out) {
    std::filesystem::create_directories(dir_ / out);
    FakeContext ctx(dir_ / out, Params(Viewpoints()), threads);
    ctx.AddInput("points", "points", WriteInputPoints("grid", QuadPoints()));
    EXPECT_TRUE(Run("render.splats", ctx).ok());
    EXPECT_EQ(ctx.counters_["points"], 41 * 41);
    EXPECT_EQ(ctx.meta_["frames"]["render"]["source"], "splats");
    EXPECT_EQ(ctx.meta_["frames"]["render"]["lighting"], "unlit");
    // Grid step 5 cm, the 8th neighbour a diagonal: local spacing 7.07 cm x
    // sqrt(pi / 8), radius 1.2 spacings.
    EXPECT_NEAR(ctx.counters_["median_radius_m"], 1.2 * 0.05 * std::sqrt(2.0) * std::sqrt(M_PI / 8), 1e-6);
    // A flat grid: every disk lies in its plane; the rim of the grid is its border.
    EXPECT_EQ(ctx.counters_["oriented_points"], 41 * 41);
    EXPECT_GE(ctx.counters_["border_points"], 4 * 39);
    EXPECT_LE(ctx.counters_["border_points"], 4 * 41 * 2);
    EXPECT_TRUE(ctx.phases_.count("spacing") && ctx.phases_.count("surfels") && ctx.phases_.count("compute"));
    return Frames(ctx).value();
  };
  const FrameSet one = render(1, "a"), two = render(2, "b");
  ASSERT_EQ(one.frames.size(), 2u);
  EXPECT_EQ(one.frames[0].entry.name, "front");
  EXPECT_EQ(one.frames[1].entry.file, "view2.png");
  for (size_t i = 0; i < one.frames.size(); ++i) {
    EXPECT_EQ(one.frames[i].image.data, two.frames[i].image.data);
    ASSERT_EQ(one.frames[i].samples.width, 32);  // the sample masks too
    EXPECT_EQ(one.frames[i].samples.data, two.frames[i].samples.data);
  }
  // Where render.frames draws the quad, the splats cover the same middle.
  const Image& front = one.frames[0].image;
  EXPECT_EQ(front.at_u8(16, 16, 3), 255);
  EXPECT_EQ(front.at_u8(16, 16, 1), 90);
  EXPECT_EQ(front.at_u8(0, 0, 3), 0);
}

TEST_F(RenderStagesTest, SplatsOfIsolatedPointsStaySmall) {
  // The grid plus one stray point 1 m in front of it, half a meter off the
  // grid's edge: its 8th neighbour is ~1 m away, but its splat is capped at
  // 4 median spacings (4 x 7.07 cm x 0.75), not a 75 cm disk.
  PointCloud cloud = QuadPoints();
  cloud.positions.insert(cloud.positions.end(), {1.5f, 4.0f, 0.0f});
  cloud.colors.insert(cloud.colors.end(), {255, 255, 255});
  // (stray_cluster_points 0: drawn, not left out as the default does; below.)
  FakeContext ctx(dir_, {{"viewpoints", {Viewpoints()[0]}}, {"size", 64}, {"stray_cluster_points", 0}});
  ctx.AddInput("points", "points", WriteInputPoints("stray", cloud));
  ASSERT_TRUE(Run("render.splats", ctx).ok());
  EXPECT_EQ(ctx.counters_["radii_capped"], 1);
  EXPECT_EQ(ctx.counters_["stray_points"], 0);
  const FrameSet frames = Frames(ctx).value();
  const Image& front = frames.frames[0].image;
  // The stray point projects to x = 32 + 1.5 / 4 * 55.4 = 52.8 px with a
  // radius of 0.21 / 4 * 55.4 = 2.9 px (uncapped: 10 px).
  int white = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) white += front.at_u8(x, y, 0) == 255 && front.at_u8(x, y, 2) == 255;
  EXPECT_GT(white, 10);
  EXPECT_LT(white, 40);
}

TEST_F(RenderStagesTest, StrayPointsAreLeftOutOfTheScansFrames) {
  // The grid plus a lone return 1 m in front of it and a floating cluster
  // of 9 returns 2 cm apart, 0.5 m in front: neither is a surface, so
  // neither is drawn, counted as a sample or hides the grid.
  PointCloud cloud = QuadPoints();
  const size_t grid = cloud.size();
  cloud.positions.insert(cloud.positions.end(), {0.2f, 4.0f, 0.1f});
  for (int c = 0; c < 9; ++c)
    cloud.positions.insert(cloud.positions.end(), {-0.5f + 0.02f * float(c % 3), 4.5f, 0.3f + 0.02f * float(c / 3)});
  cloud.colors.resize(3 * cloud.size(), 255);
  const auto render = [&](const std::string& name, const PointCloud& points, int64_t min_cluster) {
    std::filesystem::create_directories(dir_ / name);
    auto ctx = std::make_unique<FakeContext>(
        dir_ / name, nlohmann::json{{"viewpoints", {Viewpoints()[0]}}, {"size", 64}, {"stray_cluster_points", min_cluster}});
    ctx->AddInput("points", "points", WriteInputPoints(name, points));
    EXPECT_TRUE(Run("render.splats", *ctx).ok());
    return ctx;
  };
  PointCloud quad = QuadPoints();
  const auto with_strays = render("strays", cloud, 50);
  const auto without = render("quad", quad, 50);
  const auto drawn = render("drawn", cloud, 0);
  EXPECT_EQ(with_strays->counters_["stray_points"], 10);
  EXPECT_EQ(with_strays->counters_["points"], double(grid + 10));
  EXPECT_EQ(without->counters_["stray_points"], 0);
  EXPECT_EQ(drawn->counters_["stray_points"], 0);
  // The same pixels and samples as the grid alone; drawn, the strays change
  // both (their disks hide grid samples and add their own).
  const FrameSet a = Frames(*with_strays).value(), b = Frames(*without).value(), c = Frames(*drawn).value();
  EXPECT_EQ(a.frames[0].image.data, b.frames[0].image.data);
  EXPECT_EQ(a.frames[0].samples.data, b.frames[0].samples.data);
  EXPECT_EQ(with_strays->counters_["sample_pixels"], without->counters_["sample_pixels"]);
  EXPECT_NE(c.frames[0].samples.data, b.frames[0].samples.data);
  EXPECT_NE(c.frames[0].image.data, b.frames[0].image.data);
}

TEST_F(RenderStagesTest, SplatsReportBadInput) {
  FakeContext ctx(dir_, Params(Viewpoints()));
  PointCloud two;
  two.positions = {0, 0, 0, 1, 1, 1};
  ctx.AddInput("points", "points", WriteInputPoints("two", two));
  const Status status = Run("render.splats", ctx);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("render.splats"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("k = 8"), std::string::npos) << status.message();
}

TEST_F(RenderStagesTest, DepthMapsOfMeshAndSplatsAgreeOnTheSameSurface) {
  // The quad and the grid of points where it is, 5 m in front of the eye:
  // both depth maps read 5 m in the middle and 0 on the background, and
  // survive the trip through frames.json.
  nlohmann::json params = Params(Viewpoints());
  params["depth"] = true;
  std::filesystem::create_directories(dir_ / "mesh");
  FakeContext mesh_ctx(dir_ / "mesh", params);
  mesh_ctx.AddInput("mesh", "mesh", WriteInputMesh("quad", Quad()));
  ASSERT_TRUE(Run("render.frames", mesh_ctx).ok());
  std::filesystem::create_directories(dir_ / "splats");
  FakeContext splat_ctx(dir_ / "splats", params);
  splat_ctx.AddInput("points", "points", WriteInputPoints("grid", QuadPoints()));
  ASSERT_TRUE(Run("render.splats", splat_ctx).ok());
  for (FakeContext* ctx : {&mesh_ctx, &splat_ctx}) {
    Expected<FrameSet> frames = Frames(*ctx);
    ASSERT_TRUE(frames.ok()) << frames.status().message();
    const Frame& front = frames->frames[0];
    EXPECT_EQ(front.entry.depth_file, "front.depth.exr");
    ASSERT_EQ(front.depth.width, 32);
    EXPECT_NEAR(front.depth.at_f32(16, 16, 0), 5.0f, 1e-4);
    EXPECT_EQ(front.depth.at_f32(0, 0, 0), 0.0f);
  }
  // Without `depth` there is none.
  std::filesystem::create_directories(dir_ / "plain");
  FakeContext plain(dir_ / "plain", Params(Viewpoints()));
  plain.AddInput("mesh", "mesh", WriteInputMesh("quad2", Quad()));
  ASSERT_TRUE(Run("render.frames", plain).ok());
  EXPECT_TRUE(Frames(plain)->frames[0].entry.depth_file.empty());
  EXPECT_EQ(plain.files_.count("frames/front.depth.exr"), 0u);
}

// A plate in the plane y = 5 facing -y (the quad's), x in [-1.05, 1.05] and z
// in [-1.05, 1.65], cut into a 3 x 3 grid of cells at x, z = +-0.3; `hole`
// leaves the middle cell (0.6 x 0.6 m) out.
Mesh Plate(bool hole) {
  Mesh mesh;
  mesh.origin = {300000.0, 5000000.0, 100.0};
  const float xs[4] = {-1.05f, -0.3f, 0.3f, 1.05f}, zs[4] = {-1.05f, -0.3f, 0.3f, 1.65f};
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      mesh.positions.insert(mesh.positions.end(), {xs[i], 5.0f, zs[j]});
      mesh.uvs.insert(mesh.uvs.end(), {(xs[i] + 1.05f) / 2.1f, (zs[j] + 1.05f) / 2.7f});
    }
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      if (hole && i == 1 && j == 1) continue;
      const uint32_t a = uint32_t(j * 4 + i), b = a + 1, c = a + 5, d = a + 4;
      mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
    }
  mesh.normals = ComputeVertexNormals(mesh);
  return mesh;
}

TEST_F(RenderStagesTest, HolesAreCountedOnTheScanSamplesNotOnItsDisks) {
  // The reference: a 2.5 cm grid of points where the quad is, plus two
  // sparse rows above it (z = 1.3 and 1.5, every 30 cm) whose spacing is
  // inflated, drawn as large camera-facing disks (orient false, radius 3
  // spacings, capped at 8 median spacings: 0.53 m, 6 px, for the sparse
  // rows) that reach past the plate all around (the grid's by 0.07 m past
  // x = +-1 and z = -1, the plate ending 0.05 m out).
  PointCloud cloud;
  cloud.origin = {300000.0, 5000000.0, 100.0};
  for (int j = 0; j <= 80; ++j)
    for (int i = 0; i <= 80; ++i) {
      cloud.positions.insert(cloud.positions.end(), {-1.0f + 0.025f * i, 5.0f, -1.0f + 0.025f * j});
      cloud.colors.insert(cloud.colors.end(), {uint8_t(i * 3), 90, uint8_t(j * 3)});
    }
  for (const float z : {1.3f, 1.5f})
    for (int i = 0; i < 7; ++i) {
      cloud.positions.insert(cloud.positions.end(), {-0.9f + 0.3f * float(i), 5.0f, z});
      cloud.colors.insert(cloud.colors.end(), {200, 200, 200});
    }
  // (stray_cluster_points 0: the sparse rows are clusters of 7 and would be
  // left out as strays.)
  nlohmann::json splat_params = {{"viewpoints", {Viewpoints()[0]}}, {"size", 64}, {"orient", false},
                                 {"radius_scale", 3.0}, {"max_radius_spacings", 8.0},
                                 {"stray_cluster_points", 0}};
  std::filesystem::create_directories(dir_ / "scan");
  FakeContext scan(dir_ / "scan", splat_params);
  scan.AddInput("points", "points", WriteInputPoints("cloud", cloud));
  ASSERT_TRUE(Run("render.splats", scan).ok());
  const FrameSet scan_frames = Frames(scan).value();
  ASSERT_EQ(scan_frames.frames[0].entry.samples_file, "front.samples.png");
  const Image& samples = scan_frames.frames[0].samples;
  ASSERT_EQ(samples.width, 64);
  // A point counts where it falls in the middle half of its pixel (per axis:
  // the hull of the 2 x 2 sample centers). The grid (x, z = -1 .. 1 project
  // to 20.9 .. 43.1 px, 0.28 px apart) puts one there in pixels 21 .. 42 of
  // each axis; of the sparse rows (at 15.4 and 17.6 px) the points at x =
  // -0.6, -0.3, 0.3 and 0.6 (25.3, 28.7, 35.3, 38.7 px) do; the background
  // holds none.
  EXPECT_EQ(samples.at_u8(32, 32, 0), 255);
  EXPECT_EQ(samples.at_u8(20, 32, 0), 0);
  EXPECT_EQ(samples.at_u8(2, 2, 0), 0);
  EXPECT_EQ(scan.counters_.at("sample_pixels"), 22 * 22 + 2 * 4);

  auto artifact = [](const FakeContext& ctx) {
    std::map<std::string, std::string> files;
    for (const auto& [key, path] : ctx.files_)
      if (key.rfind("frames/", 0) == 0) files[key.substr(7)] = path;
    return files;
  };
  // Holes of `model` against the scan: {hole_px, enclosed_hole_px, splat_hole_px, footprint_px}.
  auto holes = [&](const Mesh& model, const std::string& out) -> std::array<double, 4> {
    std::filesystem::create_directories(dir_ / out);
    FakeContext render(dir_ / out, {{"viewpoints", {Viewpoints()[0]}}, {"size", 64}, {"lighting", "unlit"}});
    render.AddInput("mesh", "mesh", WriteInputMesh(out, model));
    EXPECT_TRUE(Run("render.frames", render).ok());
    std::filesystem::create_directories(dir_ / (out + "_metrics"));
    FakeContext metrics(dir_ / (out + "_metrics"), nlohmann::json::object());
    metrics.AddInput("frames", "frames", artifact(render));
    metrics.AddInput("reference", "frames", artifact(scan));
    const Status status = Run("metrics.image", metrics);
    EXPECT_TRUE(status.ok()) << status.message();
    const nlohmann::json table = nlohmann::json::parse(std::ifstream(metrics.outputs_.at("table")));
    std::map<std::string, double> row;
    for (size_t c = 0; c < table["columns"].size(); ++c)
      if (table["rows"][0][c].is_number()) row[table["columns"][c]] = table["rows"][0][c].get<double>();
    EXPECT_EQ(metrics.counters_.at("sample_mask_frames"), 1);
    EXPECT_DOUBLE_EQ(row["hole_fraction"], row["hole_px"] / row["footprint_px"]);
    EXPECT_EQ(row["silhouette_hole_px"], 0);  // no outline falls short of the samples
    return {row["hole_px"], row["enclosed_hole_px"], row["splat_hole_px"], row["footprint_px"]};
  };
  // The exact plate: no hole where the scan has samples, though the disks
  // reach past it all around.
  const std::array<double, 4> exact = holes(Plate(false), "exact");
  EXPECT_EQ(exact[0], 0);
  EXPECT_GT(exact[2], 40);
  EXPECT_EQ(exact[3], 22 * 22 + 2 * 4);
  // The plate with a 0.6 m hole inside the grid (x, z = -0.3 .. 0.3: 28.7 ..
  // 35.3 px, so pixels 29 .. 34 show background): each of its 36 pixels
  // holds a sample, so it counts whole, enclosed by the model; the disks'
  // count grows by the same.
  const std::array<double, 4> open = holes(Plate(true), "open");
  EXPECT_EQ(open[0], 36);
  EXPECT_EQ(open[1], 36);
  EXPECT_EQ(open[2], exact[2] + 36);
}

TEST_F(RenderStagesTest, RangeNoiseIsNotCountedAsHolesOfTheTrueSurface) {
  // The quad scanned with range noise: a 2.5 cm grid over it (its outermost
  // points half a step in from the edges, as a scan samples a surface), every point
  // moved up to 4 cm across the plane, seen obliquely from above, so the
  // noise scatters the points along its outline past it. Against the quad
  // itself (the true surface), the measured positions put sample pixels
  // outside the outline, "holes" no surface would fill (23); the points
  // moved onto their local surface (samples_on_surface, the default) leave
  // a few (7: the fit keeps about sqrt(6 / 17) of the noise, and an edge
  // point is only half a step inside the outline).
  PointCloud cloud;
  cloud.origin = {300000.0, 5000000.0, 100.0};
  uint64_t state = 4242;
  for (int j = 0; j < 80; ++j)
    for (int i = 0; i < 80; ++i) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const double noise = (double(state >> 11) * 0x1.0p-53 * 2 - 1) * 0.04;
      cloud.positions.insert(cloud.positions.end(),
                             {-0.9875f + 0.025f * i, float(5.0 + noise), -0.9875f + 0.025f * j});
      cloud.colors.insert(cloud.colors.end(), {uint8_t(i * 3), 90, uint8_t(j * 3)});
    }
  const nlohmann::json above = nlohmann::json::array(
      {{{"name", "above"}, {"eye", {300000.0, 5000003.0, 102.0}}, {"target", {300000.0, 5000005.0, 100.0}}}});
  auto hole_px = [&](bool on_surface, const std::string& out) {
    std::filesystem::create_directories(dir_ / ("scan_" + out));
    FakeContext scan(dir_ / ("scan_" + out),
                     {{"viewpoints", above}, {"size", 128}, {"samples_on_surface", on_surface}});
    scan.AddInput("points", "points", WriteInputPoints("noisy_" + out, cloud));
    EXPECT_TRUE(Run("render.splats", scan).ok());
    EXPECT_EQ(scan.meta_["frames"]["render"]["samples_on_surface"], on_surface);
    if (on_surface) {
      EXPECT_EQ(scan.counters_.at("projected_points"), 80 * 80);
      EXPECT_GT(scan.counters_.at("mean_projection_m"), 0.008);  // the noise's mean |.| is 1.5 cm
    }
    std::filesystem::create_directories(dir_ / ("quad_" + out));
    FakeContext render(dir_ / ("quad_" + out), {{"viewpoints", above}, {"size", 128}, {"lighting", "unlit"}});
    render.AddInput("mesh", "mesh", WriteInputMesh("quad_" + out, Quad()));
    EXPECT_TRUE(Run("render.frames", render).ok());
    auto artifact = [](const FakeContext& ctx) {
      std::map<std::string, std::string> files;
      for (const auto& [key, path] : ctx.files_)
        if (key.rfind("frames/", 0) == 0) files[key.substr(7)] = path;
      return files;
    };
    std::filesystem::create_directories(dir_ / ("metrics_" + out));
    FakeContext metrics(dir_ / ("metrics_" + out), nlohmann::json::object());
    metrics.AddInput("frames", "frames", artifact(render));
    metrics.AddInput("reference", "frames", artifact(scan));
    EXPECT_TRUE(Run("metrics.image", metrics).ok());
    const nlohmann::json table = nlohmann::json::parse(std::ifstream(metrics.outputs_.at("table")));
    for (size_t c = 0; c < table["columns"].size(); ++c)
      if (table["columns"][c] == "hole_px") return table["rows"][0][c].get<double>();
    ADD_FAILURE() << "no hole_px column";
    return -1.0;
  };
  const double measured = hole_px(false, "measured"), projected = hole_px(true, "projected");
  EXPECT_GT(measured, 15);
  EXPECT_LT(projected, measured / 3);
}

}  // namespace
}  // namespace pb
