#include "engine/cache.h"

#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>
#include <fstream>

#include "base/testing/fault_injecting_env.h"
#include "engine/test_util.h"

namespace pb {
namespace {

using testing::TempDir;

nlohmann::json Components(const std::string& x) { return {{"type", "t.text"}, {"x", x}}; }

// Stages one output file with `text` and commits it.
Expected<CacheEntry> CommitText(Cache& cache, const std::string& x, const std::string& text) {
  const nlohmann::json comps = Components(x);
  const Digest key = HashBytes(comps.dump());
  PB_ASSIGN_OR_RETURN(std::string staging, cache.NewStagingDir(key));
  std::filesystem::create_directories(staging + "/out");
  std::ofstream(staging + "/out/table.json") << text;
  Cache::StagedOutput out{"table", {{"table.json", staging + "/out/table.json"}}, {{"m", 1}}};
  return cache.Commit(key, comps, {{"out", out}}, {{"wall_s", 0.5}}, staging);
}

TEST(CacheTest, CommitThenLookupHitsAndSharesObjects) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  ASSERT_TRUE(CommitText(*cache, "a", "same bytes").ok());
  ASSERT_TRUE(CommitText(*cache, "b", "same bytes").ok());
  auto hit = cache->Lookup(HashBytes(Components("a").dump()));
  ASSERT_TRUE(hit.has_value());
  const Artifact& art = hit->outputs.at("out");
  EXPECT_EQ(art.meta["m"], 1);
  EXPECT_EQ(art.files.at("table.json").size_bytes, 10u);
  EXPECT_EQ(hit->record["wall_s"], 0.5);
  // Both entries point at one object.
  EXPECT_EQ(cache->Lookup(HashBytes(Components("b").dump()))->outputs.at("out").ComputeDigest(),
            art.ComputeDigest());
  EXPECT_FALSE(cache->Lookup(HashBytes(Components("c").dump())).has_value());
  // Objects are read-only.
  struct stat st;
  ASSERT_EQ(::stat(cache->ObjectPath(art.files.at("table.json").digest).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0222, 0u);
}

TEST(CacheTest, MissingObjectMakesAMissAndVerifyReportsIt) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  auto entry = CommitText(*cache, "a", "payload").value();
  const std::string obj = cache->ObjectPath(entry.outputs.at("out").files.at("table.json").digest);
  ::chmod(obj.c_str(), 0644);
  std::ofstream(obj) << "PAYLOAD";  // same size, other bytes
  auto report = cache->Verify(false).value();
  EXPECT_EQ(report.problems.size(), 2u);  // the object and the entry naming it
  auto repaired = cache->Verify(true).value();
  EXPECT_EQ(repaired.removed, 2);
  EXPECT_FALSE(cache->Lookup(entry.key).has_value());
  EXPECT_TRUE(cache->Verify(false)->problems.empty());
}

TEST(CacheTest, RelocatedCacheStillHits) {
  TempDir dir;
  Digest key;
  {
    auto cache = Cache::Open(dir.path() + "/c1").value();
    key = CommitText(*cache, "a", "x").value().key;
  }
  std::filesystem::rename(dir.path() + "/c1", dir.path() + "/c2");
  auto cache = Cache::Open(dir.path() + "/c2").value();
  EXPECT_TRUE(cache->Lookup(key).has_value());
}

// A failure at any durable write leaves either no entry or a complete one.
TEST(CacheTest, InjectedFailureAtEveryWriteNeverLeavesAPartialEntry) {
  for (int fail_at = 1; fail_at <= 6; ++fail_at) {
    TempDir dir;
    FaultInjectingEnv env(fail_at);
    auto opened = Cache::Open(dir.path() + "/c", &env);
    if (!opened.ok()) continue;  // failed while creating the layout: nothing to check
    auto& cache = *opened.value();
    auto committed = CommitText(cache, "a", "payload");
    const Digest key = HashBytes(Components("a").dump());
    auto reopened = Cache::Open(dir.path() + "/c").value();
    if (committed.ok()) {
      EXPECT_TRUE(reopened->Lookup(key).has_value()) << "fail_at " << fail_at;
    } else {
      EXPECT_FALSE(reopened->Lookup(key).has_value()) << "fail_at " << fail_at;
    }
    EXPECT_TRUE(reopened->Verify(false)->problems.empty()) << "fail_at " << fail_at;
    // The next attempt succeeds and gc cleans the torn leftovers.
    ASSERT_TRUE(CommitText(*reopened, "a", "payload").ok());
    EXPECT_TRUE(reopened->Lookup(key).has_value());
    reopened->Gc(1ull << 40).value();
    EXPECT_TRUE(reopened->Verify(false)->problems.empty());
  }
}

TEST(CacheTest, DamagedFilesAreMissesNotCrashes) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  auto entry = CommitText(*cache, "a", "x").value();
  const std::string hex = entry.key.Hex();
  const std::string path = dir.path() + "/c/entries/" + hex.substr(0, 2) + "/" + hex + ".json";
  ::chmod(path.c_str(), 0644);
  for (const char* damaged : {R"({"format": 1})", "[1]", R"({"format": "pointbake-entry 1"})", "{"}) {
    std::ofstream(path) << damaged;
    EXPECT_FALSE(cache->Lookup(entry.key).has_value()) << damaged;
    EXPECT_EQ(cache->Verify(false)->problems.size(), 1u) << damaged;
  }
  ASSERT_TRUE(cache->SaveHistory("wf", "s", {{"components", nlohmann::json::object()}, {"peak_rss_bytes", 5}}).ok());
  EXPECT_TRUE(cache->LoadHistory("wf", "s").has_value());
  for (const nlohmann::json& bad : {nlohmann::json::array({1}),
                                    nlohmann::json{{"components", 5}, {"peak_rss_bytes", 5}},
                                    nlohmann::json{{"components", nlohmann::json::object()}, {"peak_rss_bytes", "x"}}}) {
    ASSERT_TRUE(cache->SaveHistory("wf", "s", bad).ok());
    EXPECT_FALSE(cache->LoadHistory("wf", "s").has_value()) << bad.dump();
  }
}

TEST(CacheTest, GcRemovesLeftoversOfDeadProcessesWhateverTheirName) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  for (const char* name : {"abc.99999999999999999999.1", "abc.0.1", "abc.-5.1", "noname",
                           "k.2147483647.3"})
    dir.Write(std::string("c/tmp/") + name + "/f", "x");
  const std::string mine = "k." + std::to_string(::getpid()) + ".0";
  dir.Write("c/tmp/" + mine + "/f", "x");
  auto report = cache->Gc(1 << 20).value();
  EXPECT_EQ(report.temp_removed, 5);
  EXPECT_EQ(Env::Default()->ListDir(dir.path() + "/c/tmp").value(), std::vector<std::string>{mine});
}

TEST(CacheTest, GcKeepsMostRecentlyUsedWithinBudget) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  auto old_entry = CommitText(*cache, "old", std::string(1000, 'o')).value();
  auto new_entry = CommitText(*cache, "new", std::string(1000, 'n')).value();
  // Make "old" older.
  const std::string hex = old_entry.key.Hex();
  const std::string path = dir.path() + "/c/entries/" + hex.substr(0, 2) + "/" + hex + ".json";
  struct timespec times[2] = {{1, 0}, {1, 0}};
  ::utimensat(AT_FDCWD, path.c_str(), times, 0);
  auto report = cache->Gc(1500).value();
  EXPECT_EQ(report.bytes_before, 2000u);
  EXPECT_EQ(report.bytes_after, 1000u);
  EXPECT_EQ(report.entries_removed, 1);
  EXPECT_EQ(report.objects_removed, 1);
  EXPECT_FALSE(cache->Lookup(old_entry.key).has_value());
  EXPECT_TRUE(cache->Lookup(new_entry.key).has_value());
}

TEST(CacheTest, FileDigestIsMemoizedByStat) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  const std::string f = dir.Write("scan.txt", "points");
  const Digest d1 = cache->FileDigest(f).value();
  EXPECT_EQ(d1, HashBytes("points"));
  // Just written: a same-second rewrite could keep its times, so no memo yet.
  EXPECT_TRUE(Env::Default()->ListDir(dir.path() + "/c/filehash")->empty());
  std::this_thread::sleep_for(std::chrono::milliseconds(2100));
  EXPECT_EQ(cache->FileDigest(f).value(), d1);
  auto memo = Env::Default()->ListDir(dir.path() + "/c/filehash").value();
  EXPECT_EQ(memo.size(), 1u);
  // Rewritten in place with the same size and its mtime put back (cp -p,
  // rsync -t): the inode change time still tells.
  const FileInfo before = Env::Default()->Stat(f).value();
  dir.Write("scan.txt", "POINTS");
  const struct timespec times[2] = {{0, UTIME_OMIT},
                                    {before.mtime_ns / 1000000000, before.mtime_ns % 1000000000}};
  ASSERT_EQ(::utimensat(AT_FDCWD, f.c_str(), times, 0), 0);
  EXPECT_EQ(Env::Default()->Stat(f)->mtime_ns, before.mtime_ns);
  EXPECT_EQ(cache->FileDigest(f).value(), HashBytes("POINTS"));
  dir.Write("scan.txt", "other!");
  EXPECT_EQ(cache->FileDigest(f).value(), HashBytes("other!"));
}

TEST(CacheTest, KeyLockIsExclusiveAndReleasedOnClose) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  const Digest key = HashBytes("k");
  bool blocked = true;
  auto first = cache->LockKey(key, false, &blocked);
  ASSERT_TRUE(first.ok());
  EXPECT_FALSE(blocked);
  EXPECT_TRUE(first->held());
  // flock locks belong to the open file description: a second open blocks.
  auto second = cache->LockKey(key, false, &blocked);
  ASSERT_TRUE(second.ok());
  EXPECT_TRUE(blocked);
  { FileLock drop = std::move(first).value(); }
  auto third = cache->LockKey(key, false, &blocked);
  EXPECT_FALSE(blocked);
}

// What a cache shared by several machines needs from its file system
// (docs/cluster.md): a key lock held by another process excludes, and is
// released when that process dies. PB_CACHE_FS_TEST_DIR runs this on the
// file system to check (e.g. an NFS mount), else in a temporary folder.
TEST(CacheFsTest, KeyLockExcludesOtherProcessesAndDiesWithItsOwner) {
  TempDir tmp;
  const char* on = std::getenv("PB_CACHE_FS_TEST_DIR");
  const std::string dir = (on && *on ? std::string(on) : tmp.path()) + "/fs-test-cache." + std::to_string(::getpid());
  auto cache = Cache::Open(dir).value();
  const Digest key = HashBytes("shared stage");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    auto other = Cache::Open(dir);
    if (!other.ok()) ::_exit(2);
    auto lock = (*other)->LockKey(key, true);
    if (!lock.ok() || !lock->held()) ::_exit(3);
    (void)!::write(ready[1], "L", 1);
    for (;;) ::pause();  // holds the lock until killed
  }
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  bool blocked = false;
  auto mine = cache->LockKey(key, false, &blocked);
  ASSERT_TRUE(mine.ok());
  EXPECT_TRUE(blocked) << "another process holds the key lock";
  EXPECT_FALSE(mine->held());
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  // The owner died: a blocking lock returns (the test would hang otherwise).
  auto after = cache->LockKey(key, true, &blocked);
  ASSERT_TRUE(after.ok());
  EXPECT_TRUE(after->held());
  EXPECT_FALSE(blocked);
  ::close(ready[0]);
  ::close(ready[1]);
  std::filesystem::remove_all(dir);
}

// Threads of one process exclude each other on a key too: a campaign's
// parallel runs share one Cache, and on NFS flock() is a POSIX lock that the
// process's threads share, so the cache keeps its own claims.
TEST(CacheFsTest, KeyLockExcludesThreadsOfOneProcessAndWakesTheWaiter) {
  TempDir dir;
  auto cache = Cache::Open(dir.path() + "/c").value();
  const Digest key = HashBytes("shared stage");
  auto first = cache->LockKey(key, true);
  ASSERT_TRUE(first.ok());
  std::atomic<bool> acquired{false};
  std::thread waiter([&] {
    auto second = cache->LockKey(key, true);
    acquired = second.ok() && second->held();
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_FALSE(acquired.load());
  { FileLock drop = std::move(first).value(); }
  waiter.join();
  EXPECT_TRUE(acquired.load());
}

}  // namespace
}  // namespace pb
