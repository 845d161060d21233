// Status and Expected<T>: how recoverable failures travel in pointbake.
//
// The bottom layer (`pb_base`), shared by the geometry library and the engine;
// it knows neither workflows nor geometry. A failure carries a message a user
// can act on, written as `file:line:column: what was expected` where a place is
// known. Broken internal preconditions are asserts, not Statuses.
#pragma once

#include <cassert>
#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace pb {

class Status {
 public:
  enum class Code { kOk, kInvalid, kNotFound, kIo, kCorrupt, kUnsupported, kInternal };

  Status() = default;
  static Status Ok() { return Status(); }
  static Status Invalid(std::string msg) { return Status(Code::kInvalid, std::move(msg)); }
  static Status NotFound(std::string msg) { return Status(Code::kNotFound, std::move(msg)); }
  static Status Io(std::string msg) { return Status(Code::kIo, std::move(msg)); }
  static Status Corrupt(std::string msg) { return Status(Code::kCorrupt, std::move(msg)); }
  static Status Unsupported(std::string msg) { return Status(Code::kUnsupported, std::move(msg)); }
  static Status Internal(std::string msg) { return Status(Code::kInternal, std::move(msg)); }
  // Io error from errno, e.g. Errno("cache/objects/ab/cd", "rename") ->
  // "cache/objects/ab/cd: rename: No space left on device".
  static Status Errno(const std::string& path, const std::string& operation);

  bool ok() const { return code_ == Code::kOk; }
  Code code() const { return code_; }
  const std::string& message() const { return message_; }
  // Prefixes the message with context: "reading scan.ply: " + message.
  Status WithContext(const std::string& context) const;

 private:
  Status(Code code, std::string msg) : code_(code), message_(std::move(msg)) {}
  Code code_ = Code::kOk;
  std::string message_;
};

// A value or the Status explaining why there is none.
template <typename T>
class Expected {
 public:
  Expected(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design
  Expected(Status status) : status_(std::move(status)) {  // NOLINT
    assert(!status_.ok() && "an Expected built from a Status must hold an error");
  }

  bool ok() const { return value_.has_value(); }
  const Status& status() const { return status_; }
  T& value() & {
    assert(ok());
    return *value_;
  }
  const T& value() const& {
    assert(ok());
    return *value_;
  }
  T&& value() && {
    assert(ok());
    return std::move(*value_);
  }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::optional<T> value_;
  Status status_;
};

}  // namespace pb

// Returns early from the enclosing function if `expr` (a Status) failed.
#define PB_RETURN_IF_ERROR(expr)          \
  do {                                    \
    ::pb::Status pb_status_ = (expr);     \
    if (!pb_status_.ok()) return pb_status_; \
  } while (0)

#define PB_CONCAT_INNER(a, b) a##b
#define PB_CONCAT(a, b) PB_CONCAT_INNER(a, b)
// PB_ASSIGN_OR_RETURN(auto x, ComputeX()); declares x or returns the error.
#define PB_ASSIGN_OR_RETURN(decl, expr)                                  \
  auto PB_CONCAT(pb_expected_, __LINE__) = (expr);                       \
  if (!PB_CONCAT(pb_expected_, __LINE__).ok())                           \
    return PB_CONCAT(pb_expected_, __LINE__).status();                   \
  decl = std::move(PB_CONCAT(pb_expected_, __LINE__)).value()
