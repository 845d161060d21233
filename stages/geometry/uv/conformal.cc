// LSCM (Lévy et al. 2002) of one chart; see conformal.h.
#include "stages/geometry/uv/conformal.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pb {
namespace {

// Approximate minimum degree ordering of the LSCM normal matrix computed on
// its vertex graph: the two unknowns (u, v) of a vertex have the same
// rows, so the matrix is the vertex pattern with every entry a 2x2 block.
// Ordering the vertices and keeping each vertex's u and v together costs
// a quarter of ordering the unknowns (Eigen's AMDOrdering), for the same
// kind of fill.
struct VertexAmdOrdering {
  using PermutationType = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;
  // `full`: both triangles, as SimplicialLDLT passes it.
  template <typename MatrixType>
  void operator()(const MatrixType& full, PermutationType& perm) {
    const int cols = int(full.cols()), vertices = cols / 2;
    perm.resize(cols);
    if (vertices < 2) {  // nothing to order
      perm.setIdentity();
      return;
    }
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> graph(vertices, vertices);
    std::vector<int> outer(vertices + 1, 0), inner;
    inner.reserve(full.nonZeros() / 4 + vertices);
    for (int u = 0; u < vertices; ++u) {
      for (typename MatrixType::InnerIterator it(full, 2 * u); it; ++it) {
        if (it.row() % 2 == 0) inner.push_back(int(it.row()) / 2);
      }
      outer[u + 1] = int(inner.size());
    }
    graph.resizeNonZeros(int(inner.size()));
    std::copy(outer.begin(), outer.end(), graph.outerIndexPtr());
    std::copy(inner.begin(), inner.end(), graph.innerIndexPtr());
    std::fill(graph.valuePtr(), graph.valuePtr() + inner.size(), 1.0);
    PermutationType vertex_perm;
    Eigen::internal::minimum_degree_ordering(graph, vertex_perm);
    for (int i = 0; i < vertices; ++i) {
      perm.indices()[2 * i] = 2 * vertex_perm.indices()[i];
      perm.indices()[2 * i + 1] = 2 * vertex_perm.indices()[i] + 1;
    }
  }
};

double Distance2(std::span<const double> p, uint32_t a, uint32_t b) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = p[3 * size_t(a) + k] - p[3 * size_t(b) + k];
    d2 += d * d;
  }
  return d2;
}

// The vertex of `used` farthest from `from` (lowest index on ties).
uint32_t Farthest(std::span<const double> p, const std::vector<uint32_t>& used, uint32_t from) {
  uint32_t best = from;
  double best_d2 = -1;
  for (uint32_t v : used) {
    const double d2 = Distance2(p, v, from);
    if (d2 > best_d2) {
      best_d2 = d2;
      best = v;
    }
  }
  return best;
}

}  // namespace

bool LscmFlatten(std::span<const double> positions, std::span<const uint32_t> corners,
                 std::vector<double>* uv) {
  const size_t n = positions.size() / 3, faces = corners.size() / 3;
  uv->assign(2 * n, 0.0);
  // The vertices that some face uses, increasing (marks, not a sort).
  std::vector<char> is_used(n, 0);
  for (uint32_t v : corners) is_used[v] = 1;
  std::vector<uint32_t> used;
  used.reserve(n);
  for (size_t v = 0; v < n; ++v) {
    if (is_used[v]) used.push_back(uint32_t(v));
  }
  if (used.size() < 2) return false;
  // Two far-apart pins fix the similarity and keep the solve well scaled.
  const uint32_t pin_a = Farthest(positions, used, Farthest(positions, used, used.front()));
  const uint32_t pin_b = Farthest(positions, used, pin_a);
  const double pin_distance = std::sqrt(Distance2(positions, pin_a, pin_b));
  if (!(pin_distance > 0)) return false;

  // Unknowns: u, v of every used vertex but the pins.
  constexpr int kPinned = -1;
  std::vector<int> column(n, kPinned);
  int unknowns = 0;
  for (uint32_t v : used) {
    if (v != pin_a && v != pin_b) column[v] = 2 * unknowns++;
  }
  const int cols = 2 * unknowns;
  double pinned_uv[2][2] = {{0, 0}, {pin_distance, 0}};
  auto pin_index = [&](uint32_t v) { return v == pin_a ? 0 : 1; };

  // The normal equations AᵀA x = Aᵀb, assembled directly in compressed
  // columns (lower triangle, all SimplicialLDLT reads): each face gives two
  // rows of A; every entry of AᵀA and Aᵀb sums its rows' products in
  // increasing row order, as Eigen's sparse product AᵀA of the row matrix
  // did (same bits), without building A, its transpose and the product.
  struct FaceRows {
    int entries = 0;
    int column[6];
    double value[2][6];
    double b[2] = {0, 0};
  };
  std::vector<FaceRows> rows;
  rows.reserve(faces);
  for (size_t f = 0; f < faces; ++f) {
    const uint32_t v[3] = {corners[3 * f], corners[3 * f + 1], corners[3 * f + 2]};
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
      e1[k] = positions[3 * size_t(v[1]) + k] - positions[3 * size_t(v[0]) + k];
      e2[k] = positions[3 * size_t(v[2]) + k] - positions[3 * size_t(v[0]) + k];
    }
    const double length1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    const double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                             e1[0] * e2[1] - e1[1] * e2[0]};
    const double twice_area =
        std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
    if (!(length1 > 0) || !(twice_area > 1e-14 * length1 * length1)) continue;
    // The face's own frame: x along e1, y in the face plane (so that the face
    // is counter-clockwise in it).
    const double x2 = (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / length1;
    const double y2 = twice_area / length1;
    const double x[3] = {0, length1, x2}, y[3] = {0, 0, y2};
    // dU/dz-bar = sum_j W_j U_j / (4 A) with W_j = (y_{j+1} - y_{j+2}) + i (x_{j+2} - x_{j+1});
    // the row is scaled by 1/sqrt(A) so that each face weighs by its area.
    const double scale = 1.0 / std::sqrt(0.5 * twice_area);
    FaceRows& face = rows.emplace_back();
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double a = (y[j1] - y[j2]) * scale, b = (x[j2] - x[j1]) * scale;
      // Re(W U) = a u - b v, Im(W U) = b u + a v.
      if (column[v[j]] == kPinned) {
        const double* p = pinned_uv[pin_index(v[j])];
        face.b[0] -= a * p[0] - b * p[1];
        face.b[1] -= b * p[0] + a * p[1];
      } else {
        const int c = column[v[j]], e = face.entries;
        face.column[e] = c;
        face.column[e + 1] = c + 1;
        face.value[0][e] = a;
        face.value[0][e + 1] = -b;
        face.value[1][e] = b;
        face.value[1][e + 1] = a;
        face.entries += 2;
      }
    }
  }
  if (cols > 0) {
    // Pattern: column q holds the rows p >= q of the unknowns that share a
    // face with it (each unknown vertex's two columns have the same rows).
    const int vertices = cols / 2;
    std::vector<std::vector<int>> near(vertices);
    for (int u = 0; u < vertices; ++u) near[u].push_back(u);  // the diagonal, always
    for (const FaceRows& face : rows) {
      for (int p = 0; p < face.entries; p += 2) {
        for (int q = 0; q < face.entries; q += 2) {
          if (face.column[p] >= face.column[q]) near[face.column[q] / 2].push_back(face.column[p] / 2);
        }
      }
    }
    std::vector<int> outer(cols + 1, 0);
    for (int u = 0; u < vertices; ++u) {
      std::vector<int>& list = near[u];
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      // Column 2u: rows 2w, 2w+1 for every w; column 2u+1: the same but 2u.
      outer[2 * u + 1] = outer[2 * u] + 2 * int(list.size());
      outer[2 * u + 2] = outer[2 * u + 1] + 2 * int(list.size()) - 1;
    }
    Eigen::SparseMatrix<double> normal(cols, cols);
    normal.resizeNonZeros(outer[cols]);
    std::copy(outer.begin(), outer.end(), normal.outerIndexPtr());
    int* inner = normal.innerIndexPtr();
    double* values = normal.valuePtr();
    std::fill(values, values + outer[cols], 0.0);
    for (int u = 0; u < vertices; ++u) {
      int k = outer[2 * u];
      for (int w : near[u]) {
        inner[k++] = 2 * w;
        inner[k++] = 2 * w + 1;
      }
      for (int w : near[u]) {
        if (w != u) inner[k++] = 2 * w;
        inner[k++] = 2 * w + 1;
      }
    }
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(cols);
    for (const FaceRows& face : rows) {
      for (int r = 0; r < 2; ++r) {
        for (int p = 0; p < face.entries; ++p) {
          const int row = face.column[p];
          for (int q = 0; q < face.entries; ++q) {
            const int col = face.column[q];
            if (row < col) continue;
            int k = outer[col];
            while (inner[k] != row) ++k;
            values[k] += face.value[r][p] * face.value[r][q];
          }
          rhs[row] += face.value[r][p] * face.b[r];
        }
      }
    }
    // A whisper of regularization keeps vertices that only degenerate faces
    // reach from making the system singular (they land near the origin and
    // the chart's overlap check splits them off).
    double trace = 0;
    for (int k = 0; k < cols; ++k) trace += normal.coeff(k, k);
    const double ridge = 1e-12 * (trace > 0 ? trace / cols : 1.0);
    for (int k = 0; k < cols; ++k) normal.coeffRef(k, k) += ridge;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, VertexAmdOrdering> solver(
        normal);
    if (solver.info() != Eigen::Success) return false;
    const Eigen::VectorXd solution = solver.solve(rhs);
    if (solver.info() != Eigen::Success) return false;
    for (uint32_t vtx : used) {
      if (column[vtx] == kPinned) continue;
      (*uv)[2 * size_t(vtx)] = solution[column[vtx]];
      (*uv)[2 * size_t(vtx) + 1] = solution[column[vtx] + 1];
      if (!std::isfinite((*uv)[2 * size_t(vtx)]) || !std::isfinite((*uv)[2 * size_t(vtx) + 1])) {
        return false;
      }
    }
  }
  for (uint32_t p : {pin_a, pin_b}) {
    (*uv)[2 * size_t(p)] = pinned_uv[pin_index(p)][0];
    (*uv)[2 * size_t(p) + 1] = pinned_uv[pin_index(p)][1];
  }
  return true;
}

}  // namespace pb
