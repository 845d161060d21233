// bake.from_mesh: the "selected to active" bake of Blender's Cycles
// (docs.blender.org, Render > Cycles > Baking: "Selected to Active", "Cage
// Extrusion", "Max Ray Distance"), which the paper's Remeshing workflow uses
// to carry the high mesh's colors and normals onto the low mesh's atlas.
// Per texel of the low mesh two rays leave the interpolated surface point
// along +n and -n up to cage_m; the nearer hit on the high mesh gives the
// color and normal. Departs from Blender in two ways, both for a bake that
// needs no per-scene tuning: Blender casts inwards from an extruded cage
// (one direction, from cage distance), we cast both ways from the surface
// itself, which finds the high surface on either side without knowing which
// side it lies on; and a texel with no hit keeps the low mesh's own vertex
// colors and a flat normal instead of black.
//
// Rays: Embree 3 (Wald et al. 2014, "Embree: A Kernel Framework for
// Efficient CPU Ray Tracing"), a face's texels in coherent streams of up to
// 64 rays (rtcIntersect1M; 20% less CPU than one rtcIntersect1 per ray on
// the 240k/5M-face figure), robust mode (13% slower, but no ray slips
// between two triangles of the high mesh). A texel is independent of every
// other and a face's batches do not depend on the threads, so neither does
// the output.
#include "stages/geometry/bake/from_mesh.h"

#include <embree3/rtcore.h>
#include <tbb/task_arena.h>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "stages/geometry/core/tangents.h"

namespace pb {
namespace {

using Clock = std::chrono::steady_clock;

// Texels traced together: a face of a 240k-face mesh in a 4096^2 atlas owns
// about 50.
constexpr size_t kBatch = 64;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// CPU time of the whole process, all threads.
double ProcessCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

const char* EmbreeErrorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognized error";
}

// An Embree device and one triangle scene, released together. Embree reports
// errors through a callback (the text) and rtcGetDeviceError (the code).
class RayScene {
 public:
  RayScene() = default;
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;
  ~RayScene() {
    if (scene_ != nullptr) rtcReleaseScene(scene_);
    if (device_ != nullptr) rtcReleaseDevice(device_);
  }

  // `positions` are xyz floats already in the frame rays are cast in;
  // `indices` must outlive the scene (Embree reads them in place).
  Status Build(std::vector<float> positions, const std::vector<uint32_t>& indices, int threads) {
    const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : "";
    device_ = rtcNewDevice(config.empty() ? nullptr : config.c_str());
    if (device_ == nullptr) {
      return Status::Internal(std::string("bake from mesh: cannot create an Embree device: ") +
                              EmbreeErrorName(rtcGetDeviceError(nullptr)));
    }
    rtcSetDeviceErrorFunction(device_, &RayScene::OnError, this);
    scene_ = rtcNewScene(device_);
    if (scene_ == nullptr) return Failure("rtcNewScene");
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);

    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (geometry == nullptr) return Failure("rtcNewGeometry");
    const size_t vertex_count = positions.size() / 3;
    // Embree's own buffer: it pads the end for its 16-byte vector loads.
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
    if (vertices == nullptr) {
      rtcReleaseGeometry(geometry);
      return Failure("rtcSetNewGeometryBuffer");
    }
    std::copy(positions.begin(), positions.end(), vertices);
    positions = {};
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               indices.data(), 0, 3 * sizeof(uint32_t), indices.size() / 3);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_, geometry);
    rtcReleaseGeometry(geometry);  // the scene holds it
    if (Failed()) return Failure("building the geometry");

    // Embree's TBB tasks run in the caller's arena: this one caps them at
    // `threads` as the device config does.
    if (threads > 0) {
      tbb::task_arena arena(threads);
      arena.execute([&] { rtcCommitScene(scene_); });
    } else {
      rtcCommitScene(scene_);
    }
    if (Failed()) return Failure("rtcCommitScene");
    return Status::Ok();
  }

  RTCScene scene() const { return scene_; }

 private:
  // rtcGetDeviceError is per thread; the callback sees errors from any.
  bool Failed() {
    const RTCError code = rtcGetDeviceError(device_);
    std::lock_guard<std::mutex> lock(mutex_);
    if (code != RTC_ERROR_NONE && message_.empty()) message_ = EmbreeErrorName(code);
    return !message_.empty();
  }

  static void OnError(void* user, RTCError code, const char* message) {
    auto* self = static_cast<RayScene*>(user);
    std::lock_guard<std::mutex> lock(self->mutex_);
    if (self->message_.empty()) {
      self->message_ = std::string(EmbreeErrorName(code)) + (message ? ": " : "") +
                       (message ? message : "");
    }
  }

  Status Failure(const char* step) {
    Failed();  // picks up this thread's error code when no message came
    std::lock_guard<std::mutex> lock(mutex_);
    return Status::Internal(std::string("bake from mesh: Embree failed in ") + step + ": " +
                            (message_.empty() ? "no error reported" : message_));
  }

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::mutex mutex_;
  std::string message_;  // the first error Embree reported
};

void InitRay(RTCRayHit& ray, const std::array<float, 3>& origin, const std::array<float, 3>& dir,
             float sign, float tfar) {
  ray.ray.org_x = origin[0];
  ray.ray.org_y = origin[1];
  ray.ray.org_z = origin[2];
  ray.ray.dir_x = sign * dir[0];
  ray.ray.dir_y = sign * dir[1];
  ray.ray.dir_z = sign * dir[2];
  ray.ray.tnear = 0;
  ray.ray.tfar = tfar;
  ray.ray.time = 0;
  ray.ray.mask = 0xffffffffu;
  ray.ray.id = 0;
  ray.ray.flags = 0;
  ray.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  ray.hit.primID = RTC_INVALID_GEOMETRY_ID;
  ray.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

bool Hit(const RTCRayHit& ray) { return ray.hit.geomID != RTC_INVALID_GEOMETRY_ID; }

// The rays of one batch of a face's texels: neighbours on one triangle with
// nearly parallel normals, which Embree's coherent stream mode traces as
// packets.
void CastBatch(RTCScene scene, RTCRayHit* rays, size_t count) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  rtcIntersect1M(scene, &context, rays, unsigned(count), sizeof(RTCRayHit));
}

// Per-vertex attribute `values` (stride 3) of `mesh` interpolated over
// `face` with weights `w`.
template <typename T>
std::array<float, 3> Interpolate(const Mesh& mesh, const std::vector<T>& values, uint32_t face,
                                 const std::array<float, 3>& w) {
  std::array<float, 3> out{};
  for (int corner = 0; corner < 3; ++corner) {
    const T* value = &values[3 * size_t(mesh.indices[3 * size_t(face) + corner])];
    for (int k = 0; k < 3; ++k) out[k] += w[corner] * float(value[k]);
  }
  return out;
}

Status CheckInputs(const Mesh& low, const Mesh& high, const FromMeshOptions& from_mesh) {
  if (!(from_mesh.cage_m > 0) || !std::isfinite(from_mesh.cage_m)) {
    return Status::Invalid("bake from mesh: cage must be a positive distance in meters, got " +
                           std::to_string(from_mesh.cage_m));
  }
  if (!low.has_uvs()) return Status::Invalid("bake from mesh: the target mesh has no uvs");
  if (Status status = Validate(high); !status.ok()) {
    return status.WithContext("bake from mesh: the source mesh");
  }
  if (!high.has_colors()) {
    return Status::Invalid(
        "bake from mesh: the source mesh has no vertex colors: nothing to bake");
  }
  if (high.face_count() == 0) {
    return Status::Invalid("bake from mesh: the source mesh has no faces to cast rays at");
  }
  return Status::Ok();
}

}  // namespace

Expected<BakeResult> BakeFromMesh(Mesh low, const Mesh& high, const BakeOptions& options,
                                  const FromMeshOptions& from_mesh, FromMeshReport* report) {
  PB_RETURN_IF_ERROR(CheckInputs(low, high, from_mesh));
  PB_ASSIGN_OR_RETURN(Mesh mesh, PrepareBakeMesh(std::move(low)));
  PB_ASSIGN_OR_RETURN(BakeRaster raster, BakeRaster::Build(mesh, options.size, options.threads));

  const auto build_start = Clock::now();
  const double build_cpu_start = ProcessCpuSeconds();
  std::vector<float> high_normals_computed;
  if (!high.has_normals()) high_normals_computed = ComputeVertexNormals(high);
  const std::vector<float>& high_normals =
      high.has_normals() ? high.normals : high_normals_computed;
  // The high mesh in the low mesh's frame: the shift in double, then float.
  std::vector<float> positions(high.positions.size());
  const double shift[3] = {high.origin[0] - mesh.origin[0], high.origin[1] - mesh.origin[1],
                           high.origin[2] - mesh.origin[2]};
  for (size_t i = 0; i < positions.size(); ++i) {
    positions[i] = float(double(high.positions[i]) + shift[i % 3]);
  }
  RayScene rays;
  PB_RETURN_IF_ERROR(rays.Build(std::move(positions), high.indices, options.threads));
  const double build_seconds = SecondsSince(build_start);
  const double build_cpu_seconds = ProcessCpuSeconds() - build_cpu_start;

  BakeMaps maps = BakeMaps::Make(options.size, options.float_normals);
  // Per face, so that the totals are summed in face order whatever the
  // threads: each face is baked by one call.
  std::vector<uint32_t> face_hits(mesh.face_count(), 0);
  std::vector<double> face_distance(mesh.face_count(), 0.0);
  const float cage = float(from_mesh.cage_m);
  const RTCScene scene = rays.scene();
  const auto ray_start = Clock::now();
  const double ray_cpu_start = ProcessCpuSeconds();
  ForEachBakeFace(
      mesh, raster, options.threads,
      [&](uint32_t face, std::span<const BakeTexel> texels) {
        uint32_t hits = 0;
        double distance = 0;
        std::array<TexelFrame, kBatch> frames;
        std::array<RTCRayHit, kBatch> forward, backward;
        for (size_t first = 0; first < texels.size(); first += kBatch) {
          const size_t count = std::min(kBatch, texels.size() - first);
          for (size_t i = 0; i < count; ++i) {
            frames[i] = FrameAt(mesh, face, texels[first + i].bary);
            InitRay(forward[i], frames[i].position, frames[i].normal, 1.0f, cage);
          }
          CastBatch(scene, forward.data(), count);
          // Backwards only a strictly nearer hit wins (ties go forward), so
          // the forward hit bounds the search.
          for (size_t i = 0; i < count; ++i) {
            InitRay(backward[i], frames[i].position, frames[i].normal, -1.0f,
                    Hit(forward[i]) ? forward[i].ray.tfar : cage);
          }
          CastBatch(scene, backward.data(), count);
          for (size_t i = 0; i < count; ++i) {
            const BakeTexel& texel = texels[first + i];
            const bool back_wins =
                Hit(backward[i]) && (!Hit(forward[i]) || backward[i].ray.tfar < forward[i].ray.tfar);
            const RTCRayHit* best =
                back_wins ? &backward[i] : Hit(forward[i]) ? &forward[i] : nullptr;
            if (best != nullptr) {
              const std::array<float, 3> w = {1.0f - best->hit.u - best->hit.v, best->hit.u,
                                              best->hit.v};
              maps.SetColor(texel.x, texel.y, Interpolate(high, high.colors, best->hit.primID, w));
              const std::array<float, 3> normal =
                  Interpolate(high, high_normals, best->hit.primID, w);
              maps.SetNormal(texel.x, texel.y, ToTangentSpace(frames[i], normal));
              ++hits;
              distance += best->ray.tfar;
            } else {
              maps.SetColor(texel.x, texel.y,
                            mesh.has_colors() ? Interpolate(mesh, mesh.colors, face, texel.bary)
                                              : std::array<float, 3>{0, 0, 0});
              maps.SetNormal(texel.x, texel.y, {0, 0, 1});
            }
          }
        }
        face_hits[face] = hits;
        face_distance[face] = distance;
      },
      options.progress);
  const double ray_seconds = SecondsSince(ray_start);
  const double ray_cpu_seconds = ProcessCpuSeconds() - ray_cpu_start;

  BakeResult result;
  result.covered_texels = raster.covered_texels();
  result.edge_texels = raster.edge_texels();
  result.gutter_texels = DilateBakeMaps(maps, raster, options.gutter, options.threads);
  result.maps = std::move(maps);
  result.mesh = std::move(mesh);
  if (report != nullptr) {
    size_t hits = 0;
    double distance = 0;
    for (size_t f = 0; f < face_hits.size(); ++f) {
      hits += face_hits[f];
      distance += face_distance[f];
    }
    report->texels_hit = hits;
    report->texels_fallback = result.covered_texels - hits;
    report->mean_hit_distance_m = hits > 0 ? distance / double(hits) : 0.0;
    report->rays_cast = 2 * result.covered_texels;
    report->build_seconds = build_seconds;
    report->ray_seconds = ray_seconds;
    report->build_cpu_seconds = build_cpu_seconds;
    report->ray_cpu_seconds = ray_cpu_seconds;
  }
  return result;
}

}  // namespace pb
