#include "base/env.h"

#include <dirent.h>
#include <fcntl.h>
#include <linux/fs.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>

namespace pb {
namespace {

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  int release() {
    int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_;
};

Status WriteAll(int fd, const std::string& path, std::string_view data) {
  size_t done = 0;
  while (done < data.size()) {
    ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status::Errno(path, "write");
    }
    done += static_cast<size_t>(n);
  }
  return Status::Ok();
}

// Directory entries become durable only when the directory is synced.
void SyncDirOf(const std::string& path) {
  Fd dir(::open(DirName(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir.get() >= 0) ::fsync(dir.get());
}

}  // namespace

std::string TempNameFor(const std::string& path) {
  static std::atomic<uint64_t> counter{0};
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

namespace {

// The real AtomicFile: an open temporary beside the target.
class PosixAtomicFile : public AtomicFile {
 public:
  PosixAtomicFile(std::string path, std::string temp, int fd)
      : AtomicFile(std::move(path)), temp_(std::move(temp)), fd_(fd) {}
  ~PosixAtomicFile() override {
    if (!committed_) ::unlink(temp_.c_str());
  }

  Status Append(std::string_view bytes) override {
    if (fd_.get() < 0) return Abandoned();
    return Check(WriteAll(fd_.get(), temp_, bytes));
  }
  Status Sync() override {
    if (fd_.get() < 0) return Abandoned();
    if (synced_) return Status::Ok();
    if (::fsync(fd_.get()) != 0) return Check(Status::Errno(temp_, "fsync"));
    synced_ = true;
    return Status::Ok();
  }
  Status Commit() override {
    PB_RETURN_IF_ERROR(Sync());
    const int fd = fd_.release();
    if (::close(fd) != 0) return Status::Errno(temp_, "close");
    if (::rename(temp_.c_str(), path().c_str()) != 0) return Status::Errno(path(), "rename");
    committed_ = true;
    SyncDirOf(path());
    return Status::Ok();
  }

 private:
  Status Abandoned() const {
    return Status::Internal(path() + ": write after a failed or finished durable write");
  }
  // A failed write abandons the file: nothing after it may publish half.
  Status Check(Status status) {
    if (!status.ok()) ::close(fd_.release());
    synced_ = false;
    return status;
  }

  std::string temp_;
  Fd fd_;
  bool synced_ = false;
  bool committed_ = false;
};

Expected<std::unique_ptr<AtomicFile>> OpenAtomicFile(const std::string& path) {
  std::string temp = TempNameFor(path);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Status::Errno(temp, "open for writing");
  return std::unique_ptr<AtomicFile>(new PosixAtomicFile(path, std::move(temp), fd));
}

}  // namespace

Expected<std::unique_ptr<AtomicFile>> Env::NewAtomicFile(const std::string& path) {
  return OpenAtomicFile(path);
}

// The real file, not NewAtomicFile: a fake Env that overrides both counts
// one durable write once.
Status Env::WriteFileAtomic(const std::string& path, std::string_view contents) {
  PB_ASSIGN_OR_RETURN(std::unique_ptr<AtomicFile> file, OpenAtomicFile(path));
  PB_RETURN_IF_ERROR(file->Append(contents));
  return file->Commit();
}

Status WriteFilesAtomic(Env* env, const std::vector<FileContents>& files) {
  std::vector<std::unique_ptr<AtomicFile>> pending;
  for (const FileContents& contents : files) {
    PB_ASSIGN_OR_RETURN(std::unique_ptr<AtomicFile> file, env->NewAtomicFile(contents.path));
    PB_RETURN_IF_ERROR(file->Append(contents.bytes));
    PB_RETURN_IF_ERROR(file->Sync());
    pending.push_back(std::move(file));
  }
  for (std::unique_ptr<AtomicFile>& file : pending) PB_RETURN_IF_ERROR(file->Commit());
  return Status::Ok();
}

Status Env::CopyFileAtomic(const std::string& from, const std::string& to) {
  Fd in(::open(from.c_str(), O_RDONLY | O_CLOEXEC));
  if (in.get() < 0) return Status::Errno(from, "open");
  struct stat st_in;
  if (::fstat(in.get(), &st_in) != 0) return Status::Errno(from, "stat");
  const std::string tmp = TempNameFor(to);
  Fd out(::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (out.get() < 0) return Status::Errno(tmp, "open for writing");
  Status st;
  if (::ioctl(out.get(), FICLONE, in.get()) != 0) {
    off_t remaining = st_in.st_size;
    while (remaining > 0) {
      ssize_t n = ::copy_file_range(in.get(), nullptr, out.get(), nullptr,
                                    static_cast<size_t>(remaining), 0);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && (errno == EXDEV || errno == ENOSYS || errno == EINVAL)) {
        // Fall back to read/write.
        char buf[1 << 16];
        ssize_t r;
        while ((r = ::read(in.get(), buf, sizeof buf)) > 0) {
          st = WriteAll(out.get(), tmp, std::string_view(buf, static_cast<size_t>(r)));
          if (!st.ok()) break;
        }
        if (r < 0) st = Status::Errno(from, "read");
        break;
      }
      if (n < 0) {
        st = Status::Errno(tmp, "copy_file_range");
        break;
      }
      if (n == 0) {
        st = Status::Io(from + ": file shrank while being copied");
        break;
      }
      remaining -= n;
    }
  }
  if (st.ok() && ::fsync(out.get()) != 0) st = Status::Errno(tmp, "fsync");
  ::close(out.release());
  if (st.ok() && ::rename(tmp.c_str(), to.c_str()) != 0) st = Status::Errno(to, "rename");
  if (!st.ok()) {
    ::unlink(tmp.c_str());
    return st;
  }
  return Status::Ok();
}

Status Env::Rename(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0) return Status::Errno(to, "rename from " + from);
  return Status::Ok();
}

Status Env::SyncFile(const std::string& path) {
  Fd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) return Status::Errno(path, "open");
  if (::fsync(fd.get()) != 0) return Status::Errno(path, "fsync");
  return Status::Ok();
}

Expected<std::string> Env::ReadFile(const std::string& path) const {
  Fd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) return Status::Errno(path, "open");
  std::string out;
  struct stat st;
  if (::fstat(fd.get(), &st) == 0 && st.st_size > 0) out.reserve(static_cast<size_t>(st.st_size));
  char buf[1 << 16];
  for (;;) {
    ssize_t n = ::read(fd.get(), buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Status::Errno(path, "read");
    }
    if (n == 0) break;
    out.append(buf, static_cast<size_t>(n));
  }
  return out;
}

Expected<FileInfo> Env::Stat(const std::string& path) const {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return Status::Errno(path, "stat");
  FileInfo info;
  info.device = st.st_dev;
  info.inode = st.st_ino;
  info.size_bytes = static_cast<uint64_t>(st.st_size);
  info.mtime_ns = static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
  info.ctime_ns = static_cast<int64_t>(st.st_ctim.tv_sec) * 1000000000LL + st.st_ctim.tv_nsec;
  info.is_directory = S_ISDIR(st.st_mode);
  return info;
}

bool Env::Exists(const std::string& path) const { return ::access(path.c_str(), F_OK) == 0; }

Status Env::CreateDirs(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) return Status::Io(path + ": cannot create directory: " + ec.message());
  return Status::Ok();
}

Status Env::RemoveAll(const std::string& path) {
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
  if (ec) return Status::Io(path + ": cannot remove: " + ec.message());
  return Status::Ok();
}

Expected<std::vector<std::string>> Env::ListDir(const std::string& path) const {
  DIR* dir = ::opendir(path.c_str());
  if (!dir) return Status::Errno(path, "opendir");
  std::vector<std::string> names;
  while (struct dirent* e = ::readdir(dir)) {
    std::string name = e->d_name;
    if (name != "." && name != "..") names.push_back(std::move(name));
  }
  ::closedir(dir);
  std::sort(names.begin(), names.end());
  return names;
}

Env* Env::Default() {
  static Env env;
  return &env;
}

std::string JoinPath(std::string_view a, std::string_view b) {
  if (a.empty()) return std::string(b);
  if (!b.empty() && b.front() == '/') return std::string(b);
  std::string out(a);
  if (out.back() != '/') out += '/';
  out += b;
  return out;
}

std::string DirName(std::string_view path) {
  const size_t slash = path.rfind('/');
  if (slash == std::string_view::npos) return ".";
  if (slash == 0) return "/";
  return std::string(path.substr(0, slash));
}

std::string ResolvePath(std::string_view base_dir, std::string_view path) {
  std::filesystem::path p(path);
  if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
  std::error_code ec;
  std::filesystem::path abs = std::filesystem::absolute(p, ec);
  if (ec) abs = p;
  return abs.lexically_normal().string();
}

bool IsValidUtf8(std::string_view text) {
  size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    size_t extra;
    uint32_t cp;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c >> 5) == 0x6) {
      extra = 1, cp = c & 0x1f;
    } else if ((c >> 4) == 0xe) {
      extra = 2, cp = c & 0x0f;
    } else if ((c >> 3) == 0x1e) {
      extra = 3, cp = c & 0x07;
    } else {
      return false;
    }
    if (i + extra >= text.size()) return false;  // truncated sequence
    for (size_t k = 1; k <= extra; ++k) {
      const auto cc = static_cast<unsigned char>(text[i + k]);
      if ((cc >> 6) != 0x2) return false;
      cp = (cp << 6) | (cc & 0x3f);
    }
    // Overlong forms, surrogates, beyond Unicode.
    if ((extra == 1 && cp < 0x80) || (extra == 2 && cp < 0x800) || (extra == 3 && cp < 0x10000) ||
        (cp >= 0xd800 && cp <= 0xdfff) || cp > 0x10ffff)
      return false;
    i += extra + 1;
  }
  return true;
}

Expected<uint64_t> ParseByteSize(std::string_view text) {
  std::string s(text);
  size_t pos = 0;
  double value = 0;
  try {
    value = std::stod(s, &pos);
  } catch (...) {
    return Status::Invalid("'" + s + "' is not a size (expected e.g. 512M, 8G, 1.5GiB)");
  }
  std::string unit = s.substr(pos);
  unit.erase(std::remove(unit.begin(), unit.end(), ' '), unit.end());
  for (auto& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  double mult = 1;
  if (unit.empty() || unit == "B") mult = 1;
  else if (unit == "K" || unit == "KB" || unit == "KIB") mult = 1024.0;
  else if (unit == "M" || unit == "MB" || unit == "MIB") mult = 1024.0 * 1024;
  else if (unit == "G" || unit == "GB" || unit == "GIB") mult = 1024.0 * 1024 * 1024;
  else if (unit == "T" || unit == "TB" || unit == "TIB") mult = 1024.0 * 1024 * 1024 * 1024;
  else return Status::Invalid("'" + s + "': unknown size unit '" + unit + "' (use K, M, G or T)");
  if (!(value >= 0) || !std::isfinite(value)) return Status::Invalid("'" + s + "': size must be >= 0");
  return static_cast<uint64_t>(value * mult);
}

std::string FormatBytes(uint64_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 4) {
    v /= 1024;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.1f %s", v, units[u]);
  return buf;
}

}  // namespace pb
