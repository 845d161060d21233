#include "stages/geometry/mesh/poisson.h"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string>

#include "stages/geometry/mesh/poisson_module.h"

#ifndef PB_POISSON_MODULE_DIR
#define PB_POISSON_MODULE_DIR ""
#endif

namespace pb {
namespace {

constexpr const char* kModuleName = "pointbake-poisson-open3d.so";

using ModuleFn = bool (*)(PoissonModuleCall*);

std::string ExecutableDir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : exe.parent_path().string();
}

struct LoadedModule {
  ModuleFn fn = nullptr;
  std::string error;  // when fn is null
};

// Loads the module once per process; later calls return the same result.
const LoadedModule& LoadModule() {
  static std::once_flag once;
  static LoadedModule loaded;
  std::call_once(once, [] {
    std::string tried;
    for (const std::string& path : PoissonModuleCandidates()) {
      if (!std::filesystem::exists(path)) {
        tried += "\n  " + path + ": not there";
        continue;
      }
      void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
      if (!handle) {
        tried += "\n  " + path + ": " + ::dlerror();
        continue;
      }
      void* symbol = ::dlsym(handle, PB_POISSON_MODULE_SYMBOL);
      if (!symbol) {
        tried += "\n  " + path + ": no " PB_POISSON_MODULE_SYMBOL " (built from another version?)";
        continue;
      }
      loaded.fn = reinterpret_cast<ModuleFn>(symbol);
      return;
    }
    loaded.error = std::string("screened Poisson needs ") + kModuleName +
                   ", built when Open3D 0.16 is installed (apt install libopen3d-dev, then "
                   "rebuild); looked in:" +
                   tried;
  });
  return loaded;
}

// Re-winds every face when most disagree with the interpolated normals.
bool AgreeWithNormals(Mesh& mesh) {
  if (!mesh.has_normals()) return false;
  int64_t agree = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    std::array<double, 3> p[3], n{};
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) {
        p[k][c] = mesh.positions[3 * t[k] + c];
        n[c] += mesh.normals[3 * t[k] + c];
      }
    }
    const std::array<double, 3> e1{p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const std::array<double, 3> e2{p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const std::array<double, 3> cross{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                      e1[0] * e2[1] - e1[1] * e2[0]};
    const double dot = cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2];
    agree += dot > 0 ? 1 : dot < 0 ? -1 : 0;
  }
  if (agree >= 0) return false;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
  }
  return true;
}

// Open3D emits vertices and faces in an order that depends on the thread
// count (the values do not). Sorts vertices by position (then normal, color,
// density) and faces by their corners, each face rotated to start at its
// smallest index (winding kept), so equal inputs give equal bytes.
void CanonicalOrder(PoissonOutput& out) {
  Mesh& mesh = out.mesh;
  const size_t nv = mesh.vertex_count();
  std::vector<uint32_t> order(nv);
  for (size_t v = 0; v < nv; ++v) order[v] = static_cast<uint32_t>(v);
  const auto key = [&](uint32_t v) {
    std::array<float, 7> k{};
    for (int c = 0; c < 3; ++c) {
      k[c] = mesh.positions[3 * v + c];
      k[3 + c] = mesh.has_normals() ? mesh.normals[3 * v + c] : 0.0f;
    }
    k[6] = out.densities[v];
    return k;
  };
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const auto ka = key(a), kb = key(b);
    if (ka != kb) return ka < kb;
    if (mesh.has_colors()) {
      for (int c = 0; c < 3; ++c) {
        if (mesh.colors[3 * a + c] != mesh.colors[3 * b + c]) {
          return mesh.colors[3 * a + c] < mesh.colors[3 * b + c];
        }
      }
    }
    return a < b;
  });
  std::vector<uint32_t> rank(nv);
  for (size_t i = 0; i < nv; ++i) rank[order[i]] = static_cast<uint32_t>(i);
  const auto permute = [&](auto& values, size_t width) {
    auto sorted = values;
    for (size_t i = 0; i < nv; ++i) {
      std::copy_n(&values[width * order[i]], width, &sorted[width * i]);
    }
    values = std::move(sorted);
  };
  permute(mesh.positions, 3);
  if (mesh.has_normals()) permute(mesh.normals, 3);
  if (mesh.has_colors()) permute(mesh.colors, 3);
  permute(out.densities, 1);

  std::vector<std::array<uint32_t, 3>> faces(mesh.face_count());
  for (size_t f = 0; f < faces.size(); ++f) {
    std::array<uint32_t, 3> t{rank[mesh.indices[3 * f]], rank[mesh.indices[3 * f + 1]],
                              rank[mesh.indices[3 * f + 2]]};
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    faces[f] = t;
  }
  std::sort(faces.begin(), faces.end());
  for (size_t f = 0; f < faces.size(); ++f) std::copy_n(faces[f].data(), 3, &mesh.indices[3 * f]);
}

// The cube Open3D reconstructs in: the bounding box's center, its largest
// extent times `scale` (PoissonRecon's GetPointXForm).
void ReconstructionCube(const PointCloud& cloud, double scale, std::array<double, 3>* corner,
                        double* width) {
  const Bounds bounds = BoundsOf(cloud.positions);
  const std::array<double, 3> center = bounds.center_m();
  const std::array<double, 3> extent = bounds.extent_m();
  *width = std::max({extent[0], extent[1], extent[2]}) * scale;
  if (!(*width > 0)) *width = 1;
  for (int k = 0; k < 3; ++k) (*corner)[k] = center[k] - *width / 2;
}

// Interleaves the low `bits` bits of x, y, z (x lowest).
uint64_t Morton(uint32_t x, uint32_t y, uint32_t z, int bits) {
  uint64_t code = 0;
  for (int b = bits - 1; b >= 0; --b) {
    code = (code << 3) | (uint64_t{(z >> b) & 1u} << 2) | (uint64_t{(y >> b) & 1u} << 1) |
           uint64_t{(x >> b) & 1u};
  }
  return code;
}

}  // namespace

std::vector<std::string> PoissonModuleCandidates() {
  std::vector<std::string> paths;
  if (const char* env = std::getenv("PB_POISSON_MODULE"); env && *env) paths.push_back(env);
  if (const std::string dir = ExecutableDir(); !dir.empty()) {
    paths.push_back(dir + "/" + kModuleName);
  }
  if (std::string(PB_POISSON_MODULE_DIR).size() > 0) {
    const std::string built = std::string(PB_POISSON_MODULE_DIR) + "/" + kModuleName;
    if (std::find(paths.begin(), paths.end(), built) == paths.end()) paths.push_back(built);
  }
  return paths;
}

Expected<PoissonOutput> ReconstructPoisson(const PointCloud& cloud, const PoissonOptions& options) {
  if (options.depth < kPoissonMinDepth || options.depth > kPoissonMaxDepth) {
    return Status::Invalid("Poisson depth must be in [" + std::to_string(kPoissonMinDepth) + ", " +
                           std::to_string(kPoissonMaxDepth) + "], got " +
                           std::to_string(options.depth));
  }
  if (!(options.scale >= 1.0 && options.scale <= 4.0)) {
    return Status::Invalid("Poisson scale must be in [1, 4], got " + std::to_string(options.scale));
  }
  PB_RETURN_IF_ERROR(Validate(cloud));
  if (!cloud.has_normals()) {
    return Status::Invalid(
        "screened Poisson needs oriented normals; run points.normals before mesh.poisson");
  }
  if (cloud.size() < 3) {
    return Status::Invalid("screened Poisson needs at least 3 points, got " +
                           std::to_string(cloud.size()));
  }
  for (size_t i = 0; i < cloud.positions.size(); ++i) {
    if (!std::isfinite(cloud.positions[i])) {
      return Status::Invalid("point " + std::to_string(i / 3) +
                             " has a non-finite coordinate; drop such points first "
                             "(io.read_points drop_invalid)");
    }
  }
  const LoadedModule& module = LoadModule();
  if (!module.fn) return Status::Unsupported(module.error);

  PoissonOutput out;
  std::string error;
  PoissonModuleCall call;
  call.cloud = &cloud;
  call.options = options;
  call.mesh = &out.mesh;
  call.densities = &out.densities;
  call.error = &error;
  if (!module.fn(&call)) return Status::Internal("Open3D screened Poisson failed: " + error);
  if (out.densities.size() != out.mesh.vertex_count()) {
    return Status::Internal("Open3D returned " + std::to_string(out.densities.size()) +
                            " densities for " + std::to_string(out.mesh.vertex_count()) +
                            " vertices");
  }
  PB_RETURN_IF_ERROR(Validate(out.mesh).WithContext("Open3D's Poisson output"));
  out.rewound = AgreeWithNormals(out.mesh);
  CanonicalOrder(out);
  return out;
}

Mesh TrimByDensity(Mesh mesh, const std::vector<float>& densities, double quantile,
                   TrimReport* report) {
  TrimReport local;
  TrimReport& r = report ? *report : local;
  r = TrimReport();
  if (densities.empty() || !(quantile > 0)) {
    if (!densities.empty()) r.threshold = *std::min_element(densities.begin(), densities.end());
    return mesh;
  }
  std::vector<float> sorted = densities;
  const size_t rank = std::min(
      sorted.size() - 1, static_cast<size_t>(std::floor(quantile * static_cast<double>(sorted.size()))));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<ptrdiff_t>(rank), sorted.end());
  const float threshold = sorted[rank];
  r.threshold = threshold;

  size_t kept = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    if (densities[t[0]] < threshold || densities[t[1]] < threshold ||
        densities[t[2]] < threshold) {
      ++r.faces_removed;
      continue;
    }
    std::copy_n(t, 3, &mesh.indices[3 * kept++]);
  }
  mesh.indices.resize(3 * kept);
  r.vertices_removed = DropUnreferencedVertices(mesh);
  return mesh;
}

DepthChoice ChooseDepthForFaces(uint64_t target_faces, int probe_depth, uint64_t faces_at_probe,
                                const std::vector<uint64_t>& occupied) {
  DepthChoice best;
  double best_error = std::numeric_limits<double>::infinity();
  const double at_probe =
      probe_depth >= 0 && static_cast<size_t>(probe_depth) < occupied.size() && occupied[probe_depth]
          ? static_cast<double>(occupied[probe_depth])
          : 0;
  for (int d = kPoissonMinDepth; d <= kPoissonMaxDepth; ++d) {
    double predicted;
    if (at_probe > 0 && static_cast<size_t>(d) < occupied.size()) {
      predicted = static_cast<double>(faces_at_probe) * static_cast<double>(occupied[d]) / at_probe;
    } else {
      predicted = static_cast<double>(faces_at_probe) * std::pow(4.0, d - probe_depth);
    }
    predicted = std::max(predicted, 1.0);
    const double error = std::abs(std::log(predicted / static_cast<double>(target_faces)));
    if (error < best_error) {
      best_error = error;
      best = {d, predicted};
    }
  }
  return best;
}

std::vector<uint64_t> OccupiedCellsPerDepth(const PointCloud& cloud, double scale, int max_depth) {
  max_depth = std::clamp(max_depth, 0, 20);
  std::vector<uint64_t> occupied(static_cast<size_t>(max_depth) + 1, 0);
  const size_t n = cloud.size();
  if (n == 0) return occupied;
  std::array<double, 3> corner{};
  double width = 1;
  ReconstructionCube(cloud, scale, &corner, &width);
  const double cells = std::ldexp(1.0, max_depth);
  const auto max_cell = static_cast<uint32_t>(cells - 1);
  std::vector<uint64_t> codes(n);
  for (size_t i = 0; i < n; ++i) {
    uint32_t c[3];
    for (int k = 0; k < 3; ++k) {
      const double t = (cloud.positions[3 * i + k] - corner[k]) / width * cells;
      c[k] = t <= 0 ? 0 : std::min(max_cell, static_cast<uint32_t>(t));
    }
    codes[i] = Morton(c[0], c[1], c[2], max_depth);
  }
  std::sort(codes.begin(), codes.end());
  // Morton order is hierarchical: the depth-d cell is the code's prefix,
  // so distinct prefixes are counted in one pass per depth.
  for (int d = 0; d <= max_depth; ++d) {
    const int shift = 3 * (max_depth - d);
    uint64_t count = 0;
    uint64_t previous = std::numeric_limits<uint64_t>::max();
    for (const uint64_t code : codes) {
      const uint64_t prefix = shift >= 64 ? 0 : code >> shift;
      if (prefix != previous) {
        ++count;
        previous = prefix;
      }
    }
    occupied[d] = count;
  }
  return occupied;
}

}  // namespace pb
