// The content-addressed cache.
//
// On-disk layout (format "pointbake-cache 1", in the FORMAT file):
//   FORMAT                      signature and version; other versions refuse to open
//   CACHEDIR.TAG                tells backup tools to skip the folder
//   objects/ab/<digest>         immutable files, named by XXH3-128 of their bytes
//   entries/ab/<key>.json       one completed stage result: key components, output
//                               artifacts (file name -> object digest), run figures.
//                               Written last, by rename: it is the completion marker.
//   history/<workflow>/<stage>.json  last key components and peak RSS of a
//                               (workflow name, stage id), for `explain` and --mem
//   filehash/<id>               digest of an input file, keyed by (device, inode,
//                               size, mtime, ctime) so a 1 GB scan is hashed once;
//                               files changed in the last 2 s are not memoized
//   locks/                      flock() files; the kernel drops a lock when its
//                               owner dies, so a killed run never blocks the next
//                               (on a cluster's shared file system: docs/cluster.md);
//                               gc removes key locks (it runs alone) and memos
//                               in filehash/ unused for 30 days
//   tmp/                        staging folders and temporary names; a name
//                               carries its writer's pid, and gc removes those
//                               whose process is gone
//
// Crash safety: objects are written to tmp/, fsynced and renamed into
// objects/; the entry is renamed into entries/ only after all its objects are
// in place. A lookup treats an entry as a hit only if it parses and every
// object it names exists with the recorded size. Runs hold a shared cache
// lock; `gc` holds it exclusively.
//
// Relocatable: nothing in the cache records an absolute path.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/artifact.h"
#include "base/env.h"
#include "base/hash.h"

namespace pb {

inline constexpr int kCacheFormatVersion = 1;

// A cache key: XXH3-128 of the compact JSON of its components (see key.h).
Digest KeyOf(const nlohmann::json& components);

// An flock() held on a file until destruction; `release` (if any) runs
// after the file is closed.
class FileLock {
 public:
  FileLock() = default;
  explicit FileLock(int fd, std::function<void()> release = {}) : fd_(fd), release_(std::move(release)) {}
  FileLock(FileLock&& o) noexcept : fd_(o.fd_), release_(std::move(o.release_)) {
    o.fd_ = -1;
    o.release_ = nullptr;
  }
  FileLock& operator=(FileLock&& o) noexcept;
  ~FileLock();
  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
  std::function<void()> release_;
};

struct CacheEntry {
  Digest key;
  nlohmann::json components;  // what the key was computed from
  std::map<std::string, Artifact> outputs;  // by output port
  nlohmann::json record;      // figures of the run that produced it
};

struct VerifyReport {
  int entries_checked = 0;
  int objects_checked = 0;
  std::vector<std::string> problems;  // one line each
  int removed = 0;                    // with repair
};

struct GcReport {
  uint64_t bytes_before = 0;
  uint64_t bytes_after = 0;
  int entries_removed = 0;
  int objects_removed = 0;
  int temp_removed = 0;
};

class Cache {
 public:
  // Opens (creating if needed) the cache at `dir`.
  static Expected<std::unique_ptr<Cache>> Open(const std::string& dir, Env* env = Env::Default());

  const std::string& dir() const { return dir_; }
  std::string ObjectPath(const Digest& digest) const;

  // Blocking locks. Shared: a run. Exclusive: gc. Key: computing one entry.
  Expected<FileLock> LockShared();
  Expected<FileLock> LockExclusive();
  // Returns an unheld lock (and sets *would_block) if another process holds it
  // and `wait` is false.
  Expected<FileLock> LockKey(const Digest& key, bool wait, bool* would_block = nullptr);

  // Digest of an input file, computed once per (device, inode, size, mtime).
  Expected<Digest> FileDigest(const std::string& path);

  // The entry for `key` if it is complete; nullopt on a miss. A damaged entry
  // is a miss (and is reported by `verify`).
  std::optional<CacheEntry> Lookup(const Digest& key);

  // A fresh, empty staging folder for a stage computing `key`.
  Expected<std::string> NewStagingDir(const Digest& key);

  // Moves the files a stage wrote into objects and writes the entry last.
  // `outputs`: port -> {type, files: name -> path inside the staging folder,
  // meta}. Removes the staging folder.
  struct StagedOutput {
    std::string type;
    std::map<std::string, std::string> files;
    nlohmann::json meta = nlohmann::json::object();
  };
  Expected<CacheEntry> Commit(const Digest& key, const nlohmann::json& components,
                              const std::map<std::string, StagedOutput>& outputs,
                              const nlohmann::json& record, const std::string& staging_dir);

  // Explain/--mem memory: the last key components and figures per stage.
  Status SaveHistory(const std::string& workflow, const std::string& stage,
                     const nlohmann::json& history);
  // nullopt unless it is an object with "components" (object) and
  // "peak_rss_bytes" (unsigned).
  std::optional<nlohmann::json> LoadHistory(const std::string& workflow, const std::string& stage);

  // Every complete entry, with its size on disk and last use.
  struct EntryInfo {
    Digest key;
    std::string stage_type;
    uint64_t bytes = 0;
    int64_t last_used_ns = 0;
  };
  Expected<std::vector<EntryInfo>> ListEntries();
  Expected<VerifyReport> Verify(bool repair);
  Expected<GcReport> Gc(uint64_t max_bytes);

 private:
  Cache(std::string dir, Env* env) : dir_(std::move(dir)), env_(env) {}
  std::string EntryPath(const Digest& key) const;
  Expected<CacheEntry> ReadEntry(const std::string& path);
  Expected<FileLock> Lock(const std::string& path, bool exclusive, bool wait, bool* would_block,
                          std::function<void()> release = {});
  Status StoreObject(const std::string& staged_path, const Digest& digest);

  std::string dir_;
  Env* env_;
  // Key locks held by this process. flock() already excludes threads (each
  // open is its own lock), but NFS emulates flock with POSIX locks, which a
  // process shares among its threads: a campaign's parallel runs would then
  // compute a shared stage twice.
  std::mutex held_mu_;
  std::condition_variable held_cv_;
  std::set<std::string> held_keys_;
};

}  // namespace pb
