// Env: the seam between pointbake and the file system.
//
// Everything that writes durable state (the cache, output folders, run
// records) goes through an Env, so tests can inject a failure at a chosen write
// (see base/testing/fault_injecting_env.h) and check that nothing that looks complete is left
// behind. Durable writes are always "write a temporary name, fsync, rename".
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "base/status.h"

namespace pb {

struct FileInfo {
  uint64_t device = 0;
  uint64_t inode = 0;
  uint64_t size_bytes = 0;
  int64_t mtime_ns = 0;
  int64_t ctime_ns = 0;  // inode change time: users cannot set it back
  bool is_directory = false;
};

// A file written by streaming and published atomically, for files too big to
// build in memory first (a 10^7-point PLY). Bytes go to a temporary name
// beside path() (TempNameFor); Commit() fsyncs it, renames it over path() and
// syncs the folder. Destroyed without a successful Commit (an error on the
// way, an early return), it removes the temporary and path() stays as it
// was. Errors name the file and the call that failed.
class AtomicFile {
 public:
  virtual ~AtomicFile() = default;
  virtual Status Append(std::string_view bytes) = 0;
  // Flushes the bytes written so far to the disk (fsync of the temporary).
  // Commit does it too; a set of files that must appear together (OBJ + MTL +
  // textures) syncs them all before renaming any.
  virtual Status Sync() = 0;
  // Sync, rename over path(), sync the folder. Once only; after a failure the
  // file is abandoned (the temporary is removed on destruction).
  virtual Status Commit() = 0;
  const std::string& path() const { return path_; }

 protected:
  explicit AtomicFile(std::string path) : path_(std::move(path)) {}

 private:
  std::string path_;
};

class Env {
 public:
  virtual ~Env() = default;

  // Writes `contents` to `path` atomically: a sibling temporary file is
  // written, fsynced and renamed over `path`. On failure `path` is untouched.
  virtual Status WriteFileAtomic(const std::string& path, std::string_view contents);
  // Opens the temporary of a streamed durable write (see AtomicFile).
  virtual Expected<std::unique_ptr<AtomicFile>> NewAtomicFile(const std::string& path);
  // Copies `from` to `to` atomically (temporary name + rename); tries a
  // reflink, then copy_file_range.
  virtual Status CopyFileAtomic(const std::string& from, const std::string& to);
  virtual Status Rename(const std::string& from, const std::string& to);
  virtual Status SyncFile(const std::string& path);

  Expected<std::string> ReadFile(const std::string& path) const;
  Expected<FileInfo> Stat(const std::string& path) const;
  bool Exists(const std::string& path) const;
  // mkdir -p.
  Status CreateDirs(const std::string& path);
  // Removes a file, or a directory tree; missing paths are not an error.
  Status RemoveAll(const std::string& path);
  // Names (not paths) of the entries of a directory, sorted.
  Expected<std::vector<std::string>> ListDir(const std::string& path) const;

  // The process-wide real file system.
  static Env* Default();
};

// Writes several files as one durable set: every file is written to its
// temporary and synced before any is renamed, then they are renamed in the
// order given (put the file readers open first, an index or the .obj, last).
// A failed write (full disk, I/O error) leaves every earlier file as it was;
// only a failed rename leaves the files before it published.
struct FileContents {
  std::string path;
  std::string_view bytes;
};
Status WriteFilesAtomic(Env* env, const std::vector<FileContents>& files);

// A temporary name beside `path`, unique per process and call:
// "<path>.tmp.<pid>.<counter>". Cache garbage collection recognizes the
// pattern and removes those whose process is gone.
std::string TempNameFor(const std::string& path);

// Joins path components with '/'.
std::string JoinPath(std::string_view a, std::string_view b);
// Directory part of a path ("a/b/c.yaml" -> "a/b", "c.yaml" -> ".").
std::string DirName(std::string_view path);
// Absolute, lexically normalized form of `path` relative to `base_dir`.
std::string ResolvePath(std::string_view base_dir, std::string_view path);

// True if `text` is well-formed UTF-8 (JSON records and job files need it).
bool IsValidUtf8(std::string_view text);

// Parses "512M", "2G", "1.5GiB", "300000" into bytes.
Expected<uint64_t> ParseByteSize(std::string_view text);
// Formats bytes as "1.5 GiB".
std::string FormatBytes(uint64_t bytes);

}  // namespace pb
