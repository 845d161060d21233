// BufferedInput: sequential reading of a scan file through one fixed buffer,
// shared by the PLY, PCD, XYZ, PTX and LAS readers.
//
// Memory: one buffer of kBufferBytes (1 MiB) whatever the file size, plus a
// line-assembly string only for the rare line that straddles two buffer
// fills; a 1 GB file costs 1 MiB beyond the decoded arrays.
//
// Reads: lines (ReadLine), raw bytes (Read, ReadUpTo, GetByte), skipping and
// seeking (Skip, Seek). offset() is always the exact file offset of the next
// unread byte, so callers can name byte offsets in their error messages.
//
// Lines: a line ends at LF ('\n'). A CR directly before the LF is removed, so
// LF and CRLF files read the same; a lone CR (old Mac OS line ends) does NOT
// end a line and stays inside it (the readers treat it as a blank). The last
// line may lack its LF. A line longer than max_line_bytes (counted without
// the LF, with a CR) stops reading: ReadLine returns false and
// line_too_long() is set.
//
// Errors: Open returns a Status ("<path>: no such file", "<path>: is a
// directory, not <what>", or an errno message). Later calls never fail loudly:
// they return false / a short count at end of file, and a read or seek error
// is kept in error() (an Io Status naming the path). Callers check error()
// first, then line_too_long(), then treat what is left as end of file, and
// word the format-specific message (truncation, line number) themselves.
//
// Progress: every buffer fill (i.e. every 1 MiB read) and every seek calls
// `progress` with the fraction of the file read so far, in [0, 1], reaching
// 1.0 when the last byte has been buffered. Values never decrease for a
// forward-only reader.
//
// Not thread-safe; one instance reads one file once.
#ifndef PB_STAGES_GEOMETRY_BUFFERED_INPUT_H_
#define PB_STAGES_GEOMETRY_BUFFERED_INPUT_H_

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "base/status.h"

namespace pb {

class BufferedInput {
 public:
  static constexpr size_t kBufferBytes = size_t{1} << 20;

  // `max_line_bytes`: the longest line ReadLine accepts.
  explicit BufferedInput(size_t max_line_bytes = kBufferBytes) : max_line_bytes_(max_line_bytes) {}
  ~BufferedInput();
  BufferedInput(const BufferedInput&) = delete;
  BufferedInput& operator=(const BufferedInput&) = delete;

  // Opens `path` for reading. `what` names the expected format for the
  // directory error, e.g. "a PLY file". `progress` may be null or empty; it
  // must outlive this object.
  Status Open(const std::string& path, std::string_view what,
              const std::function<void(double)>* progress);

  const std::string& path() const { return path_; }
  uint64_t size() const { return size_; }  // file size in bytes, at Open
  uint64_t offset() const { return buffer_offset_ + pos_; }  // next byte to read
  uint64_t remaining() const { return size_ - std::min(size_, offset()); }
  size_t max_line_bytes() const { return max_line_bytes_; }
  const Status& error() const { return error_; }
  bool line_too_long() const { return line_too_long_; }
  // Lines returned by ReadLine so far: the 1-based number of the last one.
  int64_t line_number() const { return line_number_; }

  // Reads the next line without its LF / CRLF into `line`, a view valid until
  // the next call on this object. False at end of file, on a read error or
  // when the line is too long (see the file comment).
  bool ReadLine(std::string_view* line);
  // The same, copied into `line`.
  bool ReadLine(std::string* line) {
    std::string_view view;
    const bool ok = ReadLine(&view);
    line->assign(view);
    return ok;
  }

  // Copies exactly `n` bytes; false if fewer remain (those are consumed).
  bool Read(void* destination, size_t n) {
    if (end_ - pos_ >= n) {  // the common case: one memcpy
      std::memcpy(destination, buffer_.get() + pos_, n);
      pos_ += n;
      return true;
    }
    return ReadUpTo(destination, n) == n;
  }
  // Copies up to `n` bytes; returns how many were copied (fewer only at end
  // of file or on a read error).
  size_t ReadUpTo(void* destination, size_t n);

  // The next byte, or -1 at end of file or on a read error.
  int GetByte() {
    if (pos_ == end_ && !Fill()) return -1;
    return static_cast<unsigned char>(buffer_[pos_++]);
  }

  // Skips up to `n` bytes without reading them from disk where possible;
  // returns how many were skipped (fewer only at end of file).
  uint64_t Skip(uint64_t n);
  // Moves to byte `target` (clamped to size()); false on a seek error.
  bool Seek(uint64_t target);

 private:
  bool Fill();  // replaces the buffer with the next bytes; false at EOF/error
  void Report();

  size_t max_line_bytes_;
  std::string path_;
  const std::function<void(double)>* progress_ = nullptr;
  int fd_ = -1;
  uint64_t size_ = 0;
  std::unique_ptr<char[]> buffer_;
  uint64_t buffer_offset_ = 0;  // file offset of buffer_[0]
  size_t pos_ = 0;              // next unread byte in buffer_
  size_t end_ = 0;              // valid bytes in buffer_
  std::string long_line_;       // a line that straddles two fills
  int64_t line_number_ = 0;
  bool line_too_long_ = false;
  Status error_;
};

}  // namespace pb

#endif  // PB_STAGES_GEOMETRY_BUFFERED_INPUT_H_
