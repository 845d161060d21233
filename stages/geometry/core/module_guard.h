// For the code inside a module (pointbake-poisson-open3d.so,
// pointbake-pcl.so): a module's exported call returns false with its error
// text instead of letting a library's exception cross the dlopen boundary.
#pragma once

#include <exception>

namespace pb {

// Runs `body`; an exception becomes the call's `*error` and false.
template <typename Call, typename Body>
bool GuardModuleCall(Call* call, Body body) {
  try {
    body();
    return true;
  } catch (const std::exception& e) {
    *call->error = e.what();
  } catch (...) {
    *call->error = "unknown exception";
  }
  return false;
}

}  // namespace pb
