// A test fake of the file-system seam: an Env whose Nth durable write fails.
// Test-only (base/testing/): no production code includes it.
#pragma once

#include <string>
#include <string_view>

#include "base/env.h"

namespace pb {

// An Env that fails the Nth durable write (WriteFileAtomic, CopyFileAtomic,
// NewAtomicFile, Rename, SyncFile, counted together from 1) with ENOSPC-like
// errors, leaving a half-written temporary file behind as a real crash would.
// A streamed file (NewAtomicFile) that is the Nth write opens fine and fails
// its first Append after writing half of the bytes (or its Commit, if
// nothing was appended), as a disk that fills up mid-file.
class FaultInjectingEnv : public Env {
 public:
  explicit FaultInjectingEnv(int fail_at_write) : fail_at_(fail_at_write) {}
  Status WriteFileAtomic(const std::string& path, std::string_view contents) override;
  Expected<std::unique_ptr<AtomicFile>> NewAtomicFile(const std::string& path) override;
  Status CopyFileAtomic(const std::string& from, const std::string& to) override;
  Status Rename(const std::string& from, const std::string& to) override;
  Status SyncFile(const std::string& path) override;
  int writes_seen() const { return writes_; }

 private:
  bool ShouldFail(const std::string& path);
  int fail_at_;
  int writes_ = 0;
};

}  // namespace pb
