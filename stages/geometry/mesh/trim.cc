// Trimming by support (see trim.h). The hysteresis on connected regions is
// the two-threshold scheme of Canny's edge linking (Canny 1986, "A
// computational approach to edge detection", PAMI 8(6)) applied to faces:
// weak evidence counts only when it is connected to strong evidence.
#include "stages/geometry/mesh/trim.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>

#include "stages/geometry/points/knn.h"
#include "stages/geometry/points/spacing.h"

namespace pb {
namespace {

// Runs body(begin, end) over [0, n) in parallel, in an arena of `threads`
// when threads > 0. Results must not depend on the split (each index
// writes only its own slots).
template <typename Body>
void ParallelRanges(size_t n, int threads, const Body& body) {
  const auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024),
                      [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
  };
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute(run);
  } else {
    run();
  }
}

// The scan as a support field: nearest point and its local spacing, for
// positions given in the mesh's frame.
struct SupportField {
  KnnIndex index;
  std::vector<float> spacing;        // per point, meters
  std::array<double, 3> mesh_to_cloud{};  // add to a mesh position to get the cloud frame

  // Distance (meters) to the nearest point and that point's local spacing.
  void Nearest(const std::array<double, 3>& mesh_xyz, double* distance_m,
               double* spacing_m) const {
    const float q[3] = {static_cast<float>(mesh_xyz[0] + mesh_to_cloud[0]),
                        static_cast<float>(mesh_xyz[1] + mesh_to_cloud[1]),
                        static_cast<float>(mesh_xyz[2] + mesh_to_cloud[2])};
    Neighbor nearest[1];
    index.Query(q, 1, nearest);
    *distance_m = std::sqrt(nearest[0].squared_distance_m2);
    *spacing_m = spacing[nearest[0].index];
  }
};

Expected<SupportField> BuildField(const Mesh& mesh, const PointCloud& points, int k,
                                  int threads) {
  SupportField field;
  PB_ASSIGN_OR_RETURN(field.index, KnnIndex::Build(points.positions));
  if (field.index.size() <= static_cast<size_t>(k)) {
    return Status::Invalid("support: needs more than " + std::to_string(k) +
                           " points for the local spacing, the cloud has " +
                           std::to_string(field.index.size()));
  }
  Expected<std::vector<float>> spacing = Status::Internal("not run");
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute([&] { spacing = LocalSpacing(field.index, k); });
  } else {
    spacing = LocalSpacing(field.index, k);
  }
  PB_ASSIGN_OR_RETURN(field.spacing, std::move(spacing));
  for (int c = 0; c < 3; ++c) field.mesh_to_cloud[c] = mesh.origin[c] - points.origin[c];
  return field;
}

std::array<double, 3> Vertex(const Mesh& mesh, uint32_t v) {
  return {mesh.positions[3 * size_t{v}], mesh.positions[3 * size_t{v} + 1],
          mesh.positions[3 * size_t{v} + 2]};
}

double Distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

double TriangleArea(const std::array<double, 3>& a, const std::array<double, 3>& b,
                    const std::array<double, 3>& c) {
  const std::array<double, 3> u{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const std::array<double, 3> v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double x = u[1] * v[2] - u[2] * v[1];
  const double y = u[2] * v[0] - u[0] * v[2];
  const double z = u[0] * v[1] - u[1] * v[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

// (edge key, face) for every side of every face, sorted.
std::vector<std::pair<uint64_t, uint32_t>> SortedFaceEdges(const Mesh& mesh) {
  std::vector<std::pair<uint64_t, uint32_t>> edges;
  edges.reserve(mesh.indices.size());
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    for (int k = 0; k < 3; ++k) {
      edges.emplace_back(EdgeKey(t[k], t[(k + 1) % 3]), static_cast<uint32_t>(f));
    }
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

uint32_t FindRoot(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

double MeanEdgeLength(const Mesh& mesh) {
  if (mesh.face_count() == 0) return 0;
  double sum = 0;
  for (size_t f = 0; f < mesh.face_count(); ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    for (int k = 0; k < 3; ++k) sum += Distance(Vertex(mesh, t[k]), Vertex(mesh, t[(k + 1) % 3]));
  }
  return sum / (3.0 * static_cast<double>(mesh.face_count()));
}

uint64_t CountBoundaryEdges(const Mesh& mesh) {
  // Vertices at one position are one vertex: uv.unwrap splits vertices along
  // its seams, and a seam is no border of the surface.
  const std::vector<uint32_t> partners = EdgePartners(mesh, WeldedVertices(mesh));
  return static_cast<uint64_t>(std::count(partners.begin(), partners.end(), kBorderEdge));
}

Expected<Mesh> TrimUnsupported(const Mesh& mesh, const PointCloud& points,
                               const TrimOptions& options, SupportTrimReport* report) {
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext("mesh"));
  PB_RETURN_IF_ERROR(Validate(points).WithContext("points"));
  if (!(options.max_distance_spacings >= 0) || !(options.max_distance_edges >= 0) ||
      !(options.grow_fraction > 0 && options.grow_fraction <= 1) ||
      options.spacing_neighbors < 1 || options.min_region_faces < 0 ||
      options.smooth_passes < 0) {
    return Status::Invalid(
        "trim: need max_distance_spacings >= 0, max_distance_edges >= 0, grow_fraction in "
        "(0, 1], spacing_neighbors >= 1, min_region_faces >= 0 and smooth_passes >= 0");
  }
  SupportTrimReport local;
  SupportTrimReport& r = report ? *report : local;
  r = SupportTrimReport();
  r.faces_in = mesh.face_count();
  PB_ASSIGN_OR_RETURN(const SupportField field,
                      BuildField(mesh, points, options.spacing_neighbors, options.threads));
  r.median_spacing_m = MedianLocalSpacing(field.spacing);
  r.mean_edge_m = MeanEdgeLength(mesh);
  const double edge_term = options.max_distance_edges * r.mean_edge_m;
  // Distance of a mesh position as a fraction of its core threshold.
  const auto level = [&](const std::array<double, 3>& x) {
    double distance, spacing;
    field.Nearest(x, &distance, &spacing);
    const double threshold = std::max(options.max_distance_spacings * spacing, edge_term);
    return threshold > 0 ? distance / threshold : (distance > 0 ? HUGE_VAL : 0.0);
  };

  const size_t nv = mesh.vertex_count(), nf = mesh.face_count();
  std::vector<double> vertex_level(nv);
  ParallelRanges(nv, options.threads, [&](size_t begin, size_t end) {
    for (size_t v = begin; v < end; ++v) vertex_level[v] = level(Vertex(mesh, v));
  });
  std::vector<double> face_level(nf);
  ParallelRanges(nf, options.threads, [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) {
      const uint32_t* t = &mesh.indices[3 * f];
      std::array<double, 3> centroid{};
      for (int k = 0; k < 3; ++k) {
        const std::array<double, 3> p = Vertex(mesh, t[k]);
        for (int c = 0; c < 3; ++c) centroid[c] += p[c] / 3;
      }
      face_level[f] = std::min({level(centroid), vertex_level[t[0]], vertex_level[t[1]],
                                vertex_level[t[2]]});
    }
  });

  // Regions of weak faces joined through shared edges.
  std::vector<uint32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto weak = [&](uint32_t f) { return face_level[f] > options.grow_fraction; };
  const auto edges = SortedFaceEdges(mesh);
  for (size_t i = 1; i < edges.size(); ++i) {
    if (edges[i].first != edges[i - 1].first) continue;
    const uint32_t a = edges[i - 1].second, b = edges[i].second;
    if (!weak(a) || !weak(b)) continue;
    const uint32_t ra = FindRoot(parent, a), rb = FindRoot(parent, b);
    if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
  }
  std::vector<uint32_t> region_faces(nf, 0);
  std::vector<uint8_t> region_has_core(nf, 0);
  for (uint32_t f = 0; f < nf; ++f) {
    if (!weak(f)) continue;
    ++r.weak_faces;
    const uint32_t root = FindRoot(parent, f);
    ++region_faces[root];
    if (face_level[f] > 1) {
      ++r.core_faces;
      region_has_core[root] = 1;
    }
  }
  const auto removed_region = [&](uint32_t root) {
    return region_has_core[root] &&
           region_faces[root] >= static_cast<uint64_t>(options.min_region_faces);
  };
  for (uint32_t f = 0; f < nf; ++f) {
    if (weak(f) && FindRoot(parent, f) == f && removed_region(f)) ++r.regions_removed;
  }

  std::vector<uint8_t> removed(nf, 0);
  for (uint32_t f = 0; f < nf; ++f) {
    removed[f] = weak(f) && removed_region(FindRoot(parent, f));
  }
  // Border smoothing: a face-by-face cut zigzags at the size of a face, and
  // mesh.decimate holds borders, so every zigzag would cost faces of the
  // final mesh. Each pass flips, at once, every face whose three neighbours
  // (through edges) include at least two on the other side: kept spurs go,
  // removed notches come back. Faces on the mesh's own border count their
  // missing neighbour as neither side.
  std::vector<std::array<uint32_t, 3>> neighbor(nf, {UINT32_MAX, UINT32_MAX, UINT32_MAX});
  for (size_t i = 1; i < edges.size(); ++i) {
    if (edges[i].first != edges[i - 1].first) continue;
    if (i + 1 < edges.size() && edges[i + 1].first == edges[i].first) continue;  // non-manifold
    if (i >= 2 && edges[i - 2].first == edges[i].first) continue;
    const uint32_t a = edges[i - 1].second, b = edges[i].second;
    for (const auto& [f, g] : {std::pair{a, b}, std::pair{b, a}}) {
      for (uint32_t& slot : neighbor[f]) {
        if (slot == UINT32_MAX) {
          slot = g;
          break;
        }
      }
    }
  }
  for (int pass = 0; pass < options.smooth_passes; ++pass) {
    std::vector<uint8_t> next = removed;
    uint64_t flips = 0;
    for (uint32_t f = 0; f < nf; ++f) {
      int other = 0;
      for (const uint32_t g : neighbor[f]) other += g != UINT32_MAX && removed[g] != removed[f];
      // A removed face comes back only if the points support it a little
      // (not a core face), so a membrane is never patched back in.
      if (other >= 2 && (removed[f] == 0 || face_level[f] <= 1)) {
        next[f] = !removed[f];
        ++flips;
      }
    }
    removed.swap(next);
    r.smoothed_faces += flips;
    if (flips == 0) break;
  }

  Mesh out = mesh;
  size_t kept = 0;
  for (uint32_t f = 0; f < nf; ++f) {
    if (removed[f]) {
      ++r.faces_removed;
      continue;
    }
    std::copy_n(&mesh.indices[3 * size_t{f}], 3, &out.indices[3 * kept++]);
  }
  out.indices.resize(3 * kept);
  r.vertices_removed = DropUnreferencedVertices(out);
  return out;
}

Expected<SupportReport> MeasureSupport(const Mesh& mesh, const PointCloud& points,
                                       const SupportOptions& options) {
  PB_RETURN_IF_ERROR(Validate(mesh).WithContext("mesh"));
  PB_RETURN_IF_ERROR(Validate(points).WithContext("points"));
  if (!(options.spacings >= 0) || !(options.edges >= 0) || options.spacing_neighbors < 1) {
    return Status::Invalid("support: need spacings >= 0, edges >= 0, spacing_neighbors >= 1");
  }
  SupportReport r;
  r.faces = mesh.face_count();
  r.boundary_edges = CountBoundaryEdges(mesh);
  r.boundary_edges_per_1000_faces =
      r.faces ? 1000.0 * static_cast<double>(r.boundary_edges) / static_cast<double>(r.faces) : 0;
  r.mean_edge_m = MeanEdgeLength(mesh);
  const size_t nf = mesh.face_count();
  std::vector<double> area(nf);
  for (size_t f = 0; f < nf; ++f) {
    const uint32_t* t = &mesh.indices[3 * f];
    area[f] = TriangleArea(Vertex(mesh, t[0]), Vertex(mesh, t[1]), Vertex(mesh, t[2]));
    r.area_m2 += area[f];
  }
  if (nf == 0 || !(r.area_m2 > 0)) return r;
  PB_ASSIGN_OR_RETURN(const SupportField field,
                      BuildField(mesh, points, options.spacing_neighbors, options.threads));
  const double edge_term = options.edges * r.mean_edge_m;
  const double area_per_sample = r.area_m2 / static_cast<double>(std::max<size_t>(options.samples, 1));
  std::vector<double> invented(nf, 0.0);
  ParallelRanges(nf, options.threads, [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) {
      const uint32_t* t = &mesh.indices[3 * f];
      const std::array<double, 3> p[3] = {Vertex(mesh, t[0]), Vertex(mesh, t[1]),
                                          Vertex(mesh, t[2])};
      // m x m sub-triangles, one sample at each one's centroid (all equal area).
      const int m = std::clamp(static_cast<int>(std::round(std::sqrt(area[f] / area_per_sample))),
                               1, 64);
      int far = 0;
      const auto sample = [&](double a, double b) {
        std::array<double, 3> x;
        for (int c = 0; c < 3; ++c) x[c] = p[0][c] + a * (p[1][c] - p[0][c]) + b * (p[2][c] - p[0][c]);
        double distance, spacing;
        field.Nearest(x, &distance, &spacing);
        if (distance > std::max(options.spacings * spacing, edge_term)) ++far;
      };
      for (int i = 0; i < m; ++i) {
        for (int j = 0; i + j < m; ++j) {
          sample((i + 1.0 / 3) / m, (j + 1.0 / 3) / m);
          if (i + j < m - 1) sample((i + 2.0 / 3) / m, (j + 2.0 / 3) / m);
        }
      }
      invented[f] = area[f] * far / (static_cast<double>(m) * m);
    }
  });
  for (const double a : invented) r.invented_area_m2 += a;
  r.invented_fraction = r.invented_area_m2 / r.area_m2;
  return r;
}

}  // namespace pb
