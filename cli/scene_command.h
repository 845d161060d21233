// `pointbake scene SCAN [-o FILE] [--units U] [--up X,Y,Z] [--name N]`: a
// scene file for a user's own scan, with the viewpoints and the workflow
// parameters the shipped workflows need, read off the points
// (stages/geometry/points/scene_survey.h), so that
//   pointbake scene statue.e57 -o configs/scenes/statue.yaml
//   pointbake run configs/workflows/point_transfer.yaml --scene configs/scenes/statue.yaml
// works on a scan nobody wrote a scene for. Every value carries a comment
// saying where it came from; the user edits what they know better.
#pragma once

#include "cli/cli.h"

namespace pb {

// Reads the scan (any io.read_points format), surveys it and writes the
// scene YAML to -o FILE (the scan's path relative to FILE's folder; an
// existing FILE is kept unless --force) or to stdout (the scan's absolute
// path). Exit 0 on success, 2 on bad input or usage.
CliCommand SceneCommand();

}  // namespace pb
