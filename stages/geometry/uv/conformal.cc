// LSCM (Lévy et al. 2002) of one chart; see conformal.h.
#include "stages/geometry/uv/conformal.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <vector>

namespace pb {
namespace {

using Complex = std::complex<double>;

// Approximate minimum degree ordering of the LSCM matrix on its vertex
// graph: the pattern of the full (both triangles) matrix SimplicialLDLT
// passes, diagonal included, as a pattern-only copy (the ordering works in
// place on it).
struct VertexAmdOrdering {
  using PermutationType = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;
  template <typename MatrixType>
  void operator()(const MatrixType& full, PermutationType& perm) {
    const int vertices = int(full.cols());
    if (vertices < 2) {  // nothing to order
      perm.resize(vertices);
      perm.setIdentity();
      return;
    }
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> graph(vertices, vertices);
    const int entries = int(full.nonZeros());
    graph.resizeNonZeros(entries);
    std::copy(full.outerIndexPtr(), full.outerIndexPtr() + vertices + 1, graph.outerIndexPtr());
    std::copy(full.innerIndexPtr(), full.innerIndexPtr() + entries, graph.innerIndexPtr());
    std::fill(graph.valuePtr(), graph.valuePtr() + entries, 1.0);
    Eigen::internal::minimum_degree_ordering(graph, perm);
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

  // Unknowns: U = u + i v of every used vertex but the pins.
  constexpr int kPinned = -1;
  std::vector<int> column(n, kPinned);
  int unknowns = 0;
  for (uint32_t v : used) {
    if (v != pin_a && v != pin_b) column[v] = unknowns++;
  }
  const Complex pinned_uv[2] = {Complex(0, 0), Complex(pin_distance, 0)};
  auto pin_index = [&](uint32_t v) { return v == pin_a ? 0 : 1; };

  // Each face gives one complex row of A (its dU/dz-bar); the normal
  // equations A^H A U = A^H b are assembled directly in compressed columns
  // (lower triangle, all SimplicialLDLT reads). Complex, they have one
  // unknown per vertex: the real (u, v) form is the same system with every
  // entry a 2x2 block [re -im; im re], and factorizing it cost twice the
  // flops and four times the index work.
  struct FaceRow {
    int entries = 0;
    int column[3];
    Complex value[3];
    Complex b = 0;
  };
  std::vector<FaceRow> rows;
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
    FaceRow& face = rows.emplace_back();
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const Complex w((y[j1] - y[j2]) * scale, (x[j2] - x[j1]) * scale);
      if (column[v[j]] == kPinned) {
        face.b -= w * pinned_uv[pin_index(v[j])];
      } else {
        face.column[face.entries] = column[v[j]];
        face.value[face.entries++] = w;
      }
    }
  }
  if (unknowns > 0) {
    // Pattern: column q holds the rows p >= q of the unknowns that share a
    // face with it, the diagonal first: per column, the candidates (with
    // repeats) by counting, then each column sorted and deduplicated.
    std::vector<int> start(unknowns + 1, 0);
    for (const FaceRow& face : rows) {
      for (int p = 0; p < face.entries; ++p) {
        for (int q = 0; q < face.entries; ++q) {
          if (face.column[p] > face.column[q]) ++start[face.column[q] + 1];
        }
      }
    }
    for (int u = 0; u < unknowns; ++u) start[u + 1] += start[u] + 1;  // + the diagonal
    std::vector<int> candidates(start[unknowns]);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int u = 0; u < unknowns; ++u) candidates[fill[u]++] = u;
    for (const FaceRow& face : rows) {
      for (int p = 0; p < face.entries; ++p) {
        for (int q = 0; q < face.entries; ++q) {
          if (face.column[p] > face.column[q]) candidates[fill[face.column[q]]++] = face.column[p];
        }
      }
    }
    Eigen::SparseMatrix<Complex> normal(unknowns, unknowns);
    normal.resizeNonZeros(int(candidates.size()));
    int* outer = normal.outerIndexPtr();
    int* inner = normal.innerIndexPtr();
    outer[0] = 0;
    for (int u = 0; u < unknowns; ++u) {
      int* first = candidates.data() + start[u];
      int* last = candidates.data() + start[u + 1];
      std::sort(first + 1, last);  // the diagonal stays first
      last = std::unique(first, last);
      outer[u + 1] = int(std::copy(first, last, inner + outer[u]) - inner);
    }
    normal.resizeNonZeros(outer[unknowns]);
    Complex* values = normal.valuePtr();
    std::fill(values, values + outer[unknowns], Complex(0));
    Eigen::VectorXcd rhs = Eigen::VectorXcd::Zero(unknowns);
    for (const FaceRow& face : rows) {
      for (int p = 0; p < face.entries; ++p) {
        const int row = face.column[p];
        const Complex conj_p = std::conj(face.value[p]);
        for (int q = 0; q < face.entries; ++q) {
          const int col = face.column[q];
          if (row < col) continue;
          int k = outer[col];
          while (inner[k] != row) ++k;
          values[k] += conj_p * face.value[q];
        }
        rhs[row] += conj_p * face.b;
      }
    }
    // A whisper of regularization keeps vertices that only degenerate faces
    // reach from making the system singular (they land near the origin and
    // the chart's overlap check splits them off).
    double trace = 0;
    for (int u = 0; u < unknowns; ++u) trace += values[outer[u]].real();
    const double ridge = 1e-12 * (trace > 0 ? trace / unknowns : 1.0);
    for (int u = 0; u < unknowns; ++u) values[outer[u]] += ridge;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<Complex>, Eigen::Lower, VertexAmdOrdering> solver(
        normal);
    if (solver.info() != Eigen::Success) return false;
    const Eigen::VectorXcd solution = solver.solve(rhs);
    if (solver.info() != Eigen::Success) return false;
    for (uint32_t vtx : used) {
      if (column[vtx] == kPinned) continue;
      const Complex z = solution[column[vtx]];
      (*uv)[2 * size_t(vtx)] = z.real();
      (*uv)[2 * size_t(vtx) + 1] = z.imag();
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag())) return false;
    }
  }
  for (uint32_t p : {pin_a, pin_b}) {
    (*uv)[2 * size_t(p)] = pinned_uv[pin_index(p)].real();
    (*uv)[2 * size_t(p) + 1] = pinned_uv[pin_index(p)].imag();
  }
  return true;
}

}  // namespace pb
