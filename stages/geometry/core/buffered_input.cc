#include "stages/geometry/core/buffered_input.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

namespace pb {

BufferedInput::~BufferedInput() {
  if (fd_ >= 0) ::close(fd_);
}

Status BufferedInput::Open(const std::string& path, std::string_view what,
                           const std::function<void(double)>* progress) {
  path_ = path;
  progress_ = progress;
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) {
    if (errno == ENOENT) return Status::NotFound(path + ": no such file");
    return Status::Errno(path, "open");
  }
  struct stat st;
  if (::fstat(fd_, &st) != 0) return Status::Errno(path, "stat");
  if (S_ISDIR(st.st_mode)) {
    return Status::Invalid(path + ": is a directory, not " + std::string(what));
  }
  size_ = static_cast<uint64_t>(st.st_size);
  buffer_.reset(new char[kBufferBytes]);
  return Status::Ok();
}

bool BufferedInput::ReadLine(std::string_view* line) {
  if (pos_ == end_ && !Fill()) return false;
  // The common case: the whole line is in the buffer; return a view of it.
  const char* start = buffer_.get() + pos_;
  const void* newline = std::memchr(start, '\n', end_ - pos_);
  size_t length;
  if (newline != nullptr) {
    length = static_cast<const char*>(newline) - start;
    pos_ += length + 1;
    *line = std::string_view(start, length);
  } else {
    // The line continues past the buffer: assemble it across fills.
    long_line_.assign(start, end_ - pos_);
    pos_ = end_;
    while (long_line_.size() <= max_line_bytes_ && Fill()) {
      const char* chunk = buffer_.get();
      newline = std::memchr(chunk, '\n', end_);
      const size_t take = newline ? static_cast<const char*>(newline) - chunk : end_;
      long_line_.append(chunk, take);
      pos_ = newline ? take + 1 : take;
      if (newline) break;
    }
    if (!error_.ok()) return false;
    length = long_line_.size();
    *line = long_line_;
  }
  if (length > max_line_bytes_) {
    line_too_long_ = true;
    return false;
  }
  if (!line->empty() && line->back() == '\r') line->remove_suffix(1);
  ++line_number_;
  return true;
}

size_t BufferedInput::ReadUpTo(void* destination, size_t n) {
  char* out = static_cast<char*>(destination);
  size_t done = 0;
  while (done < n) {
    if (pos_ == end_ && !Fill()) break;
    const size_t take = std::min(n - done, end_ - pos_);
    std::memcpy(out + done, buffer_.get() + pos_, take);
    pos_ += take;
    done += take;
  }
  return done;
}

uint64_t BufferedInput::Skip(uint64_t n) {
  const uint64_t start = offset();
  const uint64_t target = std::min(size_, start + std::min(n, size_));
  if (target < start) return 0;  // already past the end (the file shrank)
  Seek(target);
  return offset() - start;
}

bool BufferedInput::Seek(uint64_t target) {
  target = std::min(target, size_);
  if (target >= buffer_offset_ && target <= buffer_offset_ + end_) {
    pos_ = static_cast<size_t>(target - buffer_offset_);  // inside the buffer: no system call
    return true;
  }
  buffer_offset_ = target;
  pos_ = end_ = 0;
  if (::lseek(fd_, static_cast<off_t>(target), SEEK_SET) < 0) {
    error_ = Status::Errno(path_, "seek");
    return false;
  }
  Report();
  return true;
}

bool BufferedInput::Fill() {
  if (!error_.ok()) return false;
  buffer_offset_ += end_;
  pos_ = end_ = 0;
  while (true) {
    const ssize_t n = ::read(fd_, buffer_.get(), kBufferBytes);
    if (n < 0) {
      if (errno == EINTR) continue;
      error_ = Status::Errno(path_, "read");
      return false;
    }
    end_ = static_cast<size_t>(n);
    break;
  }
  Report();
  return end_ > 0;
}

void BufferedInput::Report() {
  if (progress_ != nullptr && *progress_ && size_ > 0) {
    (*progress_)(std::min(1.0, static_cast<double>(buffer_offset_ + end_) / size_));
  }
}

}  // namespace pb
