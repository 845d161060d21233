#include "stages/geometry/mesh/vertex_order.h"

#include <meshoptimizer.h>

#include <cstdint>
#include <vector>

namespace pb {
namespace {

constexpr unsigned kCacheSize = 16;  // FIFO entries, typical of mobile GPUs
constexpr unsigned kCacheLine = 64;  // bytes

void Analyze(const Mesh& mesh, double* acmr, double* overfetch) {
  const size_t n = mesh.vertex_count();
  *acmr = meshopt_analyzeVertexCache(mesh.indices.data(), mesh.indices.size(), n, kCacheSize, 0, 0).acmr;
  // As one interleaved vertex of every attribute the mesh has (streams
  // follow the same order, so their locality is the same).
  const size_t vertex_bytes = sizeof(float) * (3 + (mesh.has_normals() ? 3 : 0) +
                                               (mesh.has_uvs() ? 2 : 0) + (mesh.has_tangents() ? 4 : 0)) +
                              (mesh.has_colors() ? 3 : 0);
  *overfetch = meshopt_analyzeVertexFetch(mesh.indices.data(), mesh.indices.size(), n, vertex_bytes).overfetch;
}

template <typename T>
void Remap(std::vector<T>& values, size_t per_vertex, const std::vector<uint32_t>& remap,
           size_t unique) {
  if (values.empty()) return;
  std::vector<T> out(unique * per_vertex);
  meshopt_remapVertexBuffer(out.data(), values.data(), remap.size(), per_vertex * sizeof(T),
                            remap.data());
  values = std::move(out);
}

}  // namespace

void OptimizeVertexOrder(Mesh& mesh, VertexOrderReport* report) {
  VertexOrderReport local;
  VertexOrderReport& out = report ? *report : local;
  const size_t n = mesh.vertex_count();
  if (mesh.indices.empty() || n == 0) return;
  Analyze(mesh, &out.acmr_before, &out.overfetch_before);
  std::vector<uint32_t> reordered(mesh.indices.size());
  meshopt_optimizeVertexCache(reordered.data(), mesh.indices.data(), mesh.indices.size(), n);
  // remap[old vertex] = new vertex, in first-use order; ~0u for unused ones.
  std::vector<uint32_t> remap(n);
  const size_t unique = meshopt_optimizeVertexFetchRemap(remap.data(), reordered.data(),
                                                         reordered.size(), n);
  meshopt_remapIndexBuffer(mesh.indices.data(), reordered.data(), reordered.size(), remap.data());
  Remap(mesh.positions, 3, remap, unique);
  Remap(mesh.normals, 3, remap, unique);
  Remap(mesh.colors, 3, remap, unique);
  Remap(mesh.uvs, 2, remap, unique);
  Remap(mesh.tangents, 4, remap, unique);
  Analyze(mesh, &out.acmr_after, &out.overfetch_after);
}

}  // namespace pb
