// A test of a writer's durability promise, shared by every writer's tests.
// Test-only (base/testing/).
#pragma once

#include <functional>
#include <string>

#include "base/env.h"
#include "base/status.h"

namespace pb::testing {

// `write(env)` writes its files into folder `dir`, which already holds an
// earlier, complete result of the same writer (with different content).
// Fails each durable write of `write` in turn (FaultInjectingEnv(1),
// FaultInjectingEnv(2), ...) and checks (gtest EXPECTs) that each failed
// attempt returns an error, leaves every earlier file with its bytes, and
// adds no file under a name other than a temporary ("<name>.tmp.<pid>.<n>",
// which the cache's garbage collection removes). Then checks that an attempt
// without a failure succeeds and changes at least one file. Returns the
// number of durable writes that attempt took (0 means the writer bypassed
// the Env, which fails the check too).
int ExpectFailedWritesKeepEarlierFiles(const std::string& dir,
                                       const std::function<Status(Env*)>& write);

}  // namespace pb::testing
