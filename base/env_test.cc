#include "base/env.h"

#include <gtest/gtest.h>

#include "base/hash.h"
#include "base/testing/durable_write_check.h"
#include "base/testing/fault_injecting_env.h"
#include "base/testing/temp_dir.h"

namespace pb {
namespace {

TEST(EnvTest, ParsesAndFormatsSizes) {
  EXPECT_EQ(*ParseByteSize("512M"), 512ull << 20);
  EXPECT_EQ(*ParseByteSize("1.5GiB"), 3ull << 29);
  EXPECT_EQ(*ParseByteSize("300000"), 300000u);
  EXPECT_FALSE(ParseByteSize("12 parsecs").ok());
  EXPECT_FALSE(ParseByteSize("lots").ok());
  EXPECT_EQ(FormatBytes(3ull << 29), "1.5 GiB");
}

TEST(EnvTest, ResolvesPathsLexically) {
  EXPECT_EQ(ResolvePath("/a/b", "../c/./d.ply"), "/a/c/d.ply");
  EXPECT_EQ(ResolvePath("/a/b", "/x.ply"), "/x.ply");
  EXPECT_EQ(DirName("a/b/c.yaml"), "a/b");
  EXPECT_EQ(DirName("c.yaml"), ".");
}

TEST(EnvTest, AtomicWriteLeavesOldContentOnInjectedFailure) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/file";
  ASSERT_TRUE(Env::Default()->WriteFileAtomic(path, "old").ok());
  FaultInjectingEnv env(1);
  EXPECT_FALSE(env.WriteFileAtomic(path, "new").ok());
  EXPECT_EQ(*Env::Default()->ReadFile(path), "old");
  EXPECT_TRUE(env.WriteFileAtomic(path, "new").ok());  // only the first write fails
  EXPECT_EQ(*Env::Default()->ReadFile(path), "new");
}

TEST(EnvTest, StreamedFileAppearsOnlyOnCommit) {
  testing::TempDir dir;
  const std::string path = dir.Path("big.ply");
  ASSERT_TRUE(Env::Default()->WriteFileAtomic(path, "old").ok());
  {
    auto file = Env::Default()->NewAtomicFile(path);
    ASSERT_TRUE(file.ok()) << file.status().message();
    ASSERT_TRUE((*file)->Append("ne").ok());
    ASSERT_TRUE((*file)->Append("w").ok());
    EXPECT_EQ(*Env::Default()->ReadFile(path), "old");
    // Dropped without Commit (an error on the way): the temporary goes too.
  }
  EXPECT_EQ(*Env::Default()->ReadFile(path), "old");
  EXPECT_EQ(*Env::Default()->ListDir(dir.path()), std::vector<std::string>{"big.ply"});
  auto file = Env::Default()->NewAtomicFile(path);
  ASSERT_TRUE(file.ok());
  ASSERT_TRUE((*file)->Append("new").ok());
  ASSERT_TRUE((*file)->Commit().ok());
  EXPECT_EQ(*Env::Default()->ReadFile(path), "new");
  EXPECT_EQ(*Env::Default()->ListDir(dir.path()), std::vector<std::string>{"big.ply"});
  EXPECT_FALSE((*file)->Append("more").ok());  // finished: no write reaches the published file
}

TEST(EnvTest, StreamedFileInAMissingFolderNamesTheTemporary) {
  testing::TempDir dir;
  auto file = Env::Default()->NewAtomicFile(dir.Path("missing/big.ply"));
  ASSERT_FALSE(file.ok());
  EXPECT_NE(file.status().message().find(dir.Path("missing/big.ply.tmp.")), std::string::npos)
      << file.status().message();
}

TEST(EnvTest, FileSetKeepsEveryEarlierFileWhenOneWriteFails) {
  testing::TempDir dir;
  const std::vector<FileContents> older = {{dir.Path("a.png"), "a1"}, {dir.Path("index.json"), "i1"}};
  const std::vector<FileContents> newer = {{dir.Path("a.png"), "a2"}, {dir.Path("index.json"), "i2"}};
  ASSERT_TRUE(WriteFilesAtomic(Env::Default(), older).ok());
  EXPECT_EQ(testing::ExpectFailedWritesKeepEarlierFiles(
                dir.path(), [&](Env* env) { return WriteFilesAtomic(env, newer); }),
            2);
  EXPECT_EQ(*Env::Default()->ReadFile(dir.Path("a.png")), "a2");
  EXPECT_EQ(*Env::Default()->ReadFile(dir.Path("index.json")), "i2");
}

TEST(HashTest, DigestsRoundTripAndFieldsAreFramed) {
  const Digest d = HashBytes("pointbake");
  EXPECT_EQ(Digest::FromHex(d.Hex()).value(), d);
  EXPECT_FALSE(Digest::FromHex("xyz").ok());
  EXPECT_NE(Hasher().Add("ab").Add("c").Finish(), Hasher().Add("a").Add("bc").Finish());
  testing::TempDir dir;
  const std::string p = dir.Write("f", "pointbake");
  uint64_t size = 0;
  EXPECT_EQ(HashFile(p, &size).value(), d);
  EXPECT_EQ(size, 9u);
}

}  // namespace
}  // namespace pb
