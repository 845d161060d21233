// Optional modules: shared objects built from this tree when a heavy library
// is installed (Open3D, PCL), loaded with dlopen() the first time a caller
// needs one, so that the pointbake binary and every stage process that does
// not use them start without loading their ~100 shared libraries.
//
// A module is found, in order, at $<env_var> (a full path), beside the
// running executable, then in the build directory this library was compiled
// for (test executables live in subfolders of it). Module and caller are
// built from the same tree by the same compiler, so C++ types cross the call;
// each entry point carries an ABI number in its symbol name that changes
// whenever its call struct or the meaning of a field does.
#pragma once

#include <string>
#include <vector>

#include "base/status.h"

namespace pb {

struct ModuleSpec {
  const char* file = "";     // e.g. "pointbake-pcl.so"
  const char* env_var = "";  // overrides the search, e.g. "PB_PCL_MODULE"
  // What to do when it is missing, e.g. "install libpcl-dev and rebuild".
  const char* install_hint = "";
};

// The modules this tree builds.
// Open3D 0.16: screened Poisson, normals (stages/geometry/mesh/poisson_open3d.cc).
inline constexpr ModuleSpec kOpen3dModule{
    "pointbake-poisson-open3d.so", "PB_POISSON_MODULE",
    "install libopen3d-dev (Open3D 0.16) and rebuild"};
// PCL 1.13: MLS smoothing, outliers, normals, Poisson (stages/geometry/mesh/pcl_module.cc).
inline constexpr ModuleSpec kPclModule{"pointbake-pcl.so", "PB_PCL_MODULE",
                                       "install libpcl-dev and rebuild"};

// The paths tried for `spec`, in order.
std::vector<std::string> ModuleCandidates(const ModuleSpec& spec);

// The address of `symbol` in the module, loading the module on first use
// (once per process; later calls reuse the handle, thread-safe).
// Status::Unsupported when no candidate loads or defines the symbol; the
// message starts with `user` ("implementation 'pcl' of points.normals"),
// says "<user> needs <file>, which this build lacks: <install_hint>" and
// lists where it looked and why each candidate failed.
Expected<void*> ModuleSymbol(const ModuleSpec& spec, const char* symbol, const std::string& user);

}  // namespace pb
