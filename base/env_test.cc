#include "base/env.h"

#include <gtest/gtest.h>

#include "base/hash.h"
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
