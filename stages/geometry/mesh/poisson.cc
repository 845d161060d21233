#include "stages/geometry/mesh/poisson.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string>

#include "stages/geometry/core/module.h"
#include "stages/geometry/mesh/poisson_module.h"
#include "stages/geometry/points/knn.h"

namespace pb {
namespace {

using ModuleFn = bool (*)(PoissonModuleCall*);

// PCL's Poisson returns positions and faces only: each vertex takes the
// inverse-distance-weighted mean of the normals and colors of its
// kAttributeNeighbors nearest points (Open3D interpolates them inside its
// solver), so the two implementations give the same kind of mesh.
constexpr int kAttributeNeighbors = 4;
Status AttributesFromPoints(const PointCloud& cloud, Mesh& mesh) {
  PB_ASSIGN_OR_RETURN(const KnnIndex index, KnnIndex::Build(cloud.positions));
  const size_t nv = mesh.vertex_count();
  mesh.normals.assign(3 * nv, 0.0f);
  if (cloud.has_colors()) mesh.colors.assign(3 * nv, 0);
  std::vector<Neighbor> neighbors(kAttributeNeighbors);
  for (size_t v = 0; v < nv; ++v) {
    const int count = index.Query(&mesh.positions[3 * v], kAttributeNeighbors, neighbors);
    double normal[3] = {0, 0, 0}, color[3] = {0, 0, 0}, total = 0;
    for (int j = 0; j < count; ++j) {
      const uint32_t p = neighbors[j].index;
      const double weight = 1.0 / (std::sqrt(neighbors[j].squared_distance_m2) + 1e-9);
      total += weight;
      for (int c = 0; c < 3; ++c) {
        normal[c] += weight * cloud.normals[3 * p + c];
        if (cloud.has_colors()) color[c] += weight * cloud.colors[3 * p + c];
      }
    }
    const double length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    for (int c = 0; c < 3; ++c) {
      if (length > 0) mesh.normals[3 * v + c] = static_cast<float>(normal[c] / length);
      if (cloud.has_colors() && total > 0) {
        mesh.colors[3 * v + c] =
            static_cast<uint8_t>(std::clamp(std::lround(color[c] / total), 0L, 255L));
      }
    }
  }
  return Status::Ok();
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

std::vector<std::string> PoissonModuleCandidates() { return ModuleCandidates(kOpen3dModule); }

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
  const bool pcl = options.implementation == PoissonImplementation::kPcl;
  if (pcl && options.linear_fit) {
    return Status::Invalid("Poisson: linear_fit is an Open3D option; PCL's Poisson has none");
  }
  PB_ASSIGN_OR_RETURN(
      void* symbol,
      pcl ? ModuleSymbol(kPclModule, PB_PCL_POISSON_SYMBOL, "screened Poisson (implementation 'pcl')")
          : ModuleSymbol(kOpen3dModule, PB_POISSON_MODULE_SYMBOL,
                         "screened Poisson (implementation 'open3d')"));
  const auto run = reinterpret_cast<ModuleFn>(symbol);

  PoissonOutput out;
  std::string error;
  PoissonModuleCall call;
  call.cloud = &cloud;
  call.options = options;
  call.mesh = &out.mesh;
  call.densities = &out.densities;
  call.error = &error;
  const char* solver = pcl ? "PCL" : "Open3D";
  if (!run(&call)) return Status::Internal(std::string(solver) + " screened Poisson failed: " + error);
  if (pcl) {
    PB_RETURN_IF_ERROR(Validate(out.mesh).WithContext("PCL's Poisson output"));
    PB_RETURN_IF_ERROR(AttributesFromPoints(cloud, out.mesh));
    out.densities.assign(out.mesh.vertex_count(), 0.0f);
  }
  if (out.densities.size() != out.mesh.vertex_count()) {
    return Status::Internal(std::string(solver) + " returned " + std::to_string(out.densities.size()) +
                            " densities for " + std::to_string(out.mesh.vertex_count()) +
                            " vertices");
  }
  PB_RETURN_IF_ERROR(Validate(out.mesh).WithContext(std::string(solver) + "'s Poisson output"));
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
