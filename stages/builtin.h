// The stage types built into the pointbake executable: one factory per stage
// type, defined in stages/<family>/<name>_stage.cc, and the one table that
// registers them all (builtin.cc).
#pragma once

#include "engine/stage.h"

namespace pb {

// Registers every built-in stage type.
void RegisterBuiltinStages(StageRegistry& registry);

// io.read_points: a scan file (PLY, PCD, XYZ, PTX, E57, LAS) -> `points`.
StageType ReadPointsStage();

// synth.scan: synthetic scanned scenes with ground truth.
StageType SynthScanStage();

// points.downsample: voxel-grid averaging.
StageType DownsampleStage();
// points.stats: counts, bounds, centroid and mean color as a table.
StageType StatsStage();
// points.outliers: statistical outlier removal.
StageType OutliersStage();
// points.normals: k-NN PCA normals, oriented.
StageType NormalsStage();
// points.spacing: median nearest-neighbour distance into the meta.
StageType SpacingStage();
// points.smooth: moving-least-squares smoothing (PCL, through a module).
StageType SmoothStage();

// mesh.poisson: screened Poisson surface reconstruction with trimming.
StageType PoissonStage();
// mesh.trim: removes the surface the points do not support.
StageType TrimStage();
// mesh.decimate: quadric edge-collapse decimation to a face budget.
StageType DecimateStage();
// mesh.clean: removes degenerate and duplicate faces, small components.
StageType CleanStage();
// mesh.fit: moves a mesh's vertices along their normals onto the scan.
StageType FitStage();

// uv.unwrap: charts or per-triangle UV atlas (stages/geometry/uv/atlas.h).
StageType UnwrapStage();

// bake.vertex_colors, bake.from_mesh, bake.from_points: color and normal maps.
StageType VertexColorsBakeStage();
StageType FromMeshBakeStage();
StageType FromPointsBakeStage();

// export.gltf (model.glb) and export.obj (model.obj + .mtl + maps).
StageType GltfExportStage();
StageType ObjExportStage();
// export.vtp (model.vtp + maps, VTK XML PolyData for ParaView).
StageType VtpExportStage();

// render.frames: the deterministic CPU reference renderer (docs/render.md).
StageType FramesStage();
// render.splats: the colored scan drawn as splats (what the scanner saw).
StageType SplatsStage();

// metrics.geometry: distances between a mesh and the truth; metrics.image:
// PSNR, SSIM, MS-SSIM, FLIP between two sets of frames.
StageType GeometryMetricsStage();
StageType ImageMetricsStage();

// estimate.fps: the frame rate a device profile predicts.
StageType FpsStage();

}  // namespace pb
