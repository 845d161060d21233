// UV atlases: cut a mesh into charts, flatten each, pack all into one square
// texture, and measure the result.
//
// Output of both unwrappers: the same surface with `uvs` (2 floats per
// vertex, u right, v up, in [0,1]^2). Vertices are split along chart seams:
// a vertex used by k charts becomes k vertices, each a copy of every
// attribute (normals, colors, tangents). Faces keep their order and winding;
// every UV triangle is counter-clockwise (positive signed area) as its face
// is in 3-D seen from the front, so no chart is mirrored. Input uvs are
// replaced. Output vertices are numbered chart by chart.
//
// Methods:
//   UnwrapCharts      grow charts over edge-connected faces whose normals stay
//                     within max_angle_deg of the chart's area-weighted mean
//                     normal (Blender's Smart UV Project criterion, 66 deg by
//                     default) and whose planar projection stretches no face
//                     beyond max_stretch; project each chart on the plane of
//                     its mean normal; split charts whose projection folds or
//                     overlaps itself; rotate each to its minimal-area
//                     bounding rectangle; scale all by one factor and pack
//                     them (skyline, uv_pack.h) with `gutter` texels between
//                     charts and at the border. Faces that drift beyond
//                     max_stretch (x 1.2) of their chart's final mean normal
//                     are peeled off into charts of their own. Slivers too
//                     thin for float UVs (altitude < 0.02 texel at the density
//                     of a half-covered atlas, or no positive float area
//                     after packing, which costs a second round) become
//                     "isolated" one-face charts: a fixed right triangle of
//                     one texel per side (their stretch is not meaningful).
//   UnwrapConformal   charts that follow curved surfaces (surface_charts.h):
//                     grown by normal cone (cone_deg) over smooth surface, cut
//                     at creases, flattened by least-squares conformal maps
//                     (conformal.h), split where a chart's L2 stretch exceeds
//                     max_chart_stretch, folds or overlaps itself; scaled to
//                     one texel density and packed by shape, not by box, with
//                     quarter turns (raster_pack.h). Slivers are isolated as
//                     in UnwrapCharts.
//   UnwrapPerTriangle MeshLab's trivial per-triangle parametrization: face i
//                     is a right isosceles triangle in cell i of a square grid
//                     (row-major from the bottom left), `gutter` texels apart.
//
// Non-manifold input is accepted: charts only grow across edges shared by
// exactly two faces with opposite orientation, so any other edge is a seam.
//
// Texture stretch (Sander, Snyder, Gortler, Hoppe, "Texture mapping
// progressive meshes", SIGGRAPH 2001): for a face with Jacobian columns
// Ss = dq/du, St = dq/dv (3-D meters per UV unit), a = Ss.Ss, b = Ss.St,
// c = St.St, L2 = sqrt((a + c) / 2), Linf = sqrt((a + c + sqrt((a - c)^2 +
// 4 b^2)) / 2). Mesh L2 = sqrt(sum(A3 L2^2) / sum(A3)) (A3: 3-D area), Linf =
// max over faces whose smallest altitude is at least 0.05 texel (thinner
// slivers are invisible in the texture and would dominate the max); both
// multiplied by sqrt(sum(Auv) / sum(A3)) so that 1 means
// no distortion beyond the one global scale (>= 1 always for L2).
#pragma once

#include <cstdint>
#include <functional>

#include "base/status.h"
#include "stages/geometry/core/image.h"
#include "stages/geometry/core/mesh.h"

namespace pb {

enum class UnwrapMethod { kCharts, kConformal, kPerTriangle };

struct UnwrapOptions {
  UnwrapMethod method = UnwrapMethod::kCharts;
  int size_texels = 4096;                // atlas width = height, texels (>= 8)
  int gutter_texels = 4;                 // between charts and at the border (>= 0)
  double max_angle_deg = 66;             // charts: face normal vs chart mean normal, (0, 90)
  double max_stretch = 1.25;             // charts: per-face Linf of the projection (>= 1),
                                         // i.e. normals within acos(1/max_stretch) = 36.9 deg
  double cone_deg = 45;                  // conformal: face normal vs chart mean normal, (0, 90)
  double max_chart_stretch = 1.03;       // conformal: per-chart L2 stretch bound (> 1)
  int threads = 0;                       // 0: TBB's default; results do not depend on it
  std::function<void(double)> progress;  // fraction done, optional
};

// Quality of an atlas (see the header comment for stretch).
struct AtlasReport {
  uint64_t faces = 0;
  uint64_t vertices = 0;       // of the unwrapped mesh (seams split vertices)
  uint64_t charts = 0;         // connected components through shared vertices
  double coverage = 0;         // sum of UV triangle areas / atlas area, [0, 1]
  double stretch_l2 = 0;       // normalized, 1 = no distortion
  double stretch_linf = 0;     // normalized, max over faces
  double seam_length_m = 0;    // 3-D length of edges cut (each edge once)
  uint64_t faces_outside = 0;  // faces with a UV outside [0,1]^2
  uint64_t faces_not_ccw = 0;  // faces with signed UV area <= 0
  // Filled only when MeasureOptions::check_overlaps:
  uint64_t overlapping_faces = 0;        // face pairs whose UV interiors overlap
  uint64_t overlapping_chart_pairs = 0;  // distinct chart pairs among those
  double min_chart_gap_texels = 0;       // closest approach of two charts, capped at gap_probe
  double min_border_gap_texels = 0;      // closest approach of a UV vertex to the border
  // UnwrapCharts only:
  double texels_per_meter = 0;  // the packing scale
  uint64_t isolated_faces = 0;  // slivers laid out as fixed 1-texel triangles
  int rounds = 0;               // chart/pack rounds (slivers found after packing add one)
};

struct MeasureOptions {
  bool check_overlaps = false;  // grid-based face-pair tests (not O(n^2))
  double gap_probe_texels = 8;  // chart gaps wider than this are reported as this
};

// Status::Invalid for an invalid mesh (Validate) or options out of range, or
// when the charts cannot be packed at `size_texels` (too many for the
// gutter). `report` may be null; it is filled by MeasureAtlas (no overlap
// check) plus texels_per_meter.
Expected<Mesh> UnwrapCharts(const Mesh& mesh, const UnwrapOptions& options, AtlasReport* report);
// Same contract as UnwrapCharts.
Expected<Mesh> UnwrapConformal(const Mesh& mesh, const UnwrapOptions& options,
                               AtlasReport* report);
// Status::Invalid when the grid cells would be smaller than gutter + 2
// texels (too many faces for the atlas size).
Expected<Mesh> UnwrapPerTriangle(const Mesh& mesh, const UnwrapOptions& options,
                                 AtlasReport* report);
// Dispatches on options.method.
Expected<Mesh> UnwrapMesh(const Mesh& mesh, const UnwrapOptions& options, AtlasReport* report);

// Measures an unwrapped mesh (uvs required; otherwise an empty report with
// faces_outside = faces) on a size_texels atlas.
AtlasReport MeasureAtlas(const Mesh& mesh, int size_texels, const MeasureOptions& options = {});

// The chart of each face (0-based, numbered by first face), as MeasureAtlas
// counts them: faces sharing a vertex are in one chart.
std::vector<uint32_t> ChartOfFaces(const Mesh& mesh, uint32_t* chart_count);

// A picture of the atlas for a look: each chart a flat color on white,
// `pixels` square (v up); any pixel a face touches is painted, so tiny faces
// stay visible.
Image DrawAtlas(const Mesh& mesh, int pixels);

}  // namespace pb
