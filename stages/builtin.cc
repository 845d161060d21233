#include "stages/builtin.h"

#include <cassert>

namespace pb {

namespace {

// Every built-in stage type, in the order `pointbake stages` lists them.
constexpr StageType (*kBuiltinStages[])() = {
    ReadPointsStage,   SynthScanStage,    DownsampleStage,       StatsStage,
    OutliersStage,     NormalsStage,      SpacingStage,          SmoothStage,
    PoissonStage,
    TrimStage,
    DecimateStage,     CleanStage,        FitStage,        UnwrapStage,           VertexColorsBakeStage,
    FromMeshBakeStage, FromPointsBakeStage, GltfExportStage,     ObjExportStage,
    VtpExportStage,
    FramesStage,       SplatsStage,       GeometryMetricsStage, ImageMetricsStage,
    FpsStage,
};

}  // namespace

void RegisterBuiltinStages(StageRegistry& registry) {
  for (StageType (*make)() : kBuiltinStages) {
    // The registry records failures itself (and the CLI reports them); a
    // built-in stage that fails to register is a bug caught by tests.
    [[maybe_unused]] const Status status = registry.Register(make());
    assert(status.ok());
  }
}

}  // namespace pb
