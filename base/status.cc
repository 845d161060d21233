#include "base/status.h"

#include <cerrno>
#include <cstring>

namespace pb {

Status Status::Errno(const std::string& path, const std::string& operation) {
  const int err = errno;
  return Status(Code::kIo, path + ": " + operation + ": " + std::strerror(err));
}

Status Status::WithContext(const std::string& context) const {
  if (ok()) return *this;
  return Status(code_, context + ": " + message_);
}

}  // namespace pb
