#include "stages/geometry/core/module.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <utility>

#ifndef PB_MODULE_DIR
#define PB_MODULE_DIR ""
#endif

namespace pb {
namespace {

std::string ExecutableDir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : exe.parent_path().string();
}

struct Loaded {
  void* handle = nullptr;
  std::string tried;  // why each candidate failed, one line each
};

}  // namespace

std::vector<std::string> ModuleCandidates(const ModuleSpec& spec) {
  std::vector<std::string> paths;
  if (const char* env = std::getenv(spec.env_var); env && *env) paths.push_back(env);
  if (const std::string dir = ExecutableDir(); !dir.empty()) {
    paths.push_back(dir + "/" + spec.file);
  }
  if (std::string(PB_MODULE_DIR).size() > 0) {
    const std::string built = std::string(PB_MODULE_DIR) + "/" + spec.file;
    if (std::find(paths.begin(), paths.end(), built) == paths.end()) paths.push_back(built);
  }
  return paths;
}

Expected<void*> ModuleSymbol(const ModuleSpec& spec, const char* symbol, const std::string& user) {
  // One load per module file per process: the handles stay open for the
  // process's life (RTLD_NODELETE), so their symbols stay valid.
  static std::mutex mutex;
  static std::map<std::string, Loaded> loaded;
  std::lock_guard<std::mutex> lock(mutex);
  auto [it, inserted] = loaded.try_emplace(spec.file);
  Loaded& module = it->second;
  if (inserted) {
    for (const std::string& path : ModuleCandidates(spec)) {
      if (!std::filesystem::exists(path)) {
        module.tried += "\n  " + path + ": not there";
        continue;
      }
      void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
      if (!handle) {
        module.tried += "\n  " + path + ": " + ::dlerror();
        continue;
      }
      module.handle = handle;
      break;
    }
  }
  if (module.handle) {
    if (void* address = ::dlsym(module.handle, symbol)) return address;
    return Status::Unsupported(user + " needs " + spec.file + " with " + symbol +
                               ", and the one loaded lacks it (built from another version?): " +
                               spec.install_hint);
  }
  return Status::Unsupported(user + " needs " + spec.file + ", which this build lacks: " +
                             spec.install_hint + "; looked in:" + module.tried);
}

}  // namespace pb
