#include "base/testing/fault_injecting_env.h"

#include <fcntl.h>
#include <unistd.h>

namespace pb {
namespace {

Status Injected(const std::string& path) {
  return Status::Io(path + ": write: No space left on device (injected)");
}

// Passes everything to the real file until the disk "fills up".
class FailingAtomicFile : public AtomicFile {
 public:
  explicit FailingAtomicFile(std::unique_ptr<AtomicFile> real)
      : AtomicFile(real->path()), real_(std::move(real)) {}
  Status Append(std::string_view bytes) override {
    if (!failed_) {
      failed_ = true;
      (void)real_->Append(bytes.substr(0, bytes.size() / 2));
    }
    return Injected(path());
  }
  Status Sync() override { return Injected(path()); }
  Status Commit() override { return Injected(path()); }

 private:
  std::unique_ptr<AtomicFile> real_;
  bool failed_ = false;
};

}  // namespace

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
  if (ShouldFail(path)) return Injected(path);
  return Env::WriteFileAtomic(path, contents);
}

Expected<std::unique_ptr<AtomicFile>> FaultInjectingEnv::NewAtomicFile(const std::string& path) {
  const bool fail = ShouldFail(path);
  PB_ASSIGN_OR_RETURN(std::unique_ptr<AtomicFile> file, Env::NewAtomicFile(path));
  if (!fail) return file;
  return std::unique_ptr<AtomicFile>(new FailingAtomicFile(std::move(file)));
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
