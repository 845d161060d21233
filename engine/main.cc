// pointbake: the engine's CLI with the built-in stages.
#include "engine/cli.h"
#include "stages/builtin.h"

int main(int argc, char** argv) {
  pb::Registry registry;
  pb::RegisterBuiltinStages(registry);
  return pb::CliMain(argc, argv, registry);
}
