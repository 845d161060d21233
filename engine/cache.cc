#include "engine/cache.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <climits>
#include <chrono>
#include <set>

namespace pb {
namespace {

constexpr const char* kFormatLine = "pointbake-cache 1\n";
constexpr const char* kEntryFormat = "pointbake-entry 1";

std::string Shard(const std::string& hex) { return hex.substr(0, 2); }

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// "name.tmp.<pid>.<n>" or "<key>.<pid>.<n>" staging names: the writer's pid.
std::optional<pid_t> PidOfTempName(const std::string& name) {
  // Both forms end with ".<pid>.<counter>".
  const size_t last = name.rfind('.');
  if (last == std::string::npos || last == 0) return std::nullopt;
  const size_t prev = name.rfind('.', last - 1);
  if (prev == std::string::npos) return std::nullopt;
  const std::string_view digits = std::string_view(name).substr(prev + 1, last - prev - 1);
  long pid = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), pid);
  if (ec != std::errc() || end != digits.data() + digits.size() || pid <= 0 || pid > INT_MAX)
    return std::nullopt;
  return static_cast<pid_t>(pid);
}

bool ProcessAlive(pid_t pid) { return ::kill(pid, 0) == 0 || errno == EPERM; }

// A file name safe for any workflow or stage name.
std::string SafeName(const std::string& name) {
  std::string out;
  for (char c : name) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
  return out + "-" + HashBytes(name).Hex().substr(0, 8);
}

}  // namespace

// Strings in components are UTF-8 (checked at load), so `replace` never
// changes them; it only keeps a stray byte from throwing.
Digest KeyOf(const nlohmann::json& components) {
  return HashBytes(components.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

FileLock& FileLock::operator=(FileLock&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    if (release_) release_();
    fd_ = o.fd_;
    release_ = std::move(o.release_);
    o.fd_ = -1;
    o.release_ = nullptr;
  }
  return *this;
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // closing drops the flock
  if (release_) release_();
}

Expected<std::unique_ptr<Cache>> Cache::Open(const std::string& dir, Env* env) {
  const std::string abs = ResolvePath(".", dir);
  for (const char* sub : {"objects", "entries", "history", "filehash", "locks", "tmp"})
    PB_RETURN_IF_ERROR(env->CreateDirs(JoinPath(abs, sub)));
  const std::string format_path = JoinPath(abs, "FORMAT");
  if (env->Exists(format_path)) {
    PB_ASSIGN_OR_RETURN(std::string format, env->ReadFile(format_path));
    if (format != kFormatLine)
      return Status::Unsupported(format_path + ": cache format '" +
                                 format.substr(0, format.find('\n')) + "', this pointbake uses '" +
                                 std::string(kFormatLine).substr(0, 17) +
                                 "'; use another --cache folder");
  } else {
    PB_RETURN_IF_ERROR(env->WriteFileAtomic(format_path, kFormatLine));
    PB_RETURN_IF_ERROR(env->WriteFileAtomic(
        JoinPath(abs, "CACHEDIR.TAG"),
        "Signature: 8a477f597d28d172789f06886806bc55\n# pointbake cache: results can be recomputed.\n"));
  }
  return std::unique_ptr<Cache>(new Cache(abs, env));
}

std::string Cache::ObjectPath(const Digest& digest) const {
  const std::string hex = digest.Hex();
  return dir_ + "/objects/" + Shard(hex) + "/" + hex;
}

std::string Cache::EntryPath(const Digest& key) const {
  const std::string hex = key.Hex();
  return dir_ + "/entries/" + Shard(hex) + "/" + hex + ".json";
}

Expected<FileLock> Cache::Lock(const std::string& path, bool exclusive, bool wait,
                               bool* would_block, std::function<void()> release) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (release) release();
    return Status::Errno(path, "open lock");
  }
  FileLock lock(fd, std::move(release));
  int op = (exclusive ? LOCK_EX : LOCK_SH) | (wait ? 0 : LOCK_NB);
  for (;;) {
    if (::flock(fd, op) == 0) break;
    if (errno == EINTR) continue;
    if (errno == EWOULDBLOCK && !wait) {
      if (would_block) *would_block = true;
      return FileLock();
    }
    return Status::Errno(path, "flock");
  }
  if (would_block) *would_block = false;
  if (exclusive) {
    // For people inspecting a stuck cache: who holds it.
    const std::string owner = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd, 0) == 0) (void)!::pwrite(fd, owner.data(), owner.size(), 0);
  }
  return lock;
}

Expected<FileLock> Cache::LockShared() { return Lock(dir_ + "/locks/cache.lock", false, true, nullptr); }
Expected<FileLock> Cache::LockExclusive() { return Lock(dir_ + "/locks/cache.lock", true, true, nullptr); }
Expected<FileLock> Cache::LockKey(const Digest& key, bool wait, bool* would_block) {
  const std::string hex = key.Hex();
  {
    std::unique_lock<std::mutex> g(held_mu_);
    if (held_keys_.count(hex) && !wait) {
      if (would_block) *would_block = true;
      return FileLock();
    }
    held_cv_.wait(g, [&] { return !held_keys_.count(hex); });
    held_keys_.insert(hex);
  }
  auto release = [this, hex] {
    std::lock_guard<std::mutex> g(held_mu_);
    held_keys_.erase(hex);
    held_cv_.notify_all();
  };
  // Failing or not acquired, the FileLock inside Lock() ends the claim.
  return Lock(dir_ + "/locks/" + hex + ".lock", true, wait, would_block, std::move(release));
}

Expected<Digest> Cache::FileDigest(const std::string& path) {
  PB_ASSIGN_OR_RETURN(FileInfo info, env_->Stat(path));
  if (info.is_directory) return Status::Invalid(path + ": is a directory, expected a file");
  const std::string id = Hasher()
                             .Add(std::to_string(info.device))
                             .Add(std::to_string(info.inode))
                             .Add(std::to_string(info.size_bytes))
                             .Add(std::to_string(info.mtime_ns))
                             .Add(std::to_string(info.ctime_ns))
                             .Finish()
                             .Hex();
  const std::string memo = dir_ + "/filehash/" + id;
  if (env_->Exists(memo)) {
    Expected<std::string> text = env_->ReadFile(memo);
    if (text.ok()) {
      Expected<Digest> d = Digest::FromHex(text->substr(0, 32));
      if (d.ok()) {
        ::utimensat(AT_FDCWD, memo.c_str(), nullptr, 0);  // last use, for gc
        return d;
      }
    }
  }
  uint64_t size = 0;
  PB_ASSIGN_OR_RETURN(Digest digest, HashFile(path, &size));
  // A file modified while we hashed it, or so recently that a same-second
  // rewrite would keep its times, must not be remembered.
  Expected<FileInfo> after = env_->Stat(path);
  const bool settled = NowNs() - std::max(info.mtime_ns, info.ctime_ns) > 2'000'000'000LL;
  if (after.ok() && settled && after->mtime_ns == info.mtime_ns &&
      after->ctime_ns == info.ctime_ns && after->size_bytes == size)
    (void)env_->WriteFileAtomic(memo, digest.Hex() + "\n");
  return digest;
}

Expected<CacheEntry> Cache::ReadEntry(const std::string& path) {
  PB_ASSIGN_OR_RETURN(std::string text, env_->ReadFile(path));
  nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("format") || j["format"] != kEntryFormat)
    return Status::Corrupt(path + ": not a pointbake cache entry");
  CacheEntry entry;
  try {
    PB_ASSIGN_OR_RETURN(entry.key, Digest::FromHex(j.at("key").get<std::string>()));
    entry.components = j.at("components");
    entry.record = j.value("record", nlohmann::json::object());
    for (const auto& [port, art] : j.at("outputs").items()) {
      PB_ASSIGN_OR_RETURN(Artifact a, Artifact::FromJson(art));
      entry.outputs[port] = std::move(a);
    }
  } catch (const nlohmann::json::exception& e) {
    return Status::Corrupt(path + ": " + e.what());
  }
  if (KeyOf(entry.components) != entry.key)
    return Status::Corrupt(path + ": key does not match its components");
  return entry;
}

std::optional<CacheEntry> Cache::Lookup(const Digest& key) {
  const std::string path = EntryPath(key);
  if (!env_->Exists(path)) return std::nullopt;
  Expected<CacheEntry> entry = ReadEntry(path);
  if (!entry.ok()) return std::nullopt;
  for (const auto& [port, art] : entry->outputs)
    for (const auto& [name, file] : art.files) {
      Expected<FileInfo> info = env_->Stat(ObjectPath(file.digest));
      if (!info.ok() || info->size_bytes != file.size_bytes) return std::nullopt;
    }
  // Last use, for gc's LRU order.
  ::utimensat(AT_FDCWD, path.c_str(), nullptr, 0);
  return std::move(entry).value();
}

Expected<std::string> Cache::NewStagingDir(const Digest& key) {
  static std::atomic<int> counter{0};
  const std::string path = dir_ + "/tmp/" + key.Hex() + "." + std::to_string(::getpid()) + "." +
                           std::to_string(counter++);
  PB_RETURN_IF_ERROR(env_->RemoveAll(path));
  PB_RETURN_IF_ERROR(env_->CreateDirs(path));
  return path;
}

Status Cache::StoreObject(const std::string& staged_path, const Digest& digest) {
  const std::string target = ObjectPath(digest);
  if (env_->Exists(target)) {
    Expected<FileInfo> a = env_->Stat(target);
    Expected<FileInfo> b = env_->Stat(staged_path);
    if (a.ok() && b.ok() && a->size_bytes == b->size_bytes) return Status::Ok();
  }
  PB_RETURN_IF_ERROR(env_->CreateDirs(DirName(target)));
  PB_RETURN_IF_ERROR(env_->SyncFile(staged_path));
  ::chmod(staged_path.c_str(), 0444);
  return env_->Rename(staged_path, target);
}

Expected<CacheEntry> Cache::Commit(const Digest& key, const nlohmann::json& components,
                                   const std::map<std::string, StagedOutput>& outputs,
                                   const nlohmann::json& record, const std::string& staging_dir) {
  assert(KeyOf(components) == key);
  CacheEntry entry;
  entry.key = key;
  entry.components = components;
  entry.record = record;
  for (const auto& [port, staged] : outputs) {
    Artifact art;
    art.type = staged.type;
    art.meta = staged.meta;
    for (const auto& [name, path] : staged.files) {
      uint64_t size = 0;
      PB_ASSIGN_OR_RETURN(Digest digest, HashFile(path, &size));
      PB_RETURN_IF_ERROR(StoreObject(path, digest));
      art.files[name] = StoredFile{digest, size};
    }
    entry.outputs[port] = std::move(art);
  }
  nlohmann::json j;
  j["format"] = kEntryFormat;
  j["key"] = key.Hex();
  j["components"] = components;
  j["record"] = record;
  j["created_unix_ns"] = NowNs();
  nlohmann::json outs = nlohmann::json::object();
  for (const auto& [port, art] : entry.outputs) outs[port] = art.ToJson();
  j["outputs"] = outs;
  const std::string path = EntryPath(key);
  PB_RETURN_IF_ERROR(env_->CreateDirs(DirName(path)));
  PB_RETURN_IF_ERROR(env_->WriteFileAtomic(
      path, j.dump(1, ' ', false, nlohmann::json::error_handler_t::replace)));
  (void)env_->RemoveAll(staging_dir);
  return entry;
}

Status Cache::SaveHistory(const std::string& workflow, const std::string& stage,
                          const nlohmann::json& history) {
  const std::string dir = dir_ + "/history/" + SafeName(workflow);
  PB_RETURN_IF_ERROR(env_->CreateDirs(dir));
  return env_->WriteFileAtomic(dir + "/" + SafeName(stage) + ".json",
                               history.dump(1, ' ', false, nlohmann::json::error_handler_t::replace));
}

std::optional<nlohmann::json> Cache::LoadHistory(const std::string& workflow,
                                                 const std::string& stage) {
  const std::string path = dir_ + "/history/" + SafeName(workflow) + "/" + SafeName(stage) + ".json";
  Expected<std::string> text = env_->ReadFile(path);
  if (!text.ok()) return std::nullopt;
  nlohmann::json j = nlohmann::json::parse(*text, nullptr, false);
  // Damaged history only costs explain's reasons and --mem's estimate.
  if (j.is_discarded() || !j.is_object() || !j.contains("components") ||
      !j["components"].is_object() || !j.contains("peak_rss_bytes") ||
      !j["peak_rss_bytes"].is_number_unsigned())
    return std::nullopt;
  return j;
}

Expected<std::vector<Cache::EntryInfo>> Cache::ListEntries() {
  std::vector<EntryInfo> out;
  PB_ASSIGN_OR_RETURN(std::vector<std::string> shards, env_->ListDir(dir_ + "/entries"));
  for (const std::string& shard : shards) {
    Expected<std::vector<std::string>> names = env_->ListDir(dir_ + "/entries/" + shard);
    if (!names.ok()) continue;
    for (const std::string& name : *names) {
      if (name.size() != 37 || name.substr(32) != ".json") continue;  // temp names
      const std::string path = dir_ + "/entries/" + shard + "/" + name;
      Expected<CacheEntry> entry = ReadEntry(path);
      if (!entry.ok()) continue;
      EntryInfo info;
      info.key = entry->key;
      info.stage_type = entry->components.value("type", "?");
      for (const auto& [port, art] : entry->outputs) info.bytes += art.TotalBytes();
      Expected<FileInfo> st = env_->Stat(path);
      if (st.ok()) info.last_used_ns = st->mtime_ns;
      out.push_back(info);
    }
  }
  std::sort(out.begin(), out.end(),
            [](const EntryInfo& a, const EntryInfo& b) { return a.last_used_ns > b.last_used_ns; });
  return out;
}

Expected<VerifyReport> Cache::Verify(bool repair) {
  VerifyReport report;
  // Objects: the name is the digest of the bytes.
  std::set<std::string> good_objects;
  PB_ASSIGN_OR_RETURN(std::vector<std::string> shards, env_->ListDir(dir_ + "/objects"));
  for (const std::string& shard : shards) {
    Expected<std::vector<std::string>> names = env_->ListDir(dir_ + "/objects/" + shard);
    if (!names.ok()) continue;
    for (const std::string& name : *names) {
      const std::string path = dir_ + "/objects/" + shard + "/" + name;
      if (name.find(".tmp.") != std::string::npos) continue;  // an unfinished write, never read
      ++report.objects_checked;
      Expected<Digest> actual = HashFile(path);
      if (actual.ok() && actual->Hex() == name) {
        good_objects.insert(name);
        continue;
      }
      report.problems.push_back("corrupt object " + path +
                                (actual.ok() ? " (content digest " + actual->Hex() + ")" : ""));
      if (repair && env_->RemoveAll(path).ok()) ++report.removed;
    }
  }
  // Entries: parse, and every object they name is present and intact.
  PB_ASSIGN_OR_RETURN(std::vector<std::string> eshards, env_->ListDir(dir_ + "/entries"));
  for (const std::string& shard : eshards) {
    Expected<std::vector<std::string>> names = env_->ListDir(dir_ + "/entries/" + shard);
    if (!names.ok()) continue;
    for (const std::string& name : *names) {
      const std::string path = dir_ + "/entries/" + shard + "/" + name;
      if (name.find(".tmp.") != std::string::npos) continue;  // an unfinished write, never read
      ++report.entries_checked;
      Expected<CacheEntry> entry = ReadEntry(path);
      std::string problem;
      if (!entry.ok()) {
        problem = "corrupt entry " + path + ": " + entry.status().message();
      } else if (name != entry->key.Hex() + ".json") {
        problem = "misnamed entry " + path;
      } else {
        for (const auto& [port, art] : entry->outputs)
          for (const auto& [fname, file] : art.files)
            if (!good_objects.count(file.digest.Hex()))
              problem = "entry " + path + ": output " + port + "/" + fname + " object " +
                        file.digest.Hex() + " is missing or corrupt";
      }
      if (problem.empty()) continue;
      report.problems.push_back(problem);
      if (repair && env_->RemoveAll(path).ok()) ++report.removed;
    }
  }
  return report;
}

Expected<GcReport> Cache::Gc(uint64_t max_bytes) {
  GcReport report;
  // Leftovers of dead processes (tmp/ and temporary names in any folder).
  PB_ASSIGN_OR_RETURN(std::vector<std::string> tmps, env_->ListDir(dir_ + "/tmp"));
  for (const std::string& name : tmps) {
    std::optional<pid_t> pid = PidOfTempName(name);
    if (pid && ProcessAlive(*pid)) continue;
    if (env_->RemoveAll(dir_ + "/tmp/" + name).ok()) ++report.temp_removed;
  }
  for (const char* area : {"objects", "entries"}) {
    Expected<std::vector<std::string>> shards = env_->ListDir(dir_ + "/" + area);
    if (!shards.ok()) continue;
    for (const std::string& shard : *shards) {
      Expected<std::vector<std::string>> names = env_->ListDir(dir_ + "/" + area + "/" + shard);
      if (!names.ok()) continue;
      for (const std::string& name : *names) {
        if (name.find(".tmp.") == std::string::npos) continue;
        std::optional<pid_t> pid = PidOfTempName(name);
        if (pid && ProcessAlive(*pid)) continue;
        if (env_->RemoveAll(dir_ + "/" + area + "/" + shard + "/" + name).ok()) ++report.temp_removed;
      }
    }
  }

  // gc holds the cache exclusively, so no run holds or is about to open a
  // key lock: their files can go. Input-file memos unused for 30 days too.
  if (Expected<std::vector<std::string>> locks = env_->ListDir(dir_ + "/locks"); locks.ok())
    for (const std::string& name : *locks)
      if (name != "cache.lock") (void)env_->RemoveAll(dir_ + "/locks/" + name);
  constexpr int64_t kMemoMaxAgeNs = 30LL * 24 * 3600 * 1000000000LL;
  if (Expected<std::vector<std::string>> memos = env_->ListDir(dir_ + "/filehash"); memos.ok())
    for (const std::string& name : *memos) {
      Expected<FileInfo> info = env_->Stat(dir_ + "/filehash/" + name);
      if (info.ok() && NowNs() - info->mtime_ns > kMemoMaxAgeNs)
        (void)env_->RemoveAll(dir_ + "/filehash/" + name);
    }

  PB_ASSIGN_OR_RETURN(std::vector<EntryInfo> entries, ListEntries());  // newest first
  // Objects are shared between entries: count each once.
  std::map<std::string, uint64_t> object_size;
  std::vector<std::set<std::string>> entry_objects;
  for (const EntryInfo& info : entries) {
    std::set<std::string> objs;
    Expected<CacheEntry> entry = ReadEntry(EntryPath(info.key));
    if (entry.ok())
      for (const auto& [port, art] : entry->outputs)
        for (const auto& [name, file] : art.files) {
          objs.insert(file.digest.Hex());
          object_size[file.digest.Hex()] = file.size_bytes;
        }
    entry_objects.push_back(std::move(objs));
  }
  for (const auto& [hex, size] : object_size) report.bytes_before += size;

  // Keep the most recently used entries that fit in max_bytes.
  std::set<std::string> kept_objects;
  uint64_t kept = 0;
  for (size_t i = 0; i < entries.size(); ++i) {
    uint64_t extra = 0;
    for (const std::string& o : entry_objects[i])
      if (!kept_objects.count(o)) extra += object_size[o];
    if (kept + extra <= max_bytes) {
      kept += extra;
      kept_objects.insert(entry_objects[i].begin(), entry_objects[i].end());
    } else if (env_->RemoveAll(EntryPath(entries[i].key)).ok()) {
      ++report.entries_removed;
    }
  }
  // Objects no kept entry names.
  PB_ASSIGN_OR_RETURN(std::vector<std::string> shards, env_->ListDir(dir_ + "/objects"));
  for (const std::string& shard : shards) {
    Expected<std::vector<std::string>> names = env_->ListDir(dir_ + "/objects/" + shard);
    if (!names.ok()) continue;
    for (const std::string& name : *names) {
      if (kept_objects.count(name)) continue;
      if (env_->RemoveAll(dir_ + "/objects/" + shard + "/" + name).ok()) ++report.objects_removed;
    }
  }
  report.bytes_after = kept;
  return report;
}

}  // namespace pb
