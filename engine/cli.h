// The `pointbake` command line. The engine's CLI knows no stage: main() fills
// the registry with the built-in stages and hands it over.
#pragma once

#include "engine/registry.h"

namespace pb {

// Exit status: 0 success, 1 a stage failed, 2 bad input or usage.
int CliMain(int argc, char** argv, Registry& registry);

}  // namespace pb
