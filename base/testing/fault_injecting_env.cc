#include "base/testing/fault_injecting_env.h"

#include <fcntl.h>
#include <unistd.h>

namespace pb {

bool FaultInjectingEnv::ShouldFail(const std::string& path) {
  ++writes_;
  if (writes_ != fail_at_) return false;
  // Leave a torn temporary file behind, as a crash in the middle would.
  const std::string tmp = TempNameFor(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd >= 0) {
    (void)!::write(fd, "torn", 4);
    ::close(fd);
  }
  return true;
}

Status FaultInjectingEnv::WriteFileAtomic(const std::string& path, std::string_view contents) {
  if (ShouldFail(path)) return Status::Io(path + ": write: No space left on device (injected)");
  return Env::WriteFileAtomic(path, contents);
}

Status FaultInjectingEnv::CopyFileAtomic(const std::string& from, const std::string& to) {
  if (ShouldFail(to)) return Status::Io(to + ": write: No space left on device (injected)");
  return Env::CopyFileAtomic(from, to);
}

Status FaultInjectingEnv::Rename(const std::string& from, const std::string& to) {
  if (ShouldFail(to)) return Status::Io(to + ": rename: Input/output error (injected)");
  return Env::Rename(from, to);
}

Status FaultInjectingEnv::SyncFile(const std::string& path) {
  if (ShouldFail(path)) return Status::Io(path + ": fsync: Input/output error (injected)");
  return Env::SyncFile(path);
}

}  // namespace pb
