// Test helpers shared by the engine's unit tests: the temporary folder of
// base/testing/temp_dir.h and a registry of tiny in-process stage types.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "base/testing/temp_dir.h"
#include "engine/registry.h"

namespace pb::testing {


// "t.text" writes params.text; "t.upper" upper-cases input `in`;
// "t.len" writes the length of input `in`; "t.pair" joins `a` and `b`;
// "t.file" reads params.path (x-path) and writes its content.
void RegisterTestStages(Registry& registry);

}  // namespace pb::testing
